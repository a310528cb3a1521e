//! The airglow: the night sky's own light, from chemistry in the upper
//! atmosphere that runs all night everywhere (no aurora needed).
//!
//! **Model.** Each emission is a spherical shell about the Earth's centre
//! with a Gaussian volume emission rate in altitude,
//! `eta(h) = I / (sqrt(2 pi) sigma) exp(-(h - h_p)^2 / (2 sigma^2))`
//! (rayleigh per km; cut at 6 sigma and at the ground), so its zenith column
//! seen from below is `I`, the layer's zenith brightness in rayleigh
//! (`[airglow]` keys). Seen at zenith angle `z` the column is
//! `I F(z)`, `F = int N(h(s)) ds` along the ray ([`slant_factor`], by
//! Gauss-Legendre quadrature in pieces of sigma / 2 in radius), stopped by
//! the solid Earth. For a thin layer `F` is van Rhijn's factor
//! `V(z) = 1 / sqrt(1 - (r_o sin z / r_h)^2)` ([`van_rhijn`], `r_o` and
//! `r_h` the observer's and the layer's distances from the centre); a
//! layer of width sigma adds `sigma^2 / 2 f''(r_h)`, `f(r) = r / sqrt(r^2 -
//! p^2)`, `p = r_o sin z` (the Gaussian's moments; [`thick_layer_factor`]).
//!
//! | layer (key) | lines, nm | zenith R | peak km | sigma km |
//! |---|---|---|---|---|
//! | `green_r` | OI 557.7 | 250 | 97 | 4 |
//! | `red_r` | OI 630.0, 636.4 (630.0 / 2.997) | 60 | 250 | 30 |
//! | `sodium_r` | Na D 589.0/589.6 (as 589.3) | 50 | 92 | 4 |
//! | `hydroxyl_r` | OH Meinel bands 558-727 nm, [`OH_BANDS`] | 450 | 87 | 3.4 |
//! | (continuum) | NO2 continuum, `crate::physics::night_sky::broadband` | `continuum_r_per_nm` | 90 | 6 |
//!
//! **OH.** `hydroxyl_r` is the zenith column of the OH Meinel bands from
//! 550 to 740 nm together (as before, when it held (6-1), (7-2) and (8-3)
//! in thirds): (7-1) near 558, (8-2) 588, (5-0) 615, (9-3) 625, (6-1)
//! 650, (7-2) 686 and (8-3) 727 nm, each a line at its band's centre with
//! the share of [`OH_BANDS`] (photons; approximate shares after the band
//! intensities of Krassovsky, Shefov & Yarin 1962 as Roach & Gordon 1973
//! tabulate them: the Delta v = 5 bands (6-1), (7-2), (8-3) the strongest,
//! the Delta v = 6 bands (7-1), (8-2), (9-3) and (5-0) weaker). The
//! camera records the bands from 558 to 650 nm; (8-3) at 727 nm it barely
//! sees (a red response under 1 % of 630 nm's), and the bands past 740 nm,
//! most of OH's light, are left out. (7-2) at 686 nm lies in the O2 B band
//! and reaches the ground weakened (Johnston & Broadfoot 1993, JGR 98,
//! 21593): [`o2_b_depth`].
//!
//! **The O2 B band** ([`o2_b_depth`]): oxygen's b-X (1,0) band absorbs
//! from 686.7 to 695 nm; over a band of emission lines spread
//! through it its mean zenith optical depth from sea level is taken as 0.5
//! (three fifths of the light through), scaling with the pressure above the
//! observer and the air mass like the air's other depths. It dims the (7-2)
//! band and the continua alike.
//!
//! Sources: brightness and heights, Roach & Gordon (1973), "The Light of
//! the Night Sky", and Leinert et al. (1998), A&AS 127, 1, sect. 9
//! (airglow); Na layer at 92 km, Mende et al. (1993), JGR 98, 19117; OH
//! at 87 km, 8 km full width, Baker & Stair (1988), Phys. Scr. 37, 611
//! (as used by Dunker 2018); the 630.0 / 636.4 ratio 2.997, Storey &
//! Zeippen (2000), MNRAS 312, 813. The O2 emission bands (Herzberg, blue
//! and faint) are left out. docs/physics.md, "Airglow", has the table.

use crate::scene::AirglowParams;
use crate::util::fmath;

/// Photons of OI 630.0 nm per photon of OI 636.4 nm (Storey & Zeippen 2000).
pub const OI_6300_PER_6364: f64 = 2.997;

/// Where a layer's Gaussian is cut, in sigmas (the mass beyond is 2e-9).
pub const CUT_SIGMAS: f64 = 6.0;

/// One airglow layer's shape and lines: (wavelength nm, photons per photon
/// of the layer's key).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LayerShape {
    /// The `[airglow]` key of its zenith brightness.
    pub key: &'static str,
    pub name: &'static str,
    pub peak_km: f64,
    pub sigma_km: f64,
    pub lines: &'static [(f64, f64)],
}

