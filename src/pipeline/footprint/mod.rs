//! The footprint of a curtain: a 2D density map on the ground plane saying
//! where (and how strongly) electrons precipitate.
//!
//! Two models (`footprint.model`): `"sheet"` (the default, [`sheet`]), a
//! vortex sheet rolled up by the Kelvin-Helmholtz instability and drawn with
//! rays along it; and `"fluid2014"`, as in the 2014 report (section 2.1, after
//! Lawlor & Genetti 2011), a straight band folded by a short 2D fluid
//! simulation. Either is then bent along a low-frequency noise curve and
//! faded to 0 over `end_fade_km` at each end ([`end_fade`]). The fluid:
//!
//! 1. Stable fluids ([`fluid`]: Stam, "Stable Fluids", SIGGRAPH 1999) on a
//!    MAC grid in the curtain's own frame (u along the curtain, v across;
//!    cell units): semi-Lagrangian advection, then a pressure projection by
//!    red-black Gauss-Seidel with over-relaxation.
//! 2. Initial density: a band across the middle (`band_fraction` of the
//!    width), modulated along u by a sine wave (`density_waves`). Initial
//!    velocity: the curl of a stream function made of sine waves along u
//!    (`velocity_waves`, `velocity_amplitude`), a row of counter-rotating
//!    vortices sitting on the band, so the band folds and curls.
//! 3. Remap along a noise curve: `out(u, v) = sim(u, v - bend(u))`, `bend` a
//!    1D Perlin noise of amplitude `bend_km` and wavelength
//!    `bend_wavelength * length`; normalised to a peak of 1.
//!
//! A curtain with a `path` runs the same simulation in the path's arc length
//! and normal (`crate::pipeline::footprint::curtain_path::PathFrame`), the path lifted from its altitude
//! to the beams' start altitude along the field ([`crate::pipeline::footprint::curtain_path::lift_km`]).
//! Along a long path the cells stay at most twice as long as they are wide
//! (the sheet's about as long as wide, straight or not: [`cells_along`],
//! up to [`MAX_PATH_CELLS`]), and the fluid's patterns
//! along u (its waves, the bend's wavelength) keep their size in cells: they
//! are set per `resolution[0]` cells, so a path of one resolution's worth of
//! cells is simulated exactly as the straight curtain of its length.

use crate::util::fmath;

pub mod cells;
pub mod curtain_path;
pub mod fluid;
pub mod magnetic_placement;
pub mod sheet;

pub use cells::Cells;
use fluid::bilinear;
pub use fluid::Fluid;

use crate::pipeline::footprint::curtain_path::PathFrame;
use crate::scene::{AnimationParams, Curtain, FootprintModel, FootprintParams};
use crate::util::rng;
use std::path::Path;
use std::sync::Arc;

/// Most cells along a path's footprint.
pub const MAX_PATH_CELLS: usize = 16_384;

/// Cells along a curtain's footprint: `resolution[0]`, or along a path of
/// `length` km at least enough for cells at most twice the cell width
/// across, up to [`MAX_PATH_CELLS`].
pub fn cells_along(curtain: &Curtain, length: f64, params: &FootprintParams) -> usize {
    let [nx, ny] = params.resolution;
    let dv = curtain.width / ny as f64;
    match params.model {
        FootprintModel::Sheet => nx.max(((length / dv).round() as usize).min(MAX_PATH_CELLS)),
        FootprintModel::Fluid2014 if curtain.path.is_none() => nx,
        FootprintModel::Fluid2014 => nx.max(((length / (2.0 * dv)).ceil() as usize).min(MAX_PATH_CELLS)),
    }
}

/// A footprint placed along a path: its frame and the drift across it, km.
#[derive(Clone, Debug, PartialEq)]
pub struct PlacedPath {
    pub frame: PathFrame,
    pub drift_km: f64,
}

