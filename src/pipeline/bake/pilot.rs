//! The beam count from a target noise level (`beams.target_noise`).
//!
//! The emission grid is a sum over independent, identically distributed
//! beams, each carrying `1/N` of the curtain's power, so its expectation does
//! not depend on `N` and its variance is `sigma^2 / N` in every voxel. The
//! relative RMS noise of the grid (sums over voxels and the three colour
//! components, the bench's photon-count metric against a converged reference),
//!
//! `noise(N) = sqrt(sum_v Var[e_v]) / sqrt(sum_v E[e_v]^2)`,
//!
//! falls as `N^-1/2`, and one measurement gives every other:
//! `N = m (noise(m) / target)^2`.
//!
//! [`beams_for_noise`] measures `noise(m)` by splitting a pilot into two
//! independent halves `a` and `b` of `m` beams each (disjoint random streams,
//! [`crate::pipeline::beams::trace_all_from`]) gathered on the bake's own
//! grid: `E[(a - b)^2] = 2 Var` and `E[((a + b)/2)^2] = E^2 + Var / 2`, so
//!
//! `noise(m)^2 = (sum (a - b)^2 / 2) / (sum ((a + b)/2)^2 - sum (a - b)^2 / 4)`.
//!
//! **Stratified starts** (`beams.starts = "stratified"`,
//! [`crate::pipeline::beams::starts`]) fall faster: for an integrand with
//! edges the starts' variance falls as `N^-3/2` (Mitchell 1996, "Consequences
//! of stratified sampling in graphics"; Pharr, Jakob & Humphreys, PBRT 4th
//! ed., section 8.2). Each pilot block has its own Cranley-Patterson shift
//! (a shared one would correlate the halves). The pilot fits
//! `noise(N)^2 = a / N + b / N^(3/2)` to `m` and `m / 4` beams per half (the
//! quarter pair on its own streams): with `v_i = noise(m_i)^2`,
//! `b = (m_1 v_1 - m_2 v_2) / (m_1^-1/2 - m_2^-1/2)`, `a = m_2 v_2 - b
//! m_2^-1/2`; N solves `a x^2 + b x^3 = t^2` for `x = N^-1/2` (one positive
//! root; bisection). A negative `b` is set to 0 (the plain law, exact for
//! random starts), a negative `a` to 0 (the start law alone).
//!
//! This measures noise only, not the kernel's bias (blur), which more beams
//! do not change. The pilot costs about `2.5 m` beams of tracing and
//! gathering; the count is capped at `beams.count`. Derivation and how well
//! the law predicts: docs/physics.md, "The noise target".
//!
//! **The deposition pilot** ([`check_deposition`], before every bake)
//! traces [`DEPOSIT_PILOT_BEAMS`] beams (at most `beams.count`) of each curtain on streams of their
//! own and refuses a curtain whose beams deposit under
//! [`crate::pipeline::beams::MIN_DEPOSITED_FRACTION`] of the power they
//! carry into the atmosphere (a field so shallow that they leave their
//! footprint sideways; Fang's depositions only, csda's beams stop by its own
//! rules): the fraction's sampling error at 256 beams is at most
//! `sqrt(1/4 / 256)` = 3 %.

use super::result::BakeError;
use super::stats::NoiseEstimate;
use crate::grid::Grid;
use crate::pipeline::beams::{self, dip::curtain_dip, BeamError, TraceParams, MIN_DEPOSITED_FRACTION};
use crate::pipeline::plan::{BakePlan, DEPOSIT_PILOT_BEAMS, PILOT_HALF_BEAMS};
use crate::util::fmath;
use crate::util::progress::NoProgress;

/// Beam-stream index where the pilot's second half starts: far beyond any
/// beam count the scene accepts (10^8), so the halves never share a stream.
pub const SECOND_HALF_OFFSET: u64 = 1 << 40;

/// Beam-stream indices of the quarter-size pair: beyond both halves.
pub const QUARTER_OFFSETS: [u64; 2] = [2 << 40, 3 << 40];

/// Beam-stream index where the deposition pilot's beams start: beyond the
/// noise pilot's.
pub const DEPOSIT_PILOT_OFFSET: u64 = 4 << 40;

