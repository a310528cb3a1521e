//! The air between the aurora and the eye: how much of each line's light
//! the lower atmosphere lets through (`[sky]`).
//!
//! **Model.** Almost all the air lies far below the aurora (the pressure at
//! 80 km is 1e-5 of the ground's), so light emitted above the extinction
//! layer reaches an observer at altitude `h_o` through
//!
//! ```text
//! T(lambda, direction) = exp(-tau(lambda, h_o) X(e)),   tau = tau_R + tau_O3 + tau_a
//! ```
//!
//! `tau` the zenith optical depth of the air above the observer and `X` the
//! relative air mass at the direction's elevation `e` (dimensionless; km and
//! nm elsewhere):
//!
//! - **Rayleigh**: Bodhaine et al. (1999), J. Atmos. Oceanic Technol. 16,
//!   1854, eq. (30) at sea level, times `p(h_o) / p0` of the U.S. Standard
//!   Atmosphere 1976 (NOAA-S/T 76-1562).
//! - **Ozone**, the Chappuis band: `tau_O3 = sigma(lambda) N`, `N` the column
//!   (`ozone_du`, 1 DU = 2.687e16 cm^-2), `sigma` the 233 K cross-section of
//!   Serdyuchenko et al. (2014), Atmos. Meas. Tech. 7, 625, as 10 nm bin
//!   means ([`O3_SIGMA_CM2`]), in the 10-40 km layer of Bruneton & Neyret
//!   (2008) and Bruneton (2017).
//! - **Aerosol**: `tau_550 (lambda / 550 nm)^-angstrom` (Angstrom 1929),
//!   density `exp(-z / H_a)`; defaults from Tomasi et al. (2007), J. Geophys.
//!   Res. 112, D16205, and Bruneton & Neyret (2008).
//!
//! **Air mass**: `X(e) = 1 / (sin e + 0.50572 (e + 6.07995 deg)^-1.6364)`
//! (Kasten & Young 1989, Appl. Opt. 28, 4735, refraction included), for
//! every constituent; below the horizon `X(0)`. **Paths inside the layer**
//! ([`Air::tau_path`]): plane-parallel and exact, `tau = d (C(z0) - C(z1)) /
//! (z1 - z0)` with `C(z)` the zenith depth above `z`, `d (-C'(z0))` when level.
//!
//! **Per channel.** Channel `c` holds the share `w_ic` of line `i` of a
//! reference aurora ([`REFERENCE_MIX`]) times the line's colour for the
//! scene's observer (`[colour] observer`: the camera's 557.7 nm has no red,
//! the eye's does, so the weights differ per observer; [`channel_weights`]),
//! each line dimmed by its own depth: `T_c(X) = sum_i w_ic exp(-tau_i X)`,
//! exact for that mix ([`Extinction::towards`]); its effective depth starts
//! at `sum_i w_ic tau_i` ([`Air::channel_depths`]). A per-line grid gets its
//! line's own depth ([`Extinction::for_line`]). Light is only taken away:
//! scattering into the ray is not modelled. Formulas, depths and tables:
//! docs/physics.md, "The air between the aurora and the eye".

use crate::physics::emission::line_colour::{Observer, LINES, N2_1P, N2_1P_BANDS_NM};
use crate::physics::emission::line_table::{line_colours, N_LINES};
use crate::scene::SkyParams;
use crate::util::fmath;
use glam::DVec3;

/// Sea-level pressure of the standard atmosphere, Pa.
pub const P0_PA: f64 = 101_325.0;
/// Earth radius of the standard atmosphere's geopotential, km.
const R0_KM: f64 = 6356.766;
/// `g0 M / R*`, K per km of geopotential height.
const GMR_K_PER_KM: f64 = 34.163_195;
/// U.S. Standard Atmosphere 1976 layers: base geopotential height (km),
/// base temperature (K), lapse rate (K/km).
const US1976_LAYERS: [(f64, f64, f64); 7] = [
    (0.0, 288.15, -6.5),
    (11.0, 216.65, 0.0),
    (20.0, 216.65, 1.0),
    (32.0, 228.65, 2.8),
    (47.0, 270.65, 0.0),
    (51.0, 270.65, -2.8),
    (71.0, 214.65, -2.0),
];
/// Top of the last layer, geopotential km (86 km geometric).
const US1976_TOP_KM: f64 = 84.852;

