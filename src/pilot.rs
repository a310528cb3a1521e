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
//! **Stratified starts** (`beams.starts = "stratified"`, [`crate::starts`])
//! break the exact law: beams are still independent in their energies and
//! deflections, but their starts are a low-discrepancy set, whose share of
//! the variance falls faster than `1/N` (as `1/N^2` for smooth flux maps, up
//! to logarithms). Measured on the test's small scene, each pilot block with
//! its own Cranley-Patterson shift (`crate::starts`; with one shared shift
//! the halves are correlated and the split estimate is off by 15 %):
//! `noise(62) / noise(250) = 1.87`, `noise(250) / noise(1000) = 2.12`
//! (random starts: 1.83 for the latter; 4x the beams should give 2, the
//! estimates' own error is some 10 %). The start share is small on this
//! scene, but the pilot does not assume it: it fits
//!
//! `noise(N)^2 = a / N + b / N^2`
//!
//! to two measurements, `m` and `m / 4` beams per half (the quarter pair on
//! its own disjoint streams): with `v_i = noise(m_i)^2`,
//! `b = (m_1 v_1 - m_2 v_2) / (1/m_1 - 1/m_2)` and `a = m_2 v_2 - b / m_2`;
//! then `N = (a + sqrt(a^2 + 4 t^2 b)) / (2 t^2)` for target t. A negative
//! `b` (sampling error, or random starts, where b = 0 in expectation) is set
//! to 0, which is the plain law `N = m (noise(m) / t)^2`, exact for random
//! starts.
//!
//! This measures noise only: the kernel's bias (blur), which more beams do
//! not change, is not part of it. The pilot costs about `2.5 m` beams of
//! tracing and gathering; the count is capped at `beams.count`.

pub use crate::pipeline::NoiseEstimate;
use crate::grid::Grid;
use crate::pipeline::{self, BakeError, BakePlan};
use crate::progress::NoProgress;

/// Beams in each half of the pilot: about 6 % of the default scene's
/// tracing and gathering, and enough that the noise estimate itself is
/// within a few percent (the sums run over millions of voxel values).
pub const PILOT_HALF_BEAMS: usize = 500;

/// Beam-stream index where the pilot's second half starts: far beyond any
/// beam count the scene accepts (10^8), so the halves never share a stream.
pub const SECOND_HALF_OFFSET: u64 = 1 << 40;

/// Beam-stream indices of the quarter-size pair: beyond both halves.
pub const QUARTER_OFFSETS: [u64; 2] = [2 << 40, 3 << 40];

/// `a` and `b` of `noise(N)^2 = a / N + b / N^2` from `noise(m1)` and
/// `noise(m2)` (see the module documentation); b >= 0.
pub fn fit_law(m1: f64, n1: f64, m2: f64, n2: f64) -> (f64, f64) {
    let (v1, v2) = (n1 * n1, n2 * n2);
    let b = ((m1 * v1 - m2 * v2) / (1.0 / m1 - 1.0 / m2)).max(0.0);
    let a = m2 * v2 - b / m2;
    if a <= 0.0 {
        // The fast-falling share would be all the noise: keep the plain law
        // (more beams, never fewer).
        return (m2 * v2, 0.0);
    }
    (a, b)
}