/// Traces [`DEPOSIT_PILOT_BEAMS`] beams (at most `beams.count`) of each curtain that has beams
/// (its own random streams from [`DEPOSIT_PILOT_OFFSET`], so the bake's
/// beams are untouched) and refuses the first whose deposited fraction is
/// under [`MIN_DEPOSITED_FRACTION`] ([`BeamError::LowDeposit`]); returns
/// the fractions, in curtain order (1 for a curtain without beams, and for
/// every curtain with csda, which is not refused).
pub fn check_deposition(plan: &BakePlan) -> Result<Vec<f64>, BakeError> {
    // Never more than the bake's own beams.
    let m = DEPOSIT_PILOT_BEAMS.min(plan.scene.beams.count);
    let mut fractions = Vec::with_capacity(plan.scene.curtains.len());
    for (i, c) in plan.scene.curtains.iter().enumerate() {
        // csda's beams stop by its own rules (after 1 / dt steps, off the
        // footprint): its losses are warned about, never refused.
        if !(c.beam_weight > 0.0) || plan.scene.beams.deposition == crate::scene::Deposition::Csda {
            fractions.push(1.0);
            continue;
        }
        let footprints = std::slice::from_ref(&plan.footprints[i]);
        let params = TraceParams { curtains: std::slice::from_ref(c), footprints, ..plan.trace_params() };
        let t = beams::trace_range(&params, m, DEPOSIT_PILOT_OFFSET, 0..m, false, &NoProgress).map_err(|e| match e {
            BeamError::EmptyFootprint { threshold, peak, .. } => BeamError::EmptyFootprint { curtain: i, threshold, peak },
            e => e,
        })?;
        let f = t.stats.curtains[0].deposited_fraction;
        if f < MIN_DEPOSITED_FRACTION {
            let st = &t.stats;
            return Err(BeamError::LowDeposit {
                curtain: i,
                beams: m,
                fraction: f,
                left: st.ended_left_footprint,
                bottom: st.ended_bottom,
                capped: st.ended_max_steps,
                dip_deg: curtain_dip(c, &plan.scene.beams, &plan.scene.earth, plan.site_field.as_ref()).dip_deg,
                alpha_d_deg: plan.scene.beams.alpha_d_deg,
            }
            .into());
        }
        fractions.push(f);
    }
    Ok(fractions)
}

/// `a` and `b` of `noise(N)^2 = a / N + b / N^(3/2)` from `noise(m1)` and
/// `noise(m2)` (see the module documentation); b >= 0.
pub fn fit_law(m1: f64, n1: f64, m2: f64, n2: f64) -> (f64, f64) {
    let (v1, v2) = (n1 * n1, n2 * n2);
    let b = ((m1 * v1 - m2 * v2) / (fmath::powf(m1, -0.5) - fmath::powf(m2, -0.5))).max(0.0);
    let a = m2 * v2 - b * fmath::powf(m2, -0.5);
    if a <= 0.0 {
        // The pair falls at least as fast as the starts' share alone (the
        // quarter estimate's sampling error, some 10 % at m / 4 = 125 beams,
        // can make it look faster): the start law alone through the larger
        // pilot, `a = 0`, `b = m_2^3/2 v_2`. (The plain law here asked for
        // twice the beams the target needed in the test below.)
        return (0.0, fmath::powf(m2, 1.5) * v2);
    }
    (a, b)
}

/// `noise(N)` by the fitted law.
pub fn law_noise(a: f64, b: f64, n: f64) -> f64 {
    (a / n + b * fmath::powf(n, -1.5)).sqrt()
}

