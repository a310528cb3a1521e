//! The velocity grid `v` (`grid.velocity`): how fast the emission pattern
//! moves, km/s, on the emission's active voxels, for motion blur (Cycles
//! advects its volume lookups along a velocity grid; `aurora render` does
//! the same with `render.shutter_s`).
//!
//! Model. Every motion is closed form in t (`crate::pipeline::motion`), so
//! the velocity is a central difference of positions at `t - dt` and
//! `t + dt` ([`DT_FRAMES`] of a frame each way), never a difference of two
//! bakes. Beam i keeps its identity across time: its start is the same
//! point of the unit square mapped through the footprint of each time
//! ([`crate::pipeline::beams::starts::StartMap`]), so its start velocity is
//! `(s(t + dt) - s(t - dt)) / 2 dt` (drift, travelling folds, bends: whatever
//! moves the footprint), and its whole walk down the field moves with its
//! start (the same random stream, the same deflections). On top of that the
//! rays (the start-height and colour noise along the curtain) run along it
//! at `animation.ray_speed_kms`: the pattern at curtain coordinate u moves
//! by `ray_speed_kms * d(world)/du` ([`beam_velocities`]). Pulsation changes
//! brightness, not place, and adds nothing.
//!
//! Per voxel the velocity is emission-weighted: each photon carries its
//! beam's velocity times its luminance, gathered with the emission's own
//! kernel ([`weighted_photons`]), and divided by the luminance of the
//! emission at that voxel ([`velocity_grid`]): the luminance-weighted mean
//! velocity of the light in the voxel. The red trail's photons (the O(1D)
//! glow of earlier times, `crate::pipeline::red_trail`) carry their beam's
//! velocity of the present: the trail is the past, drawn where the beam
//! was, and it moves with the pattern it trails. On a round Earth the start
//! velocities are taken in the footprint's plane (a few hundred km across,
//! the direction turns by under a degree).
//!
//! Units: km/s in the scene's frame (1 unit = 1 km). A voxel with no
//! emission (the Cycles shell's zeros) has velocity 0.

use crate::grid::{Grid, Leaf};
use crate::pipeline::beams::starts::{StartMap, UnitPoints};
use crate::pipeline::beams::{apportion, Traced};
use crate::pipeline::deposit::Photon;
use crate::pipeline::footprint::curtain_path::Lift;
use crate::pipeline::footprint::{self, Footprint};
use crate::pipeline::plan::BakePlan;
use crate::scene::{AnimationParams, BeamParams, Curtain, EarthParams, FootprintParams};
use crate::util::colour::luminance;
use crate::util::rng;
use rayon::prelude::*;

/// The central difference's half step, in frames (`dt = DT_FRAMES / fps`):
/// half a frame each way spans the frame the velocity blurs.
pub const DT_FRAMES: f64 = 0.5;

/// The central difference's half step of `animation`, s.
pub fn dt_s(animation: &AnimationParams) -> f64 {
    DT_FRAMES / animation.fps
}

/// The name of the velocity grid in the files (Blender's and Houdini's).
pub const GRID_NAME: &str = "v";

/// What [`beam_velocities`] reads of a bake, as plain data: the scene's
/// seed, curtains and sections, and the footprints of the bake's time.
#[derive(Clone, Debug)]
pub struct Motion<'a> {
    pub seed: u64,
    pub curtains: &'a [Curtain],
    pub footprint: &'a FootprintParams,
    pub animation: &'a AnimationParams,
    pub beams: &'a BeamParams,
    pub earth: &'a EarthParams,
    /// How a path is lifted to the start altitude (`Lift::of_scene`).
    pub lift: Lift,
    /// One footprint per curtain at `animation.time_s`.
    pub now: &'a [Footprint],
}

impl<'a> Motion<'a> {
    /// What the velocity grid reads of a plan.
    pub fn of(plan: &'a BakePlan) -> Self {
        let s = &plan.scene;
        Motion {
            seed: s.seed,
            curtains: &s.curtains,
            footprint: &s.footprint,
            animation: &s.animation,
            beams: &s.beams,
            earth: &s.earth,
            lift: Lift::of_scene(s),
            now: &plan.footprints,
        }
    }
}

/// The velocity of each of the `count` beams of a bake, km/s, in bake order
/// (curtain by curtain, as `crate::pipeline::beams::trace_range` numbers
/// them, streams from 0): the start's central difference through the
/// footprints of `t - dt` and `t + dt`, plus the rays' run along the
/// curtain at `t`.
pub fn beam_velocities(m: &Motion, count: usize) -> Vec<[f32; 3]> {
    let dt = dt_s(m.animation);
    let lift = &m.lift;
    let at = |t: f64| -> Vec<Footprint> {
        let anim = AnimationParams { time_s: t, ..m.animation.clone() };
        m.curtains.par_iter().map(|c| footprint::simulate_at(c, m.footprint, &anim, m.seed, t, lift)).collect()
    };
    let (before, after) = rayon::join(|| at(m.animation.time_s - dt), || at(m.animation.time_s + dt));
    let weights: Vec<f64> = m.curtains.iter().map(|c| c.beam_weight).collect();
    let counts = apportion(count, &weights);
    let mut out = Vec::with_capacity(count);
    for (ci, curtain) in m.curtains.iter().enumerate() {
        let n = counts[ci];
        let fps = [&before[ci], &m.now[ci], &after[ci]];
        let maps = fps.map(|f| StartMap::new(f, m.footprint.threshold));
        let points = UnitPoints::new(m.beams.starts, [m.seed, curtain.seed, rng::tag::BEAM_STARTS]);
        // The sheet's rays are in its footprint (their brightness runs
        // along it: `footprint::sheet`), so the start map's motion carries
        // them; the 2014 fluid's rays are the start-height and colour noise,
        // added here.
        let ray = match m.footprint.model {
            crate::scene::FootprintModel::Sheet => 0.0,
            crate::scene::FootprintModel::Fluid2014 => m.animation.ray_speed_kms,
        };
        let beams: Vec<[f32; 3]> = (0..n)
            .into_par_iter()
            .map(|i| {
                // The beam's own stream, as the trace draws it: its unit point first.
                let mut r = rng::rng(&[m.seed, curtain.seed, rng::tag::BEAM, i as u64]);
                let (xi1, xi2) = points.point(i as u64, &mut r);
                beam_velocity(&fps, &maps, (xi1, xi2), dt, ray)
            })
            .collect();
        out.extend(beams);
    }
    out
}

