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
//! **The air's scattering** (`[sky] scattering`, with the air). The air
//! near the ground, lit by the whole sky above it and by the ground's
//! reflection of it, scatters that light into every sight line: once, with
//! an isotropic phase function and the source function
//! `J = (Lbar + a E / pi) / 2` taken as constant through the lowest scale
//! heights (`Lbar` the sky's mean radiance over the upper hemisphere, `E`
//! its irradiance on level ground, `a` the ground's albedo), a sight line of
//! zenith depth `tau` at air mass `X` gains `J (1 - exp(-tau X))`
//! (Garstang 1989, PASP 101, 306: the same first-order treatment of the
//! natural sky's brightness). Each line and each nm of the broadband light
//! is scattered at its own depth. Toward the horizon, where the direct
//! light is dimmed, the scattered light takes its place: the sky brightens
//! down to the horizon, two to three times the zenith (as measured skies
//! do, Garstang's Fig. 4), instead of fading. Ozone's absorption is counted
//! as scattering (its depth is under 0.03) and multiple scattering is left
//! out (the air's zenith depth is 0.1-0.3 in the visible). The sky's
//! irradiance on level ground, [`Airglow::ground_irradiance`], lights the
//! terrain (`super::integrator`).
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
    /// The sky's irradiance on level ground (module doc), the volume's
    /// radiance unit times sr.
    ground: [f64; 3],
}

/// Elevation step of the hemisphere integrals, degrees.
const HEMISPHERE_STEP_DEG: f64 = 0.25;

/// Midpoints of the hemisphere integrals: [`HEMISPHERE_STEP_DEG`] apart.
const HEMISPHERE_SAMPLES: usize = (90.0 / HEMISPHERE_STEP_DEG) as usize;

/// The elevation of the hemisphere integrals' `k`-th midpoint, degrees.
fn hemisphere_elevation(k: usize) -> f64 {
    (k as f64 + 0.5) * HEMISPHERE_STEP_DEG
}

/// `f` at each of the hemisphere integrals' midpoints: a table that the
/// integrands of many lines and wavelengths share.
fn hemisphere_table(f: impl Fn(f64) -> f64) -> Vec<f64> {
    (0..HEMISPHERE_SAMPLES).map(|k| f(hemisphere_elevation(k))).collect()
}

/// The two hemisphere means of a radiance `g(e)` that depends only on the
/// elevation `e` (degrees): over the upper hemisphere's solid angle, and
/// its irradiance on level ground over pi (both 1 for a uniform sky of 1).
/// Midpoint rule over [`HEMISPHERE_STEP_DEG`].
pub fn hemisphere_means(g: impl Fn(f64) -> f64) -> (f64, f64) {
    hemisphere_means_at(|k| g(hemisphere_elevation(k)))
}

/// [`hemisphere_means`] of `g(k)`, the radiance at the `k`-th midpoint
/// ([`hemisphere_elevation`]).
fn hemisphere_means_at(g: impl Fn(usize) -> f64) -> (f64, f64) {
    let h = HEMISPHERE_STEP_DEG.to_radians();
    let (mut mean, mut cos_mean) = (0.0, 0.0);
    for k in 0..HEMISPHERE_SAMPLES {
        let e = hemisphere_elevation(k);
        let (s, c) = (fmath::sin(e.to_radians()), fmath::cos(e.to_radians()));
        let v = g(k);
        mean += v * c * h;
        cos_mean += 2.0 * v * s * c * h;
    }
    (mean, cos_mean)
}

/// The scattering's source function from the two hemisphere means and the
/// ground's albedo: `J = (Lbar + a E / pi) / 2` (module doc).
pub fn source_function(mean: f64, cos_mean: f64, ground_albedo: f64) -> f64 {
    0.5 * (mean + ground_albedo * cos_mean)
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
    /// factor `layer`, plus what the air scatters in at that air mass
    /// (`source`: each nm's source function, R/nm, or none): the sum over
    /// the nm, into the observer's gamut once.
    fn radiance(&self, space: f64, layer: f64, x: f64, source: Option<&[f64]>) -> [f64; 3] {
        let mut rgb = [0.0; 3];
        for (i, &(c, tau, outside, cont)) in self.nm.iter().enumerate() {
            let t = fmath::exp(-tau * x);
            let scattered = source.map_or(0.0, |j| j[i] * (1.0 - t));
            let w = ((space * outside + layer * cont) * t + scattered) * KR_PER_R;
            for k in 0..3 {
                rgb[k] += w * c[k];
            }
        }
        self.observer.in_gamut(rgb)
    }

    /// Each nm's source function of the air's scattering (module doc), R/nm:
    /// the outside light and the continuum's layer seen from the ground
    /// through the air; `layer` and `mass` are the continuum's slant factor
    /// and the air mass at the hemisphere's midpoints ([`hemisphere_table`]).
    fn sources(&self, layer: &[f64], mass: &[f64], ground_albedo: f64) -> Vec<f64> {
        self.nm
            .iter()
            .map(|&(_, tau, outside, cont)| {
                let (m, cm) = hemisphere_means_at(|k| (outside + layer[k] * cont) * fmath::exp(-tau * mass[k]));
                source_function(m, cm, ground_albedo)
            })
            .collect()
    }
}

