//! The beam count from a target noise level (`beams.target_noise`).
//!
//! The emission grid is a sum over independent, identically distributed
//! beams, each carrying `1/N` of the curtain's power: its expectation does
//! not depend on `N` and its variance is `sigma^2 / N` in every voxel. So
//! the relative RMS noise of the grid,
//!
//! `noise(N) = sqrt(sum_v Var[e_v]) / sqrt(sum_v E[e_v]^2)`
//!
//! (sums over voxels and the three colour components, the bench's
//! photon-count metric against a converged reference), falls exactly as
//! `N^-1/2`, and one measurement at a small `m` gives every other:
//! `N = m (noise(m) / target)^2`.
//!
//! [`beams_for_noise`] measures `noise(m)` by splitting a pilot into two
//! independent halves `a` and `b` of `m` beams each (disjoint random
//! streams, [`crate::beams::trace_all_from`]), gathered on the bake's own
//! grid: `E[(a - b)^2] = 2 Var`, and `E[((a + b)/2)^2] = E^2 + Var / 2`, so
//!
//! `noise(m)^2 = (sum (a - b)^2 / 2) / (sum ((a + b)/2)^2 - sum (a - b)^2 / 4)`.
//!
//! This measures noise only: the kernel's bias (blur), which more beams do
//! not change, is not part of it. The pilot costs about `2m` beams of
//! tracing and gathering; the count is capped at `beams.count`.

use crate::atmosphere::Atmosphere;
use crate::bake::{self, BakeError};
use crate::beams;
use crate::footprint::Footprint;
use crate::grid::{Grid, Transform};
use crate::photons::{self, RadiusField};
use crate::progress::NoProgress;
use crate::scene::Scene;
use crate::spectrum::ColourTable;
use glam::DVec3;
use serde::Serialize;

/// Beams in each half of the pilot: about 6 % of the default scene's
/// tracing and gathering, and enough that the noise estimate itself is
/// within a few percent (the sums run over millions of voxel values).
pub const PILOT_HALF_BEAMS: usize = 500;

/// Beam-stream index where the pilot's second half starts: far beyond any
/// beam count the scene accepts (10^8), so the halves never share a stream.
pub const SECOND_HALF_OFFSET: u64 = 1 << 40;

/// What the pilot measured and chose.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct NoiseEstimate {
    /// `beams.target_noise`.
    pub target: f64,
    /// Beams per pilot half, `m`.
    pub pilot_beams: usize,
    /// Relative RMS noise of an `m`-beam grid, measured.
    pub pilot_noise: f64,
    /// `m (pilot_noise / target)^2`.
    pub beams_needed: f64,
    /// The count used: `beams_needed` rounded up, at most `beams.count`.
    pub beams: usize,
    /// The noise expected at `beams`: `pilot_noise sqrt(m / beams)`.
    pub expected_noise: f64,
    /// `beams.count` capped the count.
    pub capped: bool,
    pub seconds: f64,
}

/// `noise(m)^2` from two independent grids of `m` beams each (see the
/// module documentation), over the union of their active voxels.
pub fn split_noise(a: &Grid<[f32; 3]>, b: &Grid<[f32; 3]>) -> f64 {
    let (mut diff2, mut mean2) = (0.0f64, 0.0f64);
    let mut add = |x: [f32; 3], y: [f32; 3]| {
        for k in 0..3 {
            let (x, y) = (x[k] as f64, y[k] as f64);
            diff2 += (x - y) * (x - y);
            mean2 += 0.25 * (x + y) * (x + y);
        }
    };
    for (ijk, x) in a.iter_active() {
        add(x, b.get(ijk));
    }
    for (ijk, y) in b.iter_active() {
        if !a.is_active(ijk) {
            add([0.0; 3], y);
        }
    }
    let signal = mean2 - 0.25 * diff2;
    if signal <= 0.0 {
        return f64::INFINITY;
    }
    0.5 * diff2 / signal
}