/// A curtain's footprint: densities in [0, 1] on an nx x ny grid in the
/// curtain frame, placed on the ground plane by centre and rotation.
#[derive(Clone, Debug, PartialEq)]
pub struct Footprint {
    pub nx: usize,
    pub ny: usize,
    /// Cell (i, j) at index `j * nx + i`; i along the curtain (u), j across (v).
    pub data: Vec<f32>,
    pub center: [f64; 2],
    pub rotation_rad: f64,
    /// Extent along u and across v, km.
    pub length: f64,
    pub width: f64,
    /// Along a path instead of the straight frame of `center` and
    /// `rotation_rad` (which then give the path's middle and its direction).
    pub path: Option<Arc<PlacedPath>>,
    /// The energy flux at density 1, in units of the curtain's
    /// `energy_flux`: 1, or with filaments the peak of body and filaments
    /// summed by their fluxes.
    pub flux_scale: f64,
    /// With filaments: each cell's share of its flux carried by them.
    pub filament_share: Option<Arc<Vec<f32>>>,
}

/// A footprint's map from world (x, y) to its curtain frame (u, v)
/// ([`Footprint::local_map`]).
#[derive(Clone, Copy, Debug)]
pub struct LocalMap<'a> {
    path: Option<&'a PlacedPath>,
    center: [f64; 2],
    /// Sine and cosine of the rotation (unused along a path).
    sin_cos: (f64, f64),
}

impl LocalMap<'_> {
    /// World (x, y) to curtain frame (u, v), km.
    #[inline]
    pub fn to_local(&self, x: f64, y: f64) -> (f64, f64) {
        if let Some(p) = self.path {
            let (u, v) = p.frame.to_local(x, y);
            return (u, v - p.drift_km);
        }
        let (s, c) = self.sin_cos;
        let (dx, dy) = (x - self.center[0], y - self.center[1]);
        (dx * c + dy * s, -dx * s + dy * c)
    }
}

/// A footprint PNG could not be written.
#[derive(Debug, thiserror::Error)]
pub enum FootprintError {
    #[error("{path}: {source}")]
    Io { path: String, source: std::io::Error },
    #[error("{path}: PNG encoding failed: {message}")]
    Png { path: String, message: String },
    #[error(transparent)]
    Output(Box<crate::util::atomic_write::AtomicError>),
}

impl FootprintError {
    /// True when the user's choice of output is at fault (exit status 2).
    pub fn is_input(&self) -> bool {
        matches!(self, FootprintError::Output(a) if a.is_input())
    }
}

impl Footprint {
    /// Cell size along u and v, km.
    pub fn cell_size(&self) -> (f64, f64) {
        (self.length / self.nx as f64, self.width / self.ny as f64)
    }

    pub fn cell_area_km2(&self) -> f64 {
        let (du, dv) = self.cell_size();
        du * dv
    }

    /// World (x, y) to curtain frame (u, v), km.
    #[inline]
    pub fn to_local(&self, x: f64, y: f64) -> (f64, f64) {
        self.local_map().to_local(x, y)
    }

