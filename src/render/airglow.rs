//! The airglow as the camera sees it (`[airglow]`, the model and its
//! sources in `crate::physics::airglow`): behind the volume, seen by camera
//! rays only (like the background, through the volume's transmittance),
//! lighting nothing, hidden by the terrain and by the solid Earth.
//!
//! **Radiance.** Each line of each layer adds
//! `L = line_rgb(lambda) I F(z) T_air(lambda, e) / 1000`: `I` its zenith
//! column in R, `F` the layer's slant factor through its shell at the
//! ray's zenith angle `z` from the camera (`slant_factor`, round Earth of
//! `[earth] radius_km`, or the mean radius 6371 km on flat ground, where a
//! plane layer's `1 / cos z` would be infinite at the horizon), `T_air =
//! exp(-tau(lambda) X(e))` the air between the camera and the layer
//! (`crate::physics::air_extinction`: the zenith depth above the camera
//! times Kasten & Young's air mass at elevation `e`; 1 with `[sky]
//! extinction = false`), and `line_rgb` the line's colour per photon
//! (`crate::physics::emission::line_colour`). The division by 1000 puts
//! it in the volume's radiance unit: 1 = a column of 1 kR of 557.7 nm,
//! 1 kR sr = 10^9 / (4 pi) photons cm^-2 s^-1 (`sky.rs`); so 1 R at the
//! zenith is 10^6 / (4 pi) photons cm^-2 s^-1 sr^-1 and reads 0.001 in
//! luminance for 557.7 nm.
//!
//! **Per ray.** The shells are concentric about the Earth's centre and the
//! camera sits at one point, so `L` depends only on the ray's elevation
//! above the camera's horizon: it is computed once per render at every
//! [`STEP_DEG`] of elevation (3601 directions, each layer by quadrature)
//! and read linearly between; the step is 1/20 of a degree, finer than the
//! pixels of any camera wider than 32 degrees at 640 pixels.

use crate::geometry::earth::{Earth, MEAN_RADIUS_KM};
use crate::physics::air_extinction::{air_mass, pressure_ratio, Air};
use crate::physics::airglow::{key_r, o2_b_depth, slant_factor, CONTINUUM_LAYER, LAYERS};
use crate::physics::emission::line_colour::{line_rgb, photon_rgb_unclipped};
use crate::physics::night_sky::broadband::{continuum_r_per_nm, starlight_r_per_nm, zodiacal_r_per_nm};
use crate::scene::{AirglowParams, SkyParams};
use crate::util::fmath;
use crate::util::observer::Observer;
use glam::DVec3;

/// Elevation step of the table, degrees.
pub const STEP_DEG: f64 = 0.05;
/// The volume's radiance unit per rayleigh of column (module doc).
pub const KR_PER_R: f64 = 1e-3;

/// The airglow's radiance per direction, for one camera position.
#[derive(Clone, Debug, PartialEq)]
pub struct Airglow {
    /// The camera's local up.
    pub up: DVec3,
    /// Radiance at elevation `-90 + i STEP_DEG` degrees.
    table: Vec<[f64; 3]>,
}

/// One line as the camera sees it: colour times zenith column (kR), the
/// zenith optical depth of the air above the camera, the layer.
struct SeenLine {
    rgb_kr: [f64; 3],
    tau: f64,
    layer: usize,
}

/// The broadband light per nm (`crate::physics::night_sky::broadband`):
/// its colour per photon, the air's zenith depth, and the spectra from
/// outside the air and of the continuum's layer, R/nm.
struct Broadband {
    observer: Observer,
    /// (camera-raw colour of one photon of the nm, zenith depth, outside
    /// R/nm, continuum's zenith R/nm), one per nm of [`BROADBAND_NM`].
    nm: Vec<([f64; 3], f64, f64, f64)>,
}

/// The wavelengths the broadband light is summed over, nm (1 nm apart):
/// the camera table's range, which holds the eye's visible light too.
pub const BROADBAND_NM: (u32, u32) = (380, 780);

impl Broadband {
    /// None when every broadband key (times `scale`) is 0.
    fn new(p: &AirglowParams, observer: Observer, tau_of: &dyn Fn(f64) -> f64) -> Option<Broadband> {
        let (zl, isl) = (p.zodiacal_light * p.scale, p.starlight * p.scale);
        let cont = key_r(p, &CONTINUUM_LAYER);
        if zl <= 0.0 && isl <= 0.0 && cont <= 0.0 {
            return None;
        }
        let nm = (BROADBAND_NM.0..=BROADBAND_NM.1)
            .map(|l| {
                let l = l as f64;
                let colour = photon_rgb_unclipped(l, observer);
                let outside = zodiacal_r_per_nm(zl, l) + starlight_r_per_nm(isl, l);
                (colour, tau_of(l), outside, continuum_r_per_nm(cont, l))
            })
            .collect();
        Some(Broadband { observer, nm })
    }