/// Measures the scene's noise with a pilot of `2 m` beams
/// ([`PILOT_HALF_BEAMS`]) and picks the beam count for `target` relative
/// RMS noise, at most `scene.beams.count`.
pub fn beams_for_noise(
    scene: &Scene,
    footprints: &[Footprint],
    atmosphere: &Atmosphere,
    colour: &ColourTable,
    target: f64,
) -> Result<NoiseEstimate, BakeError> {
    let t = std::time::Instant::now();
    let m = PILOT_HALF_BEAMS;
    let mut pilot = scene.clone();
    pilot.beams.count = m;
    let (pa, _) = beams::trace_all_from(&pilot, footprints, atmosphere, colour, 0, &NoProgress)?;
    let (pb, _) = beams::trace_all_from(&pilot, footprints, atmosphere, colour, SECOND_HALF_OFFSET, &NoProgress)?;
    // The bake's own grid ("auto" resolved on the pilot's photons, which
    // sample the same distribution as the bake's).
    let (vs, _) = bake::voxel_size(scene, &pa);
    let transform = Transform::new(vs, DVec3::ZERO);
    let radius = RadiusField::from_scene(scene);
    let p = &scene.photons;
    let ga = photons::gather_grid(&pa, transform, &radius, p.cutoff, p.gather, &NoProgress);
    let gb = photons::gather_grid(&pb, transform, &radius, p.cutoff, p.gather, &NoProgress);
    let pilot_noise = split_noise(&ga, &gb).sqrt();
    let beams_needed = m as f64 * (pilot_noise / target).powi(2);
    let cap = scene.beams.count;
    let capped = !(beams_needed <= cap as f64);
    let beams = if capped { cap } else { (beams_needed.ceil() as usize).max(1) };
    Ok(NoiseEstimate {
        target,
        pilot_beams: m,
        pilot_noise,
        beams_needed,
        beams,
        expected_noise: pilot_noise * (m as f64 / beams as f64).sqrt(),
        capped,
        seconds: t.elapsed().as_secs_f64(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::Transform;
    use glam::IVec3;

    #[test]
    fn split_noise_recovers_a_known_variance() {
        // Two grids of 20000 voxels: mean mu = 2 everywhere plus independent
        // Gaussian noise of sd 0.5 per component. noise^2 = 0.25 / 4 = 1/16
        // exactly in expectation; the estimate's relative sd is about
        // sqrt(2 / 60000) = 0.6 %: 5 % is more than 8 sd.
        use rand::Rng;
        let mut r = crate::rng::rng(&[3]);
        let mut gauss = || {
            // Box-Muller.
            let (u, v): (f64, f64) = (r.random::<f64>().max(1e-300), r.random());
            (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
        };
        let tr = Transform::new(1.0, DVec3::ZERO);
        let (mut a, mut b) = (Grid::new("e", [0.0f32; 3], tr), Grid::new("e", [0.0f32; 3], tr));
        for i in 0..20000 {
            let ijk = IVec3::new(i % 100, i / 100, 0);
            let mut v = || std::array::from_fn(|_| (2.0 + 0.5 * gauss()) as f32);
            a.set(ijk, v());
            b.set(ijk, v());
        }
        let n2 = split_noise(&a, &b);
        assert!((n2 / (1.0 / 16.0) - 1.0).abs() < 0.05, "{n2}");
        // Identical grids: no noise.
        assert_eq!(split_noise(&a, &a), 0.0);
    }

    /// One short curtain, coarse voxels: a scene that bakes in a second.
    fn small_scene() -> Scene {
        let mut s = Scene {
            curtains: vec![crate::scene::Curtain { length: 40.0, width: 16.0, bend_km: 3.0, ..Default::default() }],
            ..Scene::default()
        };
        s.footprint.resolution = [128, 48];
        s.beams.count = 100_000;
        s.photons.radius_km = 1.0;
        s.grid.voxel_size = crate::scene::VoxelSize::Km(1.0);
        s.grid.prune = 0.0;
        s
    }

    #[test]
    fn the_chosen_count_reaches_the_target_noise() {
        // End to end: pick N for a target from the pilot, then measure the
        // noise of two independent N-beam grids (streams 0.. and 2^40..,
        // neither the pilot's second half) with the same split estimator.
        // The law N^-1/2 is exact in expectation; what is left is the
        // sampling error of the two estimates (a few percent each, from the
        // heavy tail of per-voxel contributions): 15 % on the noise.
        let s = small_scene();
        let fps = bake::footprints(&s);
        let atm = Atmosphere::us1976();
        let colour = bake::colour_table(&s, &atm);
        let target = 0.18;
        let est = beams_for_noise(&s, &fps, &atm, &colour, target).unwrap();
        assert!(!est.capped && est.beams > 4 * PILOT_HALF_BEAMS, "{est:?}");
        let mut sn = s.clone();
        sn.beams.count = est.beams;
        let grid = |first: u64| {
            let (ph, _) = beams::trace_all_from(&sn, &fps, &atm, &colour, first, &NoProgress).unwrap();
            let tr = Transform::new(1.0, DVec3::ZERO);
            let p = &s.photons;
            photons::gather_grid(&ph, tr, &RadiusField::from_scene(&s), p.cutoff, p.gather, &NoProgress)
        };
        let measured = split_noise(&grid(1 << 20), &grid(3 << 40)).sqrt();
        eprintln!("target {target}: measured {measured}, {est:?}");
        assert!((measured / target - 1.0).abs() < 0.15, "measured {measured} for target {target}: {est:?}");
        // A cap below the need is reported, and honoured.
        let mut capped = s.clone();
        capped.beams.count = est.beams / 4;
        let e2 = beams_for_noise(&capped, &fps, &atm, &colour, target).unwrap();
        assert!(e2.capped && e2.beams == est.beams / 4);
        assert!((e2.expected_noise / (2.0 * target) - 1.0).abs() < 0.01, "{e2:?}");
    }
}