    /// [`Self::to_local`] for many points: the rotation's sine and cosine
    /// taken once (the same values, so the same bits).
    #[inline]
    pub fn local_map(&self) -> LocalMap<'_> {
        let sin_cos = if self.path.is_some() { (0.0, 1.0) } else { fmath::sin_cos(self.rotation_rad) };
        LocalMap { path: self.path.as_deref(), center: self.center, sin_cos }
    }

    /// Curtain frame (u, v) to world (x, y), km.
    #[inline]
    pub fn to_world(&self, u: f64, v: f64) -> (f64, f64) {
        if let Some(p) = &self.path {
            return p.frame.to_world(u, v + p.drift_km);
        }
        let (s, c) = fmath::sin_cos(self.rotation_rad);
        (self.center[0] + u * c - v * s, self.center[1] + u * s + v * c)
    }

    /// Continuous cell coordinates of (u, v): cell (i, j) spans [i, i + 1).
    #[inline]
    fn cell_coords(&self, u: f64, v: f64) -> (f64, f64) {
        let (du, dv) = self.cell_size();
        ((u + 0.5 * self.length) / du, (v + 0.5 * self.width) / dv)
    }

    /// The cell (i, j) holding (u, v) in the curtain frame, clamped to
    /// the grid.
    #[inline]
    pub fn cell_index(&self, u: f64, v: f64) -> (usize, usize) {
        let (gx, gy) = self.cell_coords(u, v);
        ((gx.max(0.0) as usize).min(self.nx - 1), (gy.max(0.0) as usize).min(self.ny - 1))
    }

    /// Density of cell (i, j).
    #[inline]
    pub fn cell(&self, i: usize, j: usize) -> f32 {
        self.data[j * self.nx + i]
    }

    /// Bilinear interpolation between cell centres in the curtain frame; zero
    /// outside the footprint box (cells beyond the edge count as 0).
    pub fn sample_local(&self, u: f64, v: f64) -> f64 {
        let (gx, gy) = self.cell_coords(u, v);
        let (x, y) = (gx - 0.5, gy - 0.5);
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let get = |i: f64, j: f64| -> f64 {
            if i < 0.0 || j < 0.0 || i >= self.nx as f64 || j >= self.ny as f64 {
                0.0
            } else {
                self.cell(i as usize, j as usize) as f64
            }
        };
        let a = get(x0, y0) * (1.0 - fx) + get(x0 + 1.0, y0) * fx;
        let b = get(x0, y0 + 1.0) * (1.0 - fx) + get(x0 + 1.0, y0 + 1.0) * fx;
        a * (1.0 - fy) + b * fy
    }

    /// Bilinear sample at world (x, y).
    pub fn sample_world(&self, x: f64, y: f64) -> f64 {
        let (u, v) = self.to_local(x, y);
        self.sample_local(u, v)
    }

    /// The piecewise-constant density of the cell holding world (x, y) (0
    /// outside): the distribution beams are drawn from, and the one their
    /// "still inside the footprint" test uses, so the two agree exactly.
    #[inline]
    pub fn cell_value_world(&self, x: f64, y: f64) -> f64 {
        let (u, v) = self.to_local(x, y);
        let (gx, gy) = self.cell_coords(u, v);
        if gx < 0.0 || gy < 0.0 || gx >= self.nx as f64 || gy >= self.ny as f64 {
            return 0.0;
        }
        self.cell(gx as usize, gy as usize) as f64
    }

    /// Integral of the density over the cells above `threshold`, km^2: the
    /// footprint's effective area (peak flux times this is the curtain power).
    pub fn integral_above(&self, threshold: f64) -> f64 {
        let s: f64 = self.data.iter().map(|&d| d as f64).filter(|&d| d > threshold).sum();
        s * self.cell_area_km2()
    }

    /// Writes an 8-bit greyscale PNG: columns along the curtain (u), rows
    /// across it with +v at the top; 255 = density 1. Written to a temporary
    /// name in the same folder, then renamed.
    pub fn write_png(&self, path: &Path) -> Result<(), FootprintError> {
        let name = path.display().to_string();
        let png_err = |e: png::EncodingError| FootprintError::Png { path: name.clone(), message: e.to_string() };
        let mut pixels = Vec::with_capacity(self.nx * self.ny);
        for j in (0..self.ny).rev() {
            for i in 0..self.nx {
                pixels.push((self.cell(i, j).clamp(0.0, 1.0) * 255.0).round() as u8);
            }
        }
        let mut tmp = crate::util::atomic_write::TempFile::create(path).map_err(|e| FootprintError::Output(Box::new(e)))?;
        {
            let w = std::io::BufWriter::new(tmp.file());
            let mut enc = png::Encoder::new(w, self.nx as u32, self.ny as u32);
            enc.set_color(png::ColorType::Grayscale);
            enc.set_depth(png::BitDepth::Eight);
            let mut writer = enc.write_header().map_err(png_err)?;
            writer.write_image_data(&pixels).map_err(png_err)?;
            writer.finish().map_err(png_err)?;
        }
        tmp.commit().map_err(|e| FootprintError::Output(Box::new(e)))
    }
}

/// Simulates one curtain's footprint. `seed` is the scene seed; the
/// curtain's own seed is mixed in, so curtains differ. The still: the same as
/// [`simulate_at`] at t = 0, whatever the motion.
/// A path is taken as given (no lift).
pub fn simulate(curtain: &Curtain, params: &FootprintParams, seed: u64) -> Footprint {
    simulate_at(curtain, params, &AnimationParams::default(), seed, 0.0, [0.0, 0.0])
}