/// One beam's velocity, km/s: `fps`/`maps` the footprints and start maps at
/// `t - dt`, `t`, `t + dt` (an empty map, a footprint gone below threshold,
/// contributes no start motion), `xi` its unit-square point, `ray` the
/// rays' speed along the curtain.
fn beam_velocity(fps: &[&Footprint; 3], maps: &[StartMap; 3], xi: (f64, f64), dt: f64, ray: f64) -> [f32; 3] {
    let world = |k: usize| {
        let (u, v) = maps[k].map(xi.0, xi.1);
        fps[k].to_world(u, v)
    };
    let mut vel = [0.0f64; 2];
    if !maps[0].is_empty() && !maps[2].is_empty() {
        let (a, b) = (world(0), world(2));
        vel = [(b.0 - a.0) / (2.0 * dt), (b.1 - a.1) / (2.0 * dt)];
    }
    if ray != 0.0 && !maps[1].is_empty() {
        // The noise read at u - ray t: the pattern runs towards +u at `ray`.
        let (u, v) = maps[1].map(xi.0, xi.1);
        let h = 0.05;
        let (p, q) = (fps[1].to_world(u + h, v), fps[1].to_world(u - h, v));
        vel[0] += ray * (p.0 - q.0) / (2.0 * h);
        vel[1] += ray * (p.1 - q.1) / (2.0 * h);
    }
    [vel[0] as f32, vel[1] as f32, 0.0]
}

/// The photons of `traced` carrying their beam's velocity times their
/// luminance (`velocities` per beam of one pass; a trail's later passes
/// repeat the beams in the same order): gathered with the emission's
/// kernel, the numerator of [`velocity_grid`].
pub fn weighted_photons(traced: &Traced, velocities: &[[f32; 3]]) -> Vec<Photon> {
    let mut weighted: Vec<Photon> = Vec::with_capacity(traced.photons.len());
    let mut first = 0usize;
    for (k, &n) in traced.beam_photons.iter().enumerate() {
        let v = velocities[k % velocities.len().max(1)];
        for p in &traced.photons[first..first + n as usize] {
            let y = luminance(p.power.map(|c| c as f64)) as f32;
            weighted.push(Photon { power: v.map(|c| c * y), ..*p });
        }
        first += n as usize;
    }
    debug_assert_eq!(first, traced.photons.len());
    weighted
}

/// The velocity grid `v` on `emission`'s active voxels, km/s: the
/// numerator's value (the gather of [`weighted_photons`]) over the emission's luminance
/// there (0 where the luminance is not positive).
pub fn velocity_grid(emission: &Grid<[f32; 3]>, numerator: &Grid<[f32; 3]>) -> Grid<[f32; 3]> {
    let leaves: Vec<Leaf<[f32; 3]>> = emission
        .leaves()
        .par_iter()
        .map(|l| {
            let mut out = Leaf::new(l.origin, [0.0f32; 3]);
            out.mask = l.mask;
            let num = numerator.leaf(l.origin);
            for n in 0..l.values.len() {
                if !l.is_active(n) {
                    continue;
                }
                let e = l.values[n];
                let y = luminance(e.map(|c| c as f64));
                if let (Some(num), true) = (num, y > 0.0) {
                    if num.is_active(n) {
                        out.values[n] = num.values[n].map(|c| (c as f64 / y) as f32);
                    }
                }
            }
            out
        })
        .collect();
    Grid::from_leaves(GRID_NAME, [0.0f32; 3], emission.transform, leaves)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::Transform;
    use glam::{DVec3, IVec3};

    #[test]
    fn the_grid_is_the_numerator_over_the_luminance_on_the_emission_voxels() {
        let tr = Transform::new(0.5, DVec3::ZERO);
        let mut e = Grid::new("emission", [0.0f32; 3], tr);
        let mut num = Grid::new("n", [0.0f32; 3], tr);
        e.set(IVec3::new(1, 2, 3), [0.0, 2.0, 0.0]);
        e.set(IVec3::new(9, 2, 3), [0.0, 1.0, 0.0]);
        let y = luminance([0.0, 2.0, 0.0]) as f32;
        num.set(IVec3::new(1, 2, 3), [3.0 * y, -y, 0.0]);
        num.set(IVec3::new(40, 2, 3), [1.0, 1.0, 1.0]);
        let v = velocity_grid(&e, &num);
        assert_eq!(v.name, "v");
        assert_eq!(v.active_voxel_count(), 2);
        let got = v.get(IVec3::new(1, 2, 3));
        assert!((got[0] - 3.0).abs() < 1e-6 && (got[1] + 1.0).abs() < 1e-6 && got[2] == 0.0, "{got:?}");
        // No numerator there: at rest.
        assert_eq!(v.get(IVec3::new(9, 2, 3)), [0.0; 3]);
        assert!(!v.is_active(IVec3::new(40, 2, 3)));
    }
}