/// One Dobson unit, molecules cm^-2.
pub const DOBSON_CM2: f64 = 2.687e16;
/// First bin centre of [`O3_SIGMA_CM2`], nm; the bins are 10 nm wide.
pub const O3_SIGMA_FIRST_NM: f64 = 405.0;
/// Ozone absorption cross-section, cm^2, at 405, 415, ... 695 nm: the 233 K
/// spectrum of Serdyuchenko et al. (2014) averaged over 10 nm bins
/// (400-410 nm, ...), as tabulated (in m^2) in E. Bruneton's
/// precomputed_atmospheric_scattering demo (2017).
pub const O3_SIGMA_CM2: [f64; 30] = [
    1.527e-23, 2.763e-23, 5.52e-23, 8.451e-23, 1.582e-22, 2.316e-22, 3.669e-22, 4.924e-22, 7.752e-22, 9.016e-22, 1.48e-21, 1.602e-21,
    2.139e-21, 2.755e-21, 3.091e-21, 3.5e-21, 4.266e-21, 4.672e-21, 4.398e-21, 4.701e-21, 5.019e-21, 4.305e-21, 3.74e-21, 3.215e-21,
    2.662e-21, 2.238e-21, 1.852e-21, 1.473e-21, 1.209e-21, 9.423e-22,
];
/// The ozone layer's triangle: zero below, peak, zero above, km.
pub const O3_LAYER_KM: (f64, f64, f64) = (10.0, 25.0, 40.0);

/// Photons of each line of [`LINES`] in the reference aurora of the
/// per-channel depths (557.7, 630.0, 636.4, 427.8 nm, N2 1P; module doc):
/// GLOW's column at E0 = 3 keV, R per erg cm^-2 s^-1.
pub const REFERENCE_MIX: [f64; N_LINES] = [
    1268.0,
    88.5,
    88.5 / crate::physics::chemistry::einstein::O1D_PHOTON_RATIO,
    265.0,
    265.0 * crate::physics::emission::line_colour::R_1P,
];

/// Rayleigh optical depth at sea level, Bodhaine et al. (1999) eq. (30).
pub fn rayleigh_tau_sea_level(lambda_nm: f64) -> f64 {
    let l2 = fmath::powi(lambda_nm * 1e-3, 2);
    0.0021520 * (1.0455996 - 341.29061 / l2 - 0.90230850 * l2) / (1.0 + 0.0027059889 / l2 - 85.968563 * l2)
}

/// Temperature (K) and pressure ratio `p / p0` of the U.S. Standard
/// Atmosphere 1976 at geometric altitude `z_km` (clamped at 0 below).
pub fn us1976(z_km: f64) -> (f64, f64) {
    let h = {
        let z = z_km.max(0.0);
        R0_KM * z / (R0_KM + z)
    };
    let mut p = 1.0;
    for (i, &(hb, tb, l)) in US1976_LAYERS.iter().enumerate() {
        let top = US1976_LAYERS.get(i + 1).map_or(US1976_TOP_KM, |n| n.0);
        let dh = h.min(top) - hb;
        let t = tb + l * dh;
        p *= if l == 0.0 { fmath::exp(-GMR_K_PER_KM * dh / tb) } else { fmath::powf(tb / t, GMR_K_PER_KM / l) };
        if h <= top {
            return (t, p);
        }
        if i == US1976_LAYERS.len() - 1 {
            // Isothermal above the last layer.
            return (t, p * fmath::exp(-GMR_K_PER_KM * (h - top) / t));
        }
    }
    unreachable!("the last layer returns")
}

/// `p / p0` of the standard atmosphere at `z_km`.
pub fn pressure_ratio(z_km: f64) -> f64 {
    us1976(z_km).1
}

/// The pressure scale height `-p / (dp/dz)` at `z_km`, km: `T / (g0 M / R*)`
/// times `(dH/dz)^-1 = ((r0 + z) / r0)^2`.
pub fn pressure_scale_height_km(z_km: f64) -> f64 {
    let z = z_km.max(0.0);
    us1976(z).0 / GMR_K_PER_KM * fmath::powi((R0_KM + z) / R0_KM, 2)
}