/// The footprint at time `t` s (closed form in t: its cost does not grow
/// with t). The initial conditions of the fluid move, and the fluid is
/// integrated for the same `steps` from them:
/// - the vortex row's three modes travel along the curtain at
///   `fold_speed_kms` times 1, -0.5 and 1.6 (a dispersive row: folds form,
///   merge and part instead of sliding rigidly), and their amplitude swings
///   by `fold_breathing` with period `fold_breathing_period_s` (folds deepen
///   and relax);
/// - the density waves along the band travel at 0.8 `fold_speed_kms`;
/// - the bend curve travels at `bend_speed_kms` and changes shape at
///   `bend_change_hz` (its Perlin noise read along a second axis, time);
/// - the whole footprint drifts across its axis by
///   `drift_km sin(2 pi t / drift_period_s)` (bounded: it never leaves).
///
/// Every term is a smooth function of t and the fluid's update is continuous
/// in its initial state, so consecutive frames differ by little.
///
/// With `params.uniform` (for validation) the density is 1 in every cell,
/// with no fluid and no bend; the drift still applies.
///
/// `lift` (km) moves a path from its altitude to the beams' start altitude
/// ([`crate::pipeline::footprint::curtain_path::lift_km`]); a straight curtain's `center` is already there.
pub fn simulate_at(
    curtain: &Curtain,
    params: &FootprintParams,
    anim: &AnimationParams,
    seed: u64,
    t: f64,
    lift: impl Into<crate::pipeline::footprint::curtain_path::Lift>,
) -> Footprint {
    let lift = lift.into();
    let frame = curtain.path.as_ref().map(|p| PathFrame::new(&lift.path(p), curtain.width));
    let length = frame.as_ref().map_or(curtain.length, |f| f.length);
    let nx = cells_along(curtain, length, params);
    let ny = params.resolution[1];
    let cells = Cells { nx, ny, length, width: curtain.width };
    if params.uniform {
        return place(curtain, anim, t, frame, cells, vec![1.0; nx * ny]);
    }
    // Patterns along u are set per resolution[0] cells (module documentation).
    let along = nx as f64 / params.resolution[0] as f64;
    let filaments = crate::physics::deposition::curtain_spectrum::has_filaments(curtain) && params.model == FootprintModel::Sheet;
    if filaments {
        // An arc with filaments: both layers bent and faded alike, summed
        // by their peak fluxes, normalised to a peak of 1; the filaments'
        // share of each cell's flux kept for the beams.
        let (body, fil) = sheet::arc_layers(cells, params, anim, [seed, curtain.seed], t);
        let body = bent_and_faded(curtain, params, anim, seed, t, cells, along, &body);
        let fil = bent_and_faded(curtain, params, anim, seed, t, cells, along, &fil);
        let ratio = (curtain.filament_energy_flux / curtain.energy_flux) as f32;
        let sum: Vec<f32> = body.iter().zip(&fil).map(|(b, f)| b + ratio * f).collect();
        let share: Vec<f32> =
            body.iter().zip(&fil).zip(&sum).map(|((_, f), s)| if *s > 0.0 { (ratio * f / s).min(1.0) } else { 0.0 }).collect();
        let peak = sum.iter().cloned().fold(0.0f32, f32::max);
        let data: Vec<f32> = if peak > 0.0 { sum.iter().map(|v| v / peak).collect() } else { sum };
        let mut fp = place(curtain, anim, t, frame, cells, data);
        fp.flux_scale = peak.max(f32::MIN_POSITIVE) as f64;
        fp.filament_share = Some(Arc::new(share));
        return fp;
    }
    let sim = match params.model {
        FootprintModel::Fluid2014 => fluid2014(curtain, params, anim, seed, t, cells, along),
        FootprintModel::Sheet => sheet::density(cells, params, anim, [seed, curtain.seed], t),
    };
    let mut data = bent_and_faded(curtain, params, anim, seed, t, cells, along, &sim);
    let peak = data.iter().cloned().fold(0.0f32, f32::max);
    if peak > 0.0 {
        for d in &mut data {
            *d /= peak;
        }
    }
    place(curtain, anim, t, frame, cells, data)
}