    /// Radiance (the volume's unit) at air mass `x`, with `space` (1, or 0
    /// behind the Earth) of the outside light and the continuum's slant
    /// factor `layer`: the sum over the nm, into the observer's gamut once.
    fn radiance(&self, space: f64, layer: f64, x: f64) -> [f64; 3] {
        let mut rgb = [0.0; 3];
        for &(c, tau, outside, cont) in &self.nm {
            let w = (space * outside + layer * cont) * fmath::exp(-tau * x) * KR_PER_R;
            for k in 0..3 {
                rgb[k] += w * c[k];
            }
        }
        self.observer.in_gamut(rgb)
    }
}

impl Airglow {
    /// The airglow of `p` seen from `position` (scene frame, km), or None
    /// when `[airglow] on = false` or every layer is 0; each line in
    /// `observer`'s colour, as the volume's.
    pub fn new(p: &AirglowParams, sky: &SkyParams, position: DVec3, earth_radius_km: f64, observer: Observer) -> Option<Airglow> {
        let earth = Earth::new(earth_radius_km);
        let (altitude, up) = (earth.altitude(position), earth.local_up(position));
        let shells_km = if earth.is_flat() { MEAN_RADIUS_KM } else { earth_radius_km };
        let air = Air::from_sky(sky);
        // The zenith optical depth above the camera at a wavelength: the air's
        // and the O2 B band's (none without air).
        let tau_of =
            |lambda: f64| air.map_or(0.0, |a| a.column_above(&a.depths(lambda), altitude) + o2_b_depth(lambda) * pressure_ratio(altitude));
        let mut lines = Vec::new();
        for (k, layer) in LAYERS.iter().enumerate() {
            for &(lambda, w) in layer.lines {
                let r = if p.on { w * key_r(p, layer) } else { 0.0 };
                if r > 0.0 {
                    lines.push(SeenLine { rgb_kr: line_rgb(lambda, observer).map(|c| c * r * KR_PER_R), tau: tau_of(lambda), layer: k });
                }
            }
        }
        let broad = if p.on { Broadband::new(p, observer, &tau_of) } else { None };
        if lines.is_empty() && broad.is_none() {
            return None;
        }
        let n = (180.0 / STEP_DEG).round() as usize + 1;
        let r0 = shells_km + altitude;
        let table = (0..n)
            .map(|i| {
                let e = -90.0 + i as f64 * STEP_DEG;
                let mu = fmath::sin(e.to_radians());
                let x = air_mass(e);
                let f: Vec<f64> = LAYERS.iter().map(|l| slant_factor(l, shells_km, altitude, mu)).collect();
                let mut rgb = [0.0; 3];
                for l in &lines {
                    let t = f[l.layer] * fmath::exp(-l.tau * x);
                    for c in 0..3 {
                        rgb[c] += l.rgb_kr[c] * t;
                    }
                }
                if let Some(b) = &broad {
                    // Light from outside the air reaches the camera unless the
                    // solid Earth is in the way.
                    let space = !(mu < 0.0 && r0 * r0 * (1.0 - mu * mu) < shells_km * shells_km && r0 >= shells_km);
                    let layer = slant_factor(&CONTINUUM_LAYER, shells_km, altitude, mu);
                    let c = b.radiance(if space { 1.0 } else { 0.0 }, layer, x);
                    for k in 0..3 {
                        rgb[k] += c[k];
                    }
                }
                rgb
            })
            .collect();
        Some(Airglow { up, table })
    }

    /// Radiance along `dir` (unit), linear between the table's elevations.
    pub fn radiance(&self, dir: DVec3) -> [f64; 3] {
        let e = fmath::asin(self.up.dot(dir).clamp(-1.0, 1.0)).to_degrees();
        let x = ((e + 90.0) / STEP_DEG).clamp(0.0, (self.table.len() - 1) as f64);
        let i = (x.floor() as usize).min(self.table.len() - 2);
        let f = x - i as f64;
        let (a, b) = (self.table[i], self.table[i + 1]);
        [0, 1, 2].map(|c| a[c] + f * (b[c] - a[c]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Without air, looking up from the ground, the green layer alone (no
    /// other line, no broadband light) reads its key in kR times its colour;
    /// looking down, nothing.
    #[test]
    fn zenith_reads_the_key_and_the_ground_hides_it() {
        let p = AirglowParams {
            red_r: 0.0,
            sodium_r: 0.0,
            hydroxyl_r: 0.0,
            continuum_r_per_nm: 0.0,
            zodiacal_light: 0.0,
            starlight: 0.0,
            ..AirglowParams::default()
        };
        let sky = SkyParams { extinction: false, ..SkyParams::default() };
        let a = Airglow::new(&p, &sky, DVec3::ZERO, 6371.0, Observer::Camera).unwrap();
        let l = a.radiance(DVec3::Z);
        let want = line_rgb(557.7, Observer::Camera).map(|c| c * 0.25);
        for c in 0..3 {
            assert!((l[c] - want[c]).abs() <= 1e-6 * want[1], "{l:?} {want:?}");
        }
        assert_eq!(a.radiance(-DVec3::Z), [0.0; 3]);
        assert!(Airglow::new(&AirglowParams { on: false, ..p }, &sky, DVec3::ZERO, 6371.0, Observer::Camera).is_none());
    }
}