/// Ozone cross-section at `lambda_nm`, cm^2: [`O3_SIGMA_CM2`] linear between
/// bin centres, 0 outside 400-700 nm (the Chappuis band's edges are 1e-3
/// of its peak).
pub fn ozone_cross_section_cm2(lambda_nm: f64) -> f64 {
    let x = (lambda_nm - O3_SIGMA_FIRST_NM) / 10.0;
    let n = O3_SIGMA_CM2.len();
    if !(-0.5..=n as f64 - 0.5).contains(&x) {
        return 0.0;
    }
    let x = x.clamp(0.0, (n - 1) as f64);
    let i = (x.floor() as usize).min(n - 2);
    let f = x - i as f64;
    O3_SIGMA_CM2[i] * (1.0 - f) + O3_SIGMA_CM2[i + 1] * f
}

/// Fraction of the ozone column above `z_km` (the triangle of [`O3_LAYER_KM`]).
pub fn ozone_fraction_above(z_km: f64) -> f64 {
    let (a, m, b) = O3_LAYER_KM;
    if z_km <= a {
        1.0
    } else if z_km <= m {
        1.0 - fmath::powi(z_km - a, 2) / ((b - a) * (m - a))
    } else if z_km < b {
        fmath::powi(b - z_km, 2) / ((b - a) * (b - m))
    } else {
        0.0
    }
}

/// Relative air mass at elevation `e_deg` (Kasten & Young 1989); below the
/// horizon, the horizon's.
pub fn air_mass(e_deg: f64) -> f64 {
    let e = e_deg.clamp(0.0, 90.0);
    1.0 / (fmath::sin(e.to_radians()) + 0.50572 * fmath::powf(e + 6.07995, -1.6364))
}

/// The atmosphere of `[sky]`: ozone column and aerosol.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Air {
    pub ozone_du: f64,
    pub aerosol_tau_550: f64,
    pub angstrom: f64,
    pub aerosol_scale_height_km: f64,
}

/// Zenith optical depths of one wavelength (or one channel) by constituent,
/// at sea level: Rayleigh, the whole ozone column, aerosol.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Depths {
    pub rayleigh: f64,
    pub ozone: f64,
    pub aerosol: f64,
}

impl Depths {
    /// `sum_j f_j d_j`: depths `d` weighted by per-constituent factors `self`.
    pub fn apply(&self, d: &Depths) -> f64 {
        self.rayleigh * d.rayleigh + self.ozone * d.ozone + self.aerosol * d.aerosol
    }

    fn scaled_add(self, o: Depths, w: f64) -> Depths {
        Depths { rayleigh: self.rayleigh + w * o.rayleigh, ozone: self.ozone + w * o.ozone, aerosol: self.aerosol + w * o.aerosol }
    }
}

impl Air {
    /// `[sky]`'s air, or None with `extinction = false`.
    pub fn from_sky(sky: &SkyParams) -> Option<Air> {
        sky.extinction.then_some(Air {
            ozone_du: sky.ozone_du,
            aerosol_tau_550: sky.aerosol_optical_depth,
            angstrom: sky.angstrom,
            aerosol_scale_height_km: sky.aerosol_scale_height_km,
        })
    }

    /// Sea-level zenith depths at `lambda_nm`.
    pub fn depths(&self, lambda_nm: f64) -> Depths {
        Depths {
            rayleigh: rayleigh_tau_sea_level(lambda_nm),
            ozone: ozone_cross_section_cm2(lambda_nm) * self.ozone_du * DOBSON_CM2,
            aerosol: self.aerosol_tau_550 * fmath::powf(lambda_nm / 550.0, -self.angstrom),
        }
    }

    /// Sea-level zenith depths of line `i` of [`LINES`] (the N2 1P bands:
    /// the mean over [`N2_1P_BANDS_NM`]).
    pub fn line_depths(&self, i: usize) -> Depths {
        if LINES[i] == N2_1P {
            let n = N2_1P_BANDS_NM.len() as f64;
            N2_1P_BANDS_NM.iter().fold(Depths::default(), |acc, &l| acc.scaled_add(self.depths(l), 1.0 / n))
        } else {
            self.depths(LINES[i].lambda_nm)
        }
    }

    /// First-order sea-level zenith depths per Rec.709 channel seen by
    /// `observer`, `tau_c = sum_i w_ic tau_i` (module doc).
    pub fn channel_depths(&self, observer: Observer) -> [Depths; 3] {
        channel_weights(observer).map(|w| (0..N_LINES).fold(Depths::default(), |acc, i| acc.scaled_add(self.line_depths(i), w[i])))
    }