/// A simulated layer remapped along the noise curve, `out(u, v) = sim(u, v -
/// bend(u))` (the curve travelling and changing shape in time), and faded
/// over `end_fade_km` at the curtain's ends; not normalised.
#[allow(clippy::too_many_arguments)]
fn bent_and_faded(
    curtain: &Curtain,
    params: &FootprintParams,
    anim: &AnimationParams,
    seed: u64,
    t: f64,
    cells: Cells,
    along: f64,
    sim: &[f64],
) -> Vec<f32> {
    let Cells { nx, ny, length, .. } = cells;
    let noise = rng::perlin(&[seed, curtain.seed, rng::tag::FOOTPRINT_BEND]);
    let dv_km = curtain.width / ny as f64;
    let wavelength = params.bend_wavelength * length / along;
    let mut data = vec![0.0f32; nx * ny];
    for i in 0..nx {
        let u_km = (i as f64 + 0.5) / nx as f64 * length - anim.bend_speed_kms * t;
        let n = if anim.bend_change_hz > 0.0 && t != 0.0 {
            rng::noise2(&noise, u_km / wavelength, rng::NOISE1_Y + anim.bend_change_hz * t)
        } else {
            rng::noise1(&noise, u_km / wavelength)
        };
        let bend_cells = curtain.bend_km * n / dv_km;
        for j in 0..ny {
            let y = j as f64 + 0.5 - bend_cells;
            let v = if y < 0.5 || y > ny as f64 - 0.5 { 0.0 } else { bilinear(sim, nx, ny, 0.5, 0.5, i as f64 + 0.5, y) };
            data[j * nx + i] = v as f32;
        }
    }
    if params.end_fade_km > 0.0 {
        for i in 0..nx {
            let w = end_fade((i as f64 + 0.5) / nx as f64 * length, length, params.end_fade_km) as f32;
            for j in 0..ny {
                data[j * nx + i] *= w;
            }
        }
    }
    data
}

/// The 2014 report's footprint before the bend: the band folded by the
/// stable fluid (module documentation), on the nx x ny cells.
fn fluid2014(curtain: &Curtain, params: &FootprintParams, anim: &AnimationParams, seed: u64, t: f64, cells: Cells, along: f64) -> Vec<f64> {
    let Cells { nx, ny, length, .. } = cells;
    let tau = std::f64::consts::TAU;
    let mut fluid = Fluid::new(nx, ny);
    let mut r = rng::rng(&[seed, curtain.seed, rng::tag::FOOTPRINT_VELOCITY]);
    use rand::Rng;
    let du_km = length / nx as f64;
    // Travel of a phase pattern at speed c km/s: k (x - c t / du).
    let shift = |speed_kms: f64| speed_kms * t / du_km;
    let phase_d: f64 = r.random::<f64>() * tau;
    let phase_v: f64 = r.random::<f64>() * tau;
    let phase_v2: f64 = r.random::<f64>() * tau;
    let phase_v3: f64 = r.random::<f64>() * tau;

    // Band across the middle, smooth over one cell at its edges (no aliasing).
    let half = 0.5 * params.band_fraction * ny as f64;
    let yc = 0.5 * ny as f64;
    let xd = shift(0.8 * anim.fold_speed_kms);
    for j in 0..ny {
        let y = j as f64 + 0.5;
        let edge = (half - (y - yc).abs() + 0.5).clamp(0.0, 1.0);
        for i in 0..nx {
            let x = (i as f64 + 0.5 - xd) / nx as f64;
            let m = 0.55 + 0.45 * fmath::sin(tau * params.density_waves * along * x + phase_d);
            fluid.density[j * nx + i] = edge * m;
        }
    }

    // Stream function: sine waves along u times a half sine across (zero on
    // the side walls), psi = A / k_u sin(k_u x + phase) sin(pi y / ny), so the
    // velocity across the band has amplitude A. A second, shorter wave at half
    // amplitude breaks the regularity, and a third, short one confined to the
    // band (Gaussian across it, a few band widths wide) spins small vortices
    // that curl the band locally: their rotation rate A k is the fastest.
    let breathing =
        if anim.fold_breathing > 0.0 { 1.0 + anim.fold_breathing * fmath::sin(tau * t / anim.fold_breathing_period_s) } else { 1.0 };
    let a = params.velocity_amplitude * breathing;
    let k1 = tau * params.velocity_waves * along / nx as f64;
    let k2 = tau * params.velocity_waves * along * 1.73 / nx as f64;
    let k3 = tau * params.velocity_waves * along * 3.7 / nx as f64;
    let (x1, x2, x3) = (shift(anim.fold_speed_kms), shift(-0.5 * anim.fold_speed_kms), shift(1.6 * anim.fold_speed_kms));
    let sigma3 = (3.0 * half).max(2.0);
    fluid.set_stream_function(|x, y| {
        let across = fmath::sin(std::f64::consts::PI * y / ny as f64);
        let mut psi = 0.0;
        if k1 > 0.0 {
            psi += a / k1 * fmath::sin(k1 * (x - x1) + phase_v) * across;
            psi += 0.5 * a / k2 * fmath::sin(k2 * (x - x2) + phase_v2) * across;
            let g = fmath::exp(-0.5 * fmath::powi((y - yc) / sigma3, 2));
            psi += 0.6 * a / k3 * fmath::sin(k3 * (x - x3) + phase_v3) * g * across;
        }
        psi
    });
    fluid.project(params.pressure_iterations);
    for _ in 0..params.steps {
        fluid.step(params.dt, params.pressure_iterations);
    }

    fluid.density
}