/// The layers of the module documentation's table.
pub const LAYERS: [LayerShape; 4] = [
    LayerShape { key: "green_r", name: "OI 557.7 nm", peak_km: 97.0, sigma_km: 4.0, lines: &[(557.7, 1.0)] },
    LayerShape {
        key: "red_r",
        name: "OI 630.0/636.4 nm",
        peak_km: 250.0,
        sigma_km: 30.0,
        lines: &[(630.0, 1.0), (636.4, 1.0 / OI_6300_PER_6364)],
    },
    LayerShape { key: "sodium_r", name: "Na D 589 nm", peak_km: 92.0, sigma_km: 4.0, lines: &[(589.3, 1.0)] },
    LayerShape { key: "hydroxyl_r", name: "OH Meinel 558-727 nm", peak_km: 87.0, sigma_km: 3.4, lines: &OH_BANDS },
];

/// The OH Meinel bands of `hydroxyl_r`: (band centre nm, share of the
/// key's photons), (7-1), (8-2), (5-0), (9-3), (6-1), (7-2), (8-3) (module doc).
pub const OH_BANDS: [(f64, f64); 7] =
    [(558.0, 0.04), (588.0, 0.07), (615.0, 0.03), (625.0, 0.08), (650.0, 0.22), (686.0, 0.26), (727.0, 0.30)];

/// The airglow continuum's layer (`crate::physics::night_sky::broadband`):
/// its shape only; its brightness is a spectrum, not lines.
pub const CONTINUUM_LAYER: LayerShape =
    LayerShape { key: "continuum_r_per_nm", name: "NO2 continuum", peak_km: 90.0, sigma_km: 6.0, lines: &[] };

/// The O2 B band (module doc): first and last wavelength, nm, and the mean
/// zenith optical depth from sea level across it.
pub const O2_B_BAND: (f64, f64, f64) = (686.7, 695.0, 0.5);

/// The O2 B band's zenith optical depth at `lambda_nm` seen from sea
/// level (module doc); the observer's share is this times the pressure
/// ratio above it.
pub fn o2_b_depth(lambda_nm: f64) -> f64 {
    let (lo, hi, tau) = O2_B_BAND;
    // The 686 nm band line sits at the band head: the band's rotational
    // lines spread over 686-693 nm, so its centre is counted in.
    if (lo - 1.0..=hi).contains(&lambda_nm) {
        tau
    } else {
        0.0
    }
}

/// One line of a layer as a scene sets it: its zenith column seen from the
/// ground, R.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LineColumn {
    pub layer: &'static str,
    pub lambda_nm: f64,
    pub zenith_r: f64,
}

/// A layer's key value in `p`, times `p.scale`.
pub fn key_r(p: &AirglowParams, shape: &LayerShape) -> f64 {
    let r = match shape.key {
        "green_r" => p.green_r,
        "red_r" => p.red_r,
        "sodium_r" => p.sodium_r,
        "continuum_r_per_nm" => p.continuum_r_per_nm,
        _ => p.hydroxyl_r,
    };
    r * p.scale
}

/// Every line's zenith column, R (0 with the airglow off): what the profile
/// reports beside the aurora's columns.
pub fn zenith_columns(p: &AirglowParams) -> Vec<LineColumn> {
    let on = if p.on { 1.0 } else { 0.0 };
    LAYERS
        .iter()
        .flat_map(|l| l.lines.iter().map(move |&(lambda_nm, w)| LineColumn { layer: l.name, lambda_nm, zenith_r: on * w * key_r(p, l) }))
        .collect()
}

/// The normalised profile `N(h)`, per km: the Gaussian of the module doc,
/// 0 beyond [`CUT_SIGMAS`].
pub fn profile_per_km(shape: &LayerShape, h_km: f64) -> f64 {
    let x = (h_km - shape.peak_km) / shape.sigma_km;
    if x.abs() > CUT_SIGMAS {
        return 0.0;
    }
    fmath::exp(-0.5 * x * x) / ((2.0 * std::f64::consts::PI).sqrt() * shape.sigma_km)
}

/// Each line's volume emission rate at `h_km`, R per km (10^6 photons
/// cm^-3 s^-1 per km of column), in [`zenith_columns`] order.
pub fn volume_emission(p: &AirglowParams, h_km: f64) -> Vec<LineColumn> {
    zenith_columns(p)
        .into_iter()
        .map(|c| {
            let shape = LAYERS.iter().find(|l| l.name == c.layer).expect("a layer of LAYERS");
            LineColumn { zenith_r: c.zenith_r * profile_per_km(shape, h_km), ..c }
        })
        .collect()
}

/// Four-point Gauss-Legendre nodes and weights on [-1, 1].
const GL4: [(f64, f64); 4] = [
    (-0.861_136_311_594_052_6, 0.347_854_845_137_453_8),
    (-0.339_981_043_584_856_3, 0.652_145_154_862_546_1),
    (0.339_981_043_584_856_3, 0.652_145_154_862_546_1),
    (0.861_136_311_594_052_6, 0.347_854_845_137_453_8),
];