impl Airglow {
    /// The airglow of `p` seen from `position` (scene frame, km), or None
    /// when `[airglow] on = false` or every layer is 0; each line in
    /// `observer`'s colour, as the volume's.
    /// `ground_albedo`: the ground's reflectance for the air's scattering
    /// (the terrain's, or the snow's default where there is none).
    pub fn new(
        p: &AirglowParams,
        sky: &SkyParams,
        position: DVec3,
        earth_radius_km: f64,
        observer: Observer,
        ground_albedo: f64,
    ) -> Option<Airglow> {
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
        // The air's scattering (module doc): each line's and each nm's source
        // function, from the sky above the ground seen through the air.
        let scatters = air.is_some() && sky.scattering;
        // Each layer's slant factor and the air mass over the hemisphere,
        // once: every line of a layer and every nm read them.
        let slant_table = |shape| hemisphere_table(|e| slant_factor(shape, shells_km, altitude, fmath::sin(e.to_radians())));
        let (mass, layer_slants, continuum_slants) = if scatters {
            (hemisphere_table(air_mass), LAYERS.iter().map(slant_table).collect(), slant_table(&CONTINUUM_LAYER))
        } else {
            (Vec::new(), Vec::new(), Vec::new())
        };
        let line_sources: Vec<f64> = lines
            .iter()
            .map(|l| {
                if !scatters {
                    return 0.0;
                }
                let slants: &Vec<f64> = &layer_slants[l.layer];
                let (m, cm) = hemisphere_means_at(|k| slants[k] * fmath::exp(-l.tau * mass[k]));
                source_function(m, cm, ground_albedo)
            })
            .collect();
        let broad_sources = broad.as_ref().filter(|_| scatters).map(|b| b.sources(&continuum_slants, &mass, ground_albedo));
        let table = (0..n)
            .map(|i| {
                let e = -90.0 + i as f64 * STEP_DEG;
                let mu = fmath::sin(e.to_radians());
                let x = air_mass(e);
                let f: Vec<f64> = LAYERS.iter().map(|l| slant_factor(l, shells_km, altitude, mu)).collect();
                // The scattered light comes from the air along sight lines above
                // the horizon (below it they end on the ground).
                let above = e >= 0.0;
                let mut rgb = [0.0; 3];
                for (l, &j) in lines.iter().zip(&line_sources) {
                    let direct = fmath::exp(-l.tau * x);
                    let t = f[l.layer] * direct + if above { j * (1.0 - direct) } else { 0.0 };
                    for c in 0..3 {
                        rgb[c] += l.rgb_kr[c] * t;
                    }
                }
                if let Some(b) = &broad {
                    // Light from outside the air reaches the camera unless the
                    // solid Earth is in the way.
                    let space = !(mu < 0.0 && r0 * r0 * (1.0 - mu * mu) < shells_km * shells_km && r0 >= shells_km);
                    let layer = slant_factor(&CONTINUUM_LAYER, shells_km, altitude, mu);
                    let c = b.radiance(if space { 1.0 } else { 0.0 }, layer, x, broad_sources.as_deref().filter(|_| above));
                    for k in 0..3 {
                        rgb[k] += c[k];
                    }
                }
                rgb
            })
            .collect();
        let mut glow = Airglow { up, table, ground: [0.0; 3] };
        if scatters {
            glow.ground = [0, 1, 2].map(|c| {
                let (_, cos_mean) = hemisphere_means(|e| glow.at_elevation(e)[c]);
                std::f64::consts::PI * cos_mean
            });
        }
        Some(glow)
    }

    /// The sky's irradiance on ground of normal `n` (unit): on level ground
    /// the table's cosine-weighted integral over the upper hemisphere, on a
    /// slope the part of it a uniform sky would give, `(1 + n . up) / 2`
    /// (the terrain's own hiding of the sky is left out). Zero without the
    /// air's scattering (`[sky] scattering`).
    pub fn ground_irradiance(&self, n: DVec3) -> [f64; 3] {
        let f = 0.5 * (1.0 + n.dot(self.up).clamp(-1.0, 1.0));
        self.ground.map(|c| c * f)
    }

    /// Radiance along `dir` (unit), linear between the table's elevations.
    pub fn radiance(&self, dir: DVec3) -> [f64; 3] {
        self.at_elevation(fmath::asin(self.up.dot(dir).clamp(-1.0, 1.0)).to_degrees())
    }

    /// Radiance at elevation `e` degrees, linear between the table's.
    fn at_elevation(&self, e: f64) -> [f64; 3] {
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
        let a = Airglow::new(&p, &sky, DVec3::ZERO, 6371.0, Observer::Camera, 0.85).unwrap();
        let l = a.radiance(DVec3::Z);
        let want = line_rgb(557.7, Observer::Camera).map(|c| c * 0.25);
        for c in 0..3 {
            assert!((l[c] - want[c]).abs() <= 1e-6 * want[1], "{l:?} {want:?}");
        }
        assert_eq!(a.radiance(-DVec3::Z), [0.0; 3]);
        assert!(Airglow::new(&AirglowParams { on: false, ..p }, &sky, DVec3::ZERO, 6371.0, Observer::Camera, 0.85).is_none());
    }
}