/// The weight of the end fade at `u_km` from the start of a footprint of
/// `length` km: a smooth step (3s^2 - 2s^3) from 0 at either end to 1 at
/// `fade_km` inside (the fades meet in the middle of a short curtain).
pub fn end_fade(u_km: f64, length: f64, fade_km: f64) -> f64 {
    if fade_km <= 0.0 {
        return 1.0;
    }
    let s = (u_km.min(length - u_km) / fade_km).clamp(0.0, 1.0);
    s * s * (3.0 - 2.0 * s)
}

/// The footprint placed at time `t`: along its path, or about `center`,
/// moved across its axis (the curtain frame's +v) by the bounded drift.
fn place(curtain: &Curtain, anim: &AnimationParams, t: f64, frame: Option<PathFrame>, cells: Cells, data: Vec<f32>) -> Footprint {
    let Cells { nx, ny, length, .. } = cells;
    let tau = std::f64::consts::TAU;
    let rot = curtain.rotation_deg.to_radians();
    let drift = if anim.drift_km > 0.0 { anim.drift_km * fmath::sin(tau * t / anim.drift_period_s) } else { 0.0 };
    if let Some(frame) = frame {
        let path = PlacedPath { frame, drift_km: drift };
        let mid = path.frame.to_world(0.0, drift);
        let ahead = path.frame.to_world(1e-3, drift);
        let rotation_rad = fmath::atan2(ahead.1 - mid.1, ahead.0 - mid.0);
        return Footprint {
            nx,
            ny,
            data,
            center: [mid.0, mid.1],
            rotation_rad,
            length,
            width: curtain.width,
            path: Some(Arc::new(path)),
            flux_scale: 1.0,
            filament_share: None,
        };
    }
    let center = [curtain.center[0] - drift * fmath::sin(rot), curtain.center[1] + drift * fmath::cos(rot)];
    Footprint {
        nx,
        ny,
        data,
        center,
        rotation_rad: rot,
        length: curtain.length,
        width: curtain.width,
        path: None,
        flux_scale: 1.0,
        filament_share: None,
    }
}