/// The beam count N with `a / N + b / N^2 = target^2`.
pub fn beams_for_law(a: f64, b: f64, target: f64) -> f64 {
    let t2 = target * target;
    (a + (a * a + 4.0 * t2 * b).sqrt()) / (2.0 * t2)
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

/// Measures the plan's noise with a pilot of `2 m` beams
/// ([`PILOT_HALF_BEAMS`]) and picks the beam count for `target` relative
/// RMS noise, at most the plan's `beams.count`. Traces and gathers through
/// the plan ([`pipeline::trace`], [`pipeline::gather`]); the count is an
/// argument, the scene is never copied.
pub fn beams_for_noise(plan: &BakePlan, target: f64) -> Result<NoiseEstimate, BakeError> {
    let t = std::time::Instant::now();
    let m = PILOT_HALF_BEAMS;
    let pa = pipeline::trace(plan, m, 0, 0..m, &NoProgress)?.photons;
    let pb = pipeline::trace(plan, m, SECOND_HALF_OFFSET, 0..m, &NoProgress)?.photons;
    // The bake's own grid ("auto" resolved on the pilot's photons, which
    // sample the same distribution as the bake's).
    let (vs, _) = plan.voxel_size(&pa);
    let grid = |photons: &[crate::beams::Photon]| pipeline::gather(plan, photons, vs, &NoProgress);
    let pilot_noise = split_noise(&grid(&pa), &grid(&pb)).sqrt();
    let q = m / 4;
    let qa = pipeline::trace(plan, q, QUARTER_OFFSETS[0], 0..q, &NoProgress)?.photons;
    let qb = pipeline::trace(plan, q, QUARTER_OFFSETS[1], 0..q, &NoProgress)?.photons;
    let quarter_noise = split_noise(&grid(&qa), &grid(&qb)).sqrt();
    let (law_a, law_b) = fit_law(q as f64, quarter_noise, m as f64, pilot_noise);
    let beams_needed = beams_for_law(law_a, law_b, target);
    let cap = plan.beams.count;
    let capped = !(beams_needed <= cap as f64);
    let beams = if capped { cap } else { (beams_needed.ceil() as usize).max(1) };
    Ok(NoiseEstimate {
        target,
        pilot_beams: m,
        pilot_noise,
        quarter_noise,
        law_a,
        law_b,
        beams_needed,
        beams,
        expected_noise: (law_a / beams as f64 + law_b / (beams as f64).powi(2)).sqrt(),
        capped,
        seconds: t.elapsed().as_secs_f64(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::Transform;
    use crate::scene::Scene;
    use glam::{DVec3, IVec3};

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
        // The atmosphere these tests were calibrated with.
        s.atmosphere.model = crate::scene::AtmosphereModel::Us1976;
        s
    }

    /// `noise(m)` of the plan measured by the split estimator.
    fn split_noise_at(plan: &BakePlan, m: usize) -> f64 {
        let grid = |first: u64| {
            let ph = pipeline::trace(plan, m, first, 0..m, &NoProgress).unwrap().photons;
            pipeline::gather(plan, &ph, 1.0, &NoProgress)
        };
        split_noise(&grid(0), &grid(SECOND_HALF_OFFSET)).sqrt()
    }

    #[test]
    fn the_noise_law_with_and_without_stratified_starts() {
        // Random starts: every beam independent, noise(250) / noise(1000) =
        // 2 (N^-1/2) within the estimates' sampling error (a few percent
        // each: 10 % on the ratio). Stratified starts: steeper (the starts'
        // share falls faster), so the fitted law a / N + b / N^2 from 62 and
        // 250 beams must predict noise(1000) better than the plain law from
        // 250. With expected deposition and the continuous start map the
        // noise falls faster still between 250 and 1000 beams (measured:
        // fitted 0.132, plain 0.153, measured 0.102): the fit errs high, so a
        // pilot using it picks more beams than needed, never fewer (the
        // end-to-end test below holds the chosen count to 15 %); 35 % here.
        let s = small_scene();
        let plan = BakePlan::new(&s, &NoProgress);
        let mut sr = s.clone();
        sr.beams.starts = crate::scene::BeamStarts::Random;
        let pr = BakePlan::reusing(&sr, &plan, &NoProgress);
        let (a, b) = (split_noise_at(&pr, 250), split_noise_at(&pr, 1000));
        eprintln!("random: noise(250) {a:.4}, noise(1000) {b:.4}, ratio {:.3}", a / b);
        assert!((a / b - 2.0).abs() < 0.2, "random: noise(250) / noise(1000) = {}", a / b);
        let (n62, n250, n1000) = (
            split_noise_at(&plan, 62),
            split_noise_at(&plan, 250),
            split_noise_at(&plan, 1000),
        );
        let (la, lb) = fit_law(62.0, n62, 250.0, n250);
        let fitted = (la / 1000.0 + lb / 1e6).sqrt();
        let plain = n250 * 0.5;
        eprintln!("stratified: noise(62) {n62:.4} (250) {n250:.4} (1000) {n1000:.4}; predicted: fitted {fitted:.4}, plain {plain:.4}");
        assert!(n250 / n1000 > 2.0, "stratified starts should fall faster than N^-1/2");
        assert!((fitted / n1000 - 1.0).abs() < 0.35 && fitted >= n1000, "fitted {fitted} vs measured {n1000}");
        assert!((fitted / n1000 - 1.0).abs() <= (plain / n1000 - 1.0).abs());
    }

    #[test]
    fn law_fit_recovers_its_coefficients() {
        let (a, b) = (3.0, 400.0);
        let v = |m: f64| (a / m + b / (m * m)).sqrt();
        let (fa, fb) = fit_law(125.0, v(125.0), 500.0, v(500.0));
        assert!((fa / a - 1.0).abs() < 1e-12 && (fb / b - 1.0).abs() < 1e-12);
        let n = beams_for_law(fa, fb, 0.05);
        assert!((v(n) / 0.05 - 1.0).abs() < 1e-12);
        // b = 0: the plain law.
        let (pa, pb) = fit_law(125.0, 0.4, 500.0, 0.2);
        assert_eq!(pb, 0.0);
        assert!((beams_for_law(pa, pb, 0.1) - 500.0 * 4.0).abs() < 1e-9);
    }

    #[test]
    fn the_chosen_count_reaches_the_target_noise() {
        // End to end: pick N for a target from the pilot, then measure the
        // noise of two independent N-beam grids (streams 0.. and 2^40..,
        // neither the pilot's second half) with the same split estimator.
        // The law N^-1/2 is exact in expectation; what is left is the
        // sampling error of the two estimates (a few percent each, from the
        // heavy tail of per-voxel contributions): 15 % on the noise. Target
        // 0.05: expected deposition with stratified starts reaches 0.1 with
        // about 1100 beams, not enough above the pilot's own 500 to test.
        let s = small_scene();
        let plan = BakePlan::new(&s, &NoProgress);
        let target = 0.05;
        let est = beams_for_noise(&plan, target).unwrap();
        assert!(!est.capped && est.beams > 4 * PILOT_HALF_BEAMS, "{est:?}");
        let n = est.beams;
        let grid = |first: u64| {
            let ph = pipeline::trace(&plan, n, first, 0..n, &NoProgress).unwrap().photons;
            pipeline::gather(&plan, &ph, 1.0, &NoProgress)
        };
        let measured = split_noise(&grid(1 << 20), &grid(3 << 40)).sqrt();
        eprintln!("target {target}: measured {measured}, {est:?}");
        assert!((measured / target - 1.0).abs() < 0.15, "measured {measured} for target {target}: {est:?}");
        // A cap below the need is reported, and honoured.
        let mut capped = s.clone();
        capped.beams.count = est.beams / 4;
        let e2 = beams_for_noise(&BakePlan::reusing(&capped, &plan, &NoProgress), target).unwrap();
        assert!(e2.capped && e2.beams == est.beams / 4);
        let want = (e2.law_a / e2.beams as f64 + e2.law_b / (e2.beams as f64).powi(2)).sqrt();
        assert!((e2.expected_noise / want - 1.0).abs() < 1e-12, "{e2:?}");
    }
}