    /// Zenith optical depth `C(z)` of `d` above altitude `z_km`.
    pub fn column_above(&self, d: &Depths, z_km: f64) -> f64 {
        self.fractions_above(z_km).apply(d)
    }

    /// The share of each constituent's column above `z_km`.
    pub fn fractions_above(&self, z_km: f64) -> Depths {
        Depths {
            rayleigh: pressure_ratio(z_km),
            ozone: ozone_fraction_above(z_km),
            aerosol: fmath::exp(-z_km.max(0.0) / self.aerosol_scale_height_km),
        }
    }

    /// `-dC/dz` at `z_km`: the extinction coefficient there, per km.
    pub fn coefficient(&self, d: &Depths, z_km: f64) -> f64 {
        self.coefficients(z_km).apply(d)
    }

    /// Each constituent's `-d(fraction above)/dz` at `z_km`, per km.
    pub fn coefficients(&self, z_km: f64) -> Depths {
        let (a, m, b) = O3_LAYER_KM;
        let o3 = if z_km > a && z_km < b {
            let peak = 2.0 / (b - a);
            if z_km <= m {
                peak * (z_km - a) / (m - a)
            } else {
                peak * (b - z_km) / (b - m)
            }
        } else {
            0.0
        };
        let h_a = self.aerosol_scale_height_km;
        Depths {
            rayleigh: pressure_ratio(z_km) / pressure_scale_height_km(z_km),
            ozone: o3,
            aerosol: fmath::exp(-z_km.max(0.0) / h_a) / h_a,
        }
    }

    /// Optical depth of `d` along a straight path of length `len_km` between
    /// altitudes `z0_km` and `z1_km` (module doc: exact in a plane-parallel
    /// atmosphere).
    pub fn tau_path(&self, d: &Depths, z0_km: f64, z1_km: f64, len_km: f64) -> f64 {
        let dz = z1_km - z0_km;
        if dz.abs() < 1e-6 * len_km.max(1e-3) {
            return len_km * self.coefficient(d, 0.5 * (z0_km + z1_km));
        }
        (len_km * (self.column_above(d, z0_km) - self.column_above(d, z1_km)) / dz).max(0.0)
    }
}

/// What the renderer needs to apply the air: the observer (altitude and
/// local up, computed once from the camera by [`Extinction::for_observer`]),
/// the air, each line's depths and each output channel's share of each
/// line.
#[derive(Clone, Debug, PartialEq)]
pub struct Extinction {
    pub air: Air,
    pub observer_km: f64,
    /// The observer's position, km, and local up.
    pub observer: DVec3,
    pub up: DVec3,
    /// Sea-level zenith depths of each line of [`LINES`].
    pub lines: [Depths; N_LINES],
    /// Each channel's weights over the lines (summing to 1): the reference
    /// mix's `w_ic` (module doc), or one line's alone.
    pub weights: [[f64; N_LINES]; 3],
    /// Zenith optical depth above the observer of each line.
    pub tau_zenith: [f64; N_LINES],
}

/// Each channel's weights over the lines for the reference mix seen by
/// `observer`.
pub fn channel_weights(observer: Observer) -> [[f64; N_LINES]; 3] {
    let colours = line_colours(observer);
    std::array::from_fn(|c| {
        let w: [f64; N_LINES] = std::array::from_fn(|i| REFERENCE_MIX[i] * colours[i][c].max(0.0));
        let total: f64 = w.iter().sum();
        w.map(|x| x / total)
    })
}

impl Extinction {
    /// The observer at `position` (km, z up): altitude `z` and up `+z` on the
    /// flat ground, with the default observer's colours. The one place the
    /// observer's frame is computed. `line`: a one-line grid's line (its
    /// depth in every channel), else the reference mix.
    pub fn for_observer(air: Air, position: DVec3, line: Option<usize>) -> Extinction {
        Self::for_observer_at(air, position, position.z, DVec3::Z, line, Observer::default())
    }

    /// [`Self::for_observer`] for an observer at `position` whose altitude
    /// and local up (a unit vector) are given: on a round Earth, the
    /// distance from its centre minus its radius and the radial direction
    /// (`crate::geometry::earth`); on flat ground, `position.z` and +z. The
    /// channels' weights are `observer`'s.
    pub fn for_observer_at(air: Air, position: DVec3, altitude_km: f64, up: DVec3, line: Option<usize>, observer: Observer) -> Extinction {
        let weights = match line {
            Some(i) => [std::array::from_fn(|k| if k == i { 1.0 } else { 0.0 }); 3],
            None => channel_weights(observer),
        };
        let lines: [Depths; N_LINES] = std::array::from_fn(|i| air.line_depths(i));
        let tau_zenith = lines.map(|d| air.column_above(&d, altitude_km));
        Extinction { air, observer_km: altitude_km, observer: position, up, lines, weights, tau_zenith }
    }