/// The 2014 fluid on a small grid, no end fade: a broad folded band of
/// hundreds of cells, for the tests of the footprint and of the starts
/// drawn on it.
#[cfg(test)]
pub(crate) fn small_params() -> FootprintParams {
    FootprintParams {
        model: FootprintModel::Fluid2014,
        resolution: [128, 48],
        steps: 6,
        pressure_iterations: 30,
        end_fade_km: 0.0,
        ..FootprintParams::default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use super::small_params;

    #[test]
    fn sheet_footprint_is_normalised_deterministic_continuous_and_fades_at_its_ends() {
        let c = Curtain { length: 80.0, width: 20.0, ..Curtain::default() };
        let p = FootprintParams { resolution: [256, 64], sheet_steps: 8, end_fade_km: 10.0, ..FootprintParams::default() };
        let a = simulate(&c, &p, 3);
        assert_eq!(a, simulate(&c, &p, 3));
        let peak = a.data.iter().cloned().fold(0.0f32, f32::max);
        assert!((peak - 1.0).abs() < 1e-6 && a.data.iter().all(|d| (0.0..=1.0).contains(d)));
        assert_ne!(simulate(&Curtain { seed: 4, ..c.clone() }, &p, 3).data, a.data);
        // The end fade: the first and last columns are all but dark (the
        // smooth step at half a cell of 10 km), the middle is not.
        let column = |i: usize| (0..a.ny).map(|j| a.cell(i, j)).fold(0.0f32, f32::max);
        assert!(column(0) < 1e-3 && column(a.nx - 1) < 1e-3, "{} {}", column(0), column(a.nx - 1));
        assert!((a.nx / 4..3 * a.nx / 4).map(column).fold(0.0f32, f32::max) > 0.5);
        assert_eq!(end_fade(5.0, 80.0, 10.0), 0.5);
        assert_eq!(end_fade(40.0, 80.0, 10.0), 1.0);
        // Motion: a tenth of a frame's step changes it by well under half
        // a frame's change (L1 per cell).
        let anim = AnimationParams::default();
        let l1 = |x: &Footprint, y: &Footprint| x.data.iter().zip(&y.data).map(|(u, v)| (u - v).abs() as f64).sum::<f64>();
        let f0 = simulate_at(&c, &p, &anim, 3, 50.0, [0.0; 2]);
        let (f1, f10) =
            (simulate_at(&c, &p, &anim, 3, 50.0 + 1.0 / 24.0, [0.0; 2]), simulate_at(&c, &p, &anim, 3, 50.0 + 1.0 / 240.0, [0.0; 2]));
        let (near, tenth) = (l1(&f0, &f1), l1(&f0, &f10));
        assert!(near > 0.0 && tenth < 0.3 * near, "1/240 s {tenth}, 1/24 s {near}");
    }

    #[test]
    fn footprint_is_normalised_deterministic_and_follows_its_frame() {
        let c = Curtain { center: [10.0, -5.0], rotation_deg: 30.0, ..Curtain::default() };
        let p = small_params();
        let a = simulate(&c, &p, 42);
        let b = simulate(&c, &p, 42);
        assert_eq!(a, b);
        let peak = a.data.iter().cloned().fold(0.0f32, f32::max);
        assert!((peak - 1.0).abs() < 1e-6);
        assert!(a.data.iter().all(|d| (0.0..=1.0).contains(d)));
        // Local <-> world round trip, and the peak cell found through the
        // world sampler.
        let (x, y) = a.to_world(12.3, -4.5);
        let (u, v) = a.to_local(x, y);
        assert!((u - 12.3).abs() < 1e-12 && (v + 4.5).abs() < 1e-12);
        let k = a.data.iter().position(|&d| d == peak).unwrap();
        let (i, j) = (k % a.nx, k / a.nx);
        let (du, dv) = a.cell_size();
        let (x, y) = a.to_world(-0.5 * a.length + (i as f64 + 0.5) * du, -0.5 * a.width + (j as f64 + 0.5) * dv);
        assert!((a.sample_world(x, y) - 1.0).abs() < 1e-6);
        assert_eq!(a.cell_value_world(x, y), 1.0);
        assert_eq!(a.sample_world(1e4, 0.0), 0.0);
        // A different curtain seed gives a different footprint.
        let c2 = Curtain { seed: 9, ..c };
        assert_ne!(simulate(&c2, &p, 42).data, a.data);
    }

    #[test]
    fn uniform_footprint_is_one_everywhere_and_still_drifts() {
        let c = Curtain { bend_km: 8.0, ..Curtain::default() };
        let p = FootprintParams { uniform: true, ..small_params() };
        let f = simulate(&c, &p, 5);
        assert_eq!((f.nx, f.ny), (128, 48));
        assert!(f.data.iter().all(|&d| d == 1.0));
        assert!((f.integral_above(p.threshold) - f.length * f.width).abs() < 1e-9 * f.length * f.width);
        // The drift moves the box as it moves the simulated footprint.
        let anim = AnimationParams { drift_km: 5.0, drift_period_s: 40.0, ..AnimationParams::default() };
        let (a, b) = (
            simulate_at(&c, &p, &anim, 5, 10.0, [0.0; 2]),
            simulate_at(&c, &FootprintParams { uniform: false, ..p.clone() }, &anim, 5, 10.0, [0.0; 2]),
        );
        assert_eq!(a.center, b.center);
        assert_ne!(a.center, f.center);
    }

    #[test]
    fn bend_moves_the_band_by_at_most_bend_km() {
        // With no flow the band stays straight; the bend shifts each column's
        // centre of mass by |bend| <= bend_km (noise in [-1, 1]).
        let c = Curtain { bend_km: 8.0, ..Curtain::default() };
        let p = FootprintParams { steps: 0, velocity_amplitude: 0.0, ..small_params() };
        let f = simulate(&c, &p, 1);
        let (_, dv) = f.cell_size();
        let mut moved = 0.0f64;
        for i in 0..f.nx {
            let (mut m, mut s) = (0.0, 0.0);
            for j in 0..f.ny {
                let d = f.cell(i, j) as f64;
                m += d * (-0.5 * f.width + (j as f64 + 0.5) * dv);
                s += d;
            }
            let centre = m / s;
            // One cell of slack for the band's discretisation.
            assert!(centre.abs() <= 8.0 + dv, "column {i}: {centre}");
            moved = moved.max(centre.abs());
        }
        assert!(moved > 1.0, "the band should bend, moved {moved}");
    }

    fn still() -> AnimationParams {
        AnimationParams {
            fold_speed_kms: 0.0,
            fold_breathing: 0.0,
            bend_speed_kms: 0.0,
            bend_change_hz: 0.0,
            drift_km: 0.0,
            ray_speed_kms: 0.0,
            pulsation: 0.0,
            ..AnimationParams::default()
        }
    }

    #[test]
    fn motion_is_closed_form_continuous_and_off_at_zero() {
        let c = Curtain { rotation_deg: 20.0, ..Curtain::default() };
        let p = small_params();
        let anim = AnimationParams::default();
        // t = 0 is the still, whatever the motion.
        assert_eq!(simulate_at(&c, &p, &anim, 7, 0.0, [0.0; 2]), simulate(&c, &p, 7));
        // No motion: every time gives the same footprint.
        assert_eq!(simulate_at(&c, &p, &still(), 7, 37.5, [0.0; 2]), simulate(&c, &p, 7));
        // Motion: a frame apart (1/24 s) the footprint changes by a little,
        // 10 s apart by much more (L1 per cell, density peak 1).
        let l1 =
            |a: &Footprint, b: &Footprint| a.data.iter().zip(&b.data).map(|(x, y)| (x - y).abs() as f64).sum::<f64>() / a.data.len() as f64;
        // Continuity: a tenth of the time step gives well under half the
        // change (a jump would give the same change for any step; a smooth
        // motion a tenth of it).
        let f0 = simulate_at(&c, &p, &anim, 7, 100.0, [0.0; 2]);
        let f1 = simulate_at(&c, &p, &anim, 7, 100.0 + 1.0 / 24.0, [0.0; 2]);
        let f_tenth = simulate_at(&c, &p, &anim, 7, 100.0 + 1.0 / 240.0, [0.0; 2]);
        let f2 = simulate_at(&c, &p, &anim, 7, 110.0, [0.0; 2]);
        let (near, tenth, far) = (l1(&f0, &f1), l1(&f0, &f_tenth), l1(&f0, &f2));
        assert!(near > 0.0 && tenth < 0.3 * near && far > 3.0 * near, "1/240 s {tenth}, 1/24 s {near}, 10 s {far}");
        // The drift is bounded by drift_km, across the axis.
        for k in 0..50 {
            let f = simulate_at(&c, &p, &anim, 7, k as f64 * 17.0, [0.0; 2]);
            let d = (fmath::powi(f.center[0] - c.center[0], 2) + fmath::powi(f.center[1] - c.center[1], 2)).sqrt();
            assert!(d <= anim.drift_km + 1e-9);
        }
    }

    #[test]
    fn png_is_written_atomically_with_the_grid_size() {
        let f = simulate(&Curtain::default(), &small_params(), 5);
        let dir = std::env::temp_dir().join(format!("aurora-fp-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("fp.png");
        f.write_png(&path).unwrap();
        let decoder = png::Decoder::new(std::fs::File::open(&path).unwrap());
        let reader = decoder.read_info().unwrap();
        assert_eq!((reader.info().width, reader.info().height), (f.nx as u32, f.ny as u32));
        assert!(!dir.join(".fp.png.tmp").exists());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