/// The beam count N with `a / N + b / N^(3/2) = target^2`: bisection for x
/// = N^-1/2 on `a x^2 + b x^3 = t^2` (increasing in x), between 0 and the
/// smaller of the roots of either term alone; 200 halvings reach f64's
/// resolution.
pub fn beams_for_law(a: f64, b: f64, target: f64) -> f64 {
    let t2 = target * target;
    let f = |x: f64| a * x * x + b * x * x * x - t2;
    let mut hi = f64::INFINITY;
    if a > 0.0 {
        hi = hi.min((t2 / a).sqrt());
    }
    if b > 0.0 {
        hi = hi.min(fmath::cbrt(t2 / b));
    }
    if !hi.is_finite() {
        return 1.0;
    }
    let mut lo = 0.0;
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if f(mid) < 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    1.0 / (hi * hi)
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
/// the plan ([`crate::pipeline::bake::trace::trace`], [`crate::pipeline::bake::gather::gather`]); the count is an
/// argument, the scene is never copied.
pub fn beams_for_noise(plan: &BakePlan, target: f64) -> Result<NoiseEstimate, BakeError> {
    let t = std::time::Instant::now();
    let m = PILOT_HALF_BEAMS;
    let pa = crate::pipeline::bake::trace::trace(plan, m, 0, 0..m, &NoProgress)?.photons;
    let pb = crate::pipeline::bake::trace::trace(plan, m, SECOND_HALF_OFFSET, 0..m, &NoProgress)?.photons;
    // The bake's own grid ("auto" resolved on the pilot's photons, which
    // sample the same distribution as the bake's).
    let (vs, _) = plan.voxel_size(&pa);
    let grid = |photons: &[crate::pipeline::deposit::Photon]| crate::pipeline::bake::gather::gather(plan, photons, vs, &NoProgress);
    let pilot_noise = split_noise(&grid(&pa), &grid(&pb)).sqrt();
    let q = m / 4;
    let qa = crate::pipeline::bake::trace::trace(plan, q, QUARTER_OFFSETS[0], 0..q, &NoProgress)?.photons;
    let qb = crate::pipeline::bake::trace::trace(plan, q, QUARTER_OFFSETS[1], 0..q, &NoProgress)?.photons;
    let quarter_noise = split_noise(&grid(&qa), &grid(&qb)).sqrt();
    let (law_a, law_b) = fit_law(q as f64, quarter_noise, m as f64, pilot_noise);
    let beams_needed = beams_for_law(law_a, law_b, target);
    let cap = plan.scene.beams.count;
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
        expected_noise: law_noise(law_a, law_b, beams as f64),
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
        let mut r = crate::util::rng::rng(&[3]);
        let mut gauss = || {
            // Box-Muller.
            let (u, v): (f64, f64) = (r.random::<f64>().max(1e-300), r.random());
            (-2.0 * fmath::ln(u)).sqrt() * fmath::cos(std::f64::consts::TAU * v)
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
        let mut s = crate::scene::presets::small_test_scene();
        s.beams.count = 100_000;
        s.grid.prune = 0.0;
        // The atmosphere these tests were calibrated with.
        s.atmosphere.model = crate::scene::AtmosphereModel::Us1976;
        s
    }

    /// `noise(m)` of the plan measured by the split estimator.
    fn split_noise_at(plan: &BakePlan, m: usize) -> f64 {
        let grid = |first: u64| {
            let ph = crate::pipeline::bake::trace::trace(plan, m, first, 0..m, &NoProgress).unwrap().photons;
            crate::pipeline::bake::gather::gather(plan, &ph, 1.0, &NoProgress)
        };
        split_noise(&grid(0), &grid(SECOND_HALF_OFFSET)).sqrt()
    }

    #[test]
    fn the_noise_law_with_and_without_stratified_starts() {
        // Random starts: every beam independent, noise(250) / noise(1000) =
        // 2 (N^-1/2) within the estimates' sampling error (a few percent
        // each: 10 % on the ratio). Stratified starts: steeper (the starts'
        // share falls faster). The law a / N + b / N^(3/2) fitted to the
        // pilot's own pair (125 and 500 beams) predicts noise(2000), four
        // times beyond the pilot as a bake uses it, within 20 %: each of the
        // three split estimates has a few percent of sampling error (the
        // module documentation's means of three moved by up to 8 % between
        // single estimates), and the law itself was within 8 % of those
        // means from 1000 to 4000 beams. The plain law from 500 (0.076 vs
        // 0.059 measured) does worse.
        let s = small_scene();
        let plan = BakePlan::new(&s, &NoProgress);
        let mut sr = s.clone();
        sr.beams.starts = crate::scene::BeamStarts::Random;
        let pr = BakePlan::reusing(&sr, &plan, &NoProgress);
        let (a, b) = (split_noise_at(&pr, 250), split_noise_at(&pr, 1000));
        eprintln!("random: noise(250) {a:.4}, noise(1000) {b:.4}, ratio {:.3}", a / b);
        assert!((a / b - 2.0).abs() < 0.2, "random: noise(250) / noise(1000) = {}", a / b);
        let (n125, n500, n2000) = (split_noise_at(&plan, 125), split_noise_at(&plan, 500), split_noise_at(&plan, 2000));
        let (la, lb) = fit_law(125.0, n125, 500.0, n500);
        let fitted = law_noise(la, lb, 2000.0);
        let plain = n500 * 0.5;
        eprintln!("stratified: noise(125) {n125:.4} (500) {n500:.4} (2000) {n2000:.4}; predicted: fitted {fitted:.4}, plain {plain:.4}");
        assert!(n500 / n2000 > 2.0, "stratified starts should fall faster than N^-1/2");
        assert!((fitted / n2000 - 1.0).abs() < 0.2, "fitted {fitted} vs measured {n2000}");
        assert!((fitted / n2000 - 1.0).abs() <= (plain / n2000 - 1.0).abs());
    }

    #[test]
    fn law_fit_recovers_its_coefficients() {
        let (a, b) = (3.0, 400.0);
        let v = |m: f64| law_noise(a, b, m);
        let (fa, fb) = fit_law(125.0, v(125.0), 500.0, v(500.0));
        assert!((fa / a - 1.0).abs() < 1e-12 && (fb / b - 1.0).abs() < 1e-12, "{fa} {fb}");
        let n = beams_for_law(fa, fb, 0.05);
        assert!((v(n) / 0.05 - 1.0).abs() < 1e-12, "{n}: {}", v(n));
        // b = 0: the plain law.
        let (pa, pb) = fit_law(125.0, 0.4, 500.0, 0.2);
        assert_eq!(pb, 0.0);
        assert!((beams_for_law(pa, pb, 0.1) - 500.0 * 4.0).abs() < 1e-9);
        // a = 0: N = (b / t^2)^(2/3).
        assert!((beams_for_law(0.0, 8.0, 0.5) - fmath::powf(32f64, 2.0 / 3.0)).abs() < 1e-9);
    }

    #[test]
    fn the_chosen_count_reaches_the_target_noise() {
        // End to end: pick N for a target from the pilot, then measure the
        // noise of two independent N-beam grids (streams 0.. and 2^40..,
        // neither the pilot's second half) with the same split estimator.
        // What is left is the sampling error of the pilot's two estimates:
        // the quarter estimate at 125 beams scatters 10-20 % (the module
        // documentation's means of three), and when it comes out high the
        // fit falls back to the start law alone (a = 0), which then carries
        // that scatter into the count; plus a few percent in the measured
        // pair here. 20 % on the noise, as the law test above (measured
        // after the BakePlan merge: 0.0577 for 0.05, the a = 0 branch). Target
        // 0.05: expected deposition with stratified starts reaches 0.1 with
        // about 1100 beams, not enough above the pilot's own 500 to test.
        let s = small_scene();
        let plan = BakePlan::new(&s, &NoProgress);
        let target = 0.05;
        let est = beams_for_noise(&plan, target).unwrap();
        assert!(!est.capped && est.beams > 4 * PILOT_HALF_BEAMS, "{est:?}");
        let n = est.beams;
        let grid = |first: u64| {
            let ph = crate::pipeline::bake::trace::trace(&plan, n, first, 0..n, &NoProgress).unwrap().photons;
            crate::pipeline::bake::gather::gather(&plan, &ph, 1.0, &NoProgress)
        };
        let measured = split_noise(&grid(1 << 20), &grid(3 << 40)).sqrt();
        eprintln!("target {target}: measured {measured}, {est:?}");
        assert!((measured / target - 1.0).abs() < 0.2, "measured {measured} for target {target}: {est:?}");
        // A cap below the need is reported, and honoured.
        let mut capped = s.clone();
        capped.beams.count = est.beams / 4;
        let e2 = beams_for_noise(&BakePlan::reusing(&capped, &plan, &NoProgress), target).unwrap();
        assert!(e2.capped && e2.beams == est.beams / 4);
        let want = law_noise(e2.law_a, e2.law_b, e2.beams as f64);
        assert!((e2.expected_noise / want - 1.0).abs() < 1e-12, "{e2:?}");
    }
}