    /// A per-line grid's extinction: line `i`'s depths in every channel.
    pub fn for_line(air: Air, position: DVec3, i: usize) -> Extinction {
        Self::for_observer(air, position, Some(i))
    }

    /// Elevation of `dir` above the observer's horizon, degrees.
    pub fn elevation_deg(&self, dir: DVec3) -> f64 {
        fmath::asin(self.up.dot(dir.normalize()).clamp(-1.0, 1.0)).to_degrees()
    }

    /// Each channel's transmittance from the lines' optical depths along a
    /// path: `sum_i w_ic exp(-tau_i)`.
    fn mix(&self, tau: [f64; N_LINES]) -> [f64; 3] {
        let t = tau.map(|x| fmath::exp(-x));
        self.weights.map(|w| w.iter().zip(&t).map(|(w, t)| w * t).sum())
    }

    /// Transmittance per channel towards `dir` for light from above the
    /// layer: `sum_i w_ic exp(-tau_i X(e))`.
    pub fn towards(&self, dir: DVec3) -> [f64; 3] {
        let x = air_mass(self.elevation_deg(dir));
        self.mix(self.tau_zenith.map(|t| t * x))
    }

    /// The effective optical depth of channel `c` at air mass `x`,
    /// `-ln T_c / X` (the first-order `tau_c` of [`Air::channel_depths`] as
    /// `x -> 0`).
    pub fn effective_tau(&self, c: usize, x: f64) -> f64 {
        let t: f64 = self.weights[c].iter().zip(&self.tau_zenith).map(|(w, t)| w * fmath::exp(-t * x)).sum();
        -fmath::ln(t) / x
    }

    /// Transmittance per channel towards `dir` from a point `x` (km) below
    /// the layer for light from above it: the air-mass law with the column
    /// above the point's altitude (the terrain lit by the aurora).
    pub fn towards_from(&self, x: DVec3, dir: DVec3) -> [f64; 3] {
        let z = self.observer_km + self.up.dot(x - self.observer);
        let am = air_mass(self.elevation_deg(dir));
        let f = self.air.fractions_above(z);
        self.mix(self.lines.map(|d| am * f.apply(&d)))
    }

    /// Transmittance per channel from a point `p` (km) to the observer at
    /// `o` along the straight path between them.
    pub fn along(&self, o: DVec3, p: DVec3) -> [f64; 3] {
        let len = (p - o).length();
        let (z0, z1) = (self.observer_km, self.observer_km + self.up.dot(p - o));
        let dz = z1 - z0;
        if dz.abs() < 1e-6 * len.max(1e-3) {
            let k = self.air.coefficients(0.5 * (z0 + z1));
            return self.mix(self.lines.map(|d| len * k.apply(&d)));
        }
        let (f0, f1) = (self.air.fractions_above(z0), self.air.fractions_above(z1));
        self.mix(self.lines.map(|d| (len * (f0.apply(&d) - f1.apply(&d)) / dz).max(0.0)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The ozone triangle integrates to the whole column and its
    /// coefficient is minus the derivative of the column above.
    #[test]
    fn ozone_profile_is_consistent() {
        let air = Air { ozone_du: 300.0, aerosol_tau_550: 0.05, angstrom: 1.3, aerosol_scale_height_km: 1.2 };
        let d = air.depths(600.0);
        assert!((ozone_fraction_above(0.0) - 1.0).abs() < 1e-15 && ozone_fraction_above(50.0) == 0.0);
        assert!((ozone_fraction_above(25.0) - 0.5).abs() < 1e-12);
        for z in [0.5, 5.0, 12.0, 24.0, 30.0, 39.0, 60.0] {
            let h = 1e-4;
            let num = -(air.column_above(&d, z + h) - air.column_above(&d, z - h)) / (2.0 * h);
            let k = air.coefficient(&d, z);
            // Central difference error ~ h^2 C''' / 6: far below 1e-6 relative.
            assert!((num - k).abs() <= 1e-6 * k.max(1e-9), "z {z}: {num} vs {k}");
        }
    }
}