/// `int N(h(s)) ds` along the ray from an observer at altitude
/// `observer_km` whose direction has cosine `cos_zenith` with the local
/// up, on a sphere of radius `earth_radius_km` (> 0): the column over the
/// zenith column. The ray ends where it meets the Earth. Exact to about
/// 1e-7 (pieces of sigma / 2 in radius, 4 Gauss-Legendre points each, on
/// either side of the ray's closest approach to the centre).
pub fn slant_factor(shape: &LayerShape, earth_radius_km: f64, observer_km: f64, cos_zenith: f64) -> f64 {
    let re = earth_radius_km;
    let r0 = re + observer_km;
    let mu = cos_zenith.clamp(-1.0, 1.0);
    let p2 = r0 * r0 * (1.0 - mu * mu);
    // s of the closest approach; r(s)^2 = p^2 + (s - b)^2.
    let b = -r0 * mu;
    let s_max = if mu < 0.0 && p2 < re * re && r0 >= re { b - (re * re - p2).sqrt() } else { f64::INFINITY };
    let lo = re + (shape.peak_km - CUT_SIGMAS * shape.sigma_km).max(0.0);
    let hi = re + shape.peak_km + CUT_SIGMAS * shape.sigma_km;
    if hi * hi <= p2 {
        return 0.0;
    }
    let dh = (hi * hi - p2).sqrt();
    let dl = (lo * lo - p2).max(0.0).sqrt();
    let n_of = |h: f64| profile_per_km(shape, h - re);
    let mut total = 0.0;
    // Inward (s < b, r falling) and outward (s > b, r rising).
    for side in [-1.0f64, 1.0] {
        let (a, c) = if side < 0.0 { (b - dh, b - dl) } else { (b + dl, b + dh) };
        let (s0, s1) = (a.max(0.0), c.min(s_max));
        if s1 <= s0 {
            continue;
        }
        let r_at = |s: f64| (p2 + (s - b) * (s - b)).sqrt();
        let (ra, rb) = (r_at(s0), r_at(s1));
        let n = ((rb - ra).abs() / (0.5 * shape.sigma_km)).ceil().max(1.0) as usize;
        let s_of = |r: f64| b + side * (r * r - p2).max(0.0).sqrt();
        let mut s_prev = s0;
        for k in 1..=n {
            let s_next = if k == n { s1 } else { s_of(ra + (rb - ra) * k as f64 / n as f64).clamp(s0, s1) };
            let (m, half) = (0.5 * (s_prev + s_next), 0.5 * (s_next - s_prev));
            total += half * GL4.iter().map(|&(x, w)| w * n_of(r_at(m + half * x))).sum::<f64>();
            s_prev = s_next;
        }
    }
    total
}

/// Van Rhijn's factor of a thin layer at `layer_km`, zenith angle
/// `zenith_rad`, observer at `observer_km` (below the layer).
pub fn van_rhijn(earth_radius_km: f64, observer_km: f64, layer_km: f64, zenith_rad: f64) -> f64 {
    let q = (earth_radius_km + observer_km) / (earth_radius_km + layer_km) * fmath::sin(zenith_rad);
    1.0 / (1.0 - q * q).sqrt()
}

/// The slant factor of a Gaussian layer to second order in its width:
/// `V + sigma^2 / 2 f''(r_h)` with `f'' = 3 p^2 r_h / (r_h^2 - p^2)^(5/2)`;
/// also the next term, `sigma^4 / 8 f''''(r_h)`, `f'''' = 15 p^2 r_h (4
/// r_h^2 + 3 p^2) / (r_h^2 - p^2)^(9/2)`, the size of the error.
pub fn thick_layer_factor(shape: &LayerShape, earth_radius_km: f64, observer_km: f64, zenith_rad: f64) -> (f64, f64) {
    let r = earth_radius_km + shape.peak_km;
    let p = (earth_radius_km + observer_km) * fmath::sin(zenith_rad);
    let g = r * r - p * p;
    let s2 = shape.sigma_km * shape.sigma_km;
    let f = r / g.sqrt();
    let f2 = 3.0 * p * p * r * fmath::powf(g, -2.5);
    let f4 = 15.0 * p * p * r * (4.0 * r * r + 3.0 * p * p) * fmath::powf(g, -4.5);
    (f + 0.5 * s2 * f2, s2 * s2 / 8.0 * f4)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// At the zenith the slant factor is the Gaussian's mass above the
    /// observer: 1 from the ground to 1e-7.
    #[test]
    fn the_zenith_column_is_the_key() {
        for l in &LAYERS {
            let f = slant_factor(l, 6371.0, 0.0, 1.0);
            assert!((f - 1.0).abs() < 1e-7, "{}: {f}", l.name);
            // Looking down from the ground: nothing (the Earth).
            assert_eq!(slant_factor(l, 6371.0, 0.0, -0.5), 0.0);
        }
        // The profile integrates to the key.
        let p = AirglowParams::default();
        let col: f64 = (0..4000).map(|i| volume_emission(&p, 0.1 * i as f64 + 0.05)[0].zenith_r * 0.1).sum();
        assert!((col / 250.0 - 1.0).abs() < 1e-6, "{col}");
        let red = zenith_columns(&p);
        assert!((red[1].zenith_r / red[2].zenith_r - 2.997).abs() < 1e-12);
    }
}
