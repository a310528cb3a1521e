//! Merged runs: before the kd-tree and splat gathers, straight and evenly
//! lit runs of a beam's contiguous steps become one segment each, along the
//! run's chord with the run's summed power ([`merge_segments`], which states
//! the error bounds: the chord's kernel is the sum of the steps' kernels to
//! within `0.61 off_r + 2 max_cdf` of its peak). A short segment's kernel
//! is mostly its two end caps (two half balls, `4/3 pi (c r)^3` together,
//! against `pi (c r)^2 L` for the body), so one capsule per run instead of
//! one per step cuts the voxels evaluated. The merge runs in parallel over
//! chunks cut between beams, where no run can continue: the same list as
//! one pass (tested).

use crate::pipeline::deposit::{end, pos, Photon};
use glam::DVec3;
use rayon::prelude::*;

/// Tolerances of [`merge_segments`] in the gather, for the kernel radius r
/// at the run's start: chords up to `MERGE_LEN_R` r long, interior joints
/// within `MERGE_OFF_R` r of the chord, and the power's along-chord CDF
/// within `MERGE_CDF` of the uniform one at every joint.
pub const MERGE_LEN_R: f64 = 4.0;
pub const MERGE_OFF_R: f64 = 0.1;
pub const MERGE_CDF: f64 = 0.05;

/// Merges runs of consecutive, contiguous segment photons (one beam's
/// steps, in order: each starts where the previous one ends) into single
/// segments along their chords, with the run's summed power, where the run
/// is straight and evenly lit enough that the segment kernel of the chord
/// is the sum of the steps' kernels to within a stated tolerance:
///
/// - the chord is at most `len_r` r long, r = `radius(start of the run)`;
/// - every interior joint lies within `off_r` r of the chord's line: the
///   steps' kernels are then the chord's shifted sideways by at most
///   `off_r` r, which changes a Gaussian of sd r by at most
///   `off_r * max|u phi(u)| / phi(0) = 0.61 off_r` of its peak. The joints
///   are random (the path is the Monte Carlo sample), their sideways
///   offsets from the chord of either sign, so the estimate's expectation
///   moves by the second-order term only: the chord drops a lateral spread
///   of at most `off_r^2 r^2` from the kernel's `r^2`, 1 % for `off_r = 0.1`;
/// - at every joint, the run's cumulative power share F (each colour
///   component's) and the joint's position along the chord t (as a share of
///   its length) differ by at most `max_cdf`. The steps spread their power uniformly each; integrating by
///   parts along the chord, the kernel sums differ by
///   `P int (F(t) - t) dK/dt dt`, at most `2 max_cdf` times the peak of the
///   chord's along-axis kernel.
///
/// A beam step deflects 2-5 degrees from B (`beams.alpha_d_deg`,
/// `delta_alpha_deg`) and its power follows Fang's smooth profile, so a
/// run of several 0.5 km steps passes these tests: the gather then
/// evaluates one capsule for the run instead of one per step, whose end
/// caps (two half balls, `4/3 pi (c r)^3` together, against `pi (c r)^2 L`
/// for the body) are most of a short segment's voxels. Point photons and photons that do not
/// touch are left alone. Deterministic (a pure function of the list).
///
/// In parallel over chunks of about [`MERGE_CHUNK`] photons cut where no
/// run can continue (a point photon on either side, or a photon that does
/// not start where the previous one ends: between beams): the runs, and so
/// the list, are those of one pass over the whole.
pub fn merge_segments(photons: &[Photon], radius: impl Fn(DVec3) -> f64 + Sync, len_r: f64, off_r: f64, max_cdf: f64) -> Vec<Photon> {
    let breaks_at = |k: usize| {
        let (a, b) = (&photons[k - 1], &photons[k]);
        a.is_point() || b.is_point() || b.position != a.end
    };
    let mut cuts = vec![0];
    let mut k = MERGE_CHUNK;
    while k < photons.len() {
        while k < photons.len() && !breaks_at(k) {
            k += 1;
        }
        if k < photons.len() {
            cuts.push(k);
        }
        k += MERGE_CHUNK;
    }
    cuts.push(photons.len());
    let parts: Vec<Vec<Photon>> =
        cuts.par_windows(2).map(|w| merge_run_list(&photons[w[0]..w[1]], &radius, len_r, off_r, max_cdf)).collect();
    parts.concat()
}

/// Photons per chunk of [`merge_segments`]' parallel pass (before the cut
/// moves to the next beam's start).
pub const MERGE_CHUNK: usize = 1 << 15;

/// [`merge_segments`] in one pass.
fn merge_run_list(photons: &[Photon], radius: &impl Fn(DVec3) -> f64, len_r: f64, off_r: f64, max_cdf: f64) -> Vec<Photon> {
    let mut out = Vec::with_capacity(photons.len());
    let mut i = 0;
    while i < photons.len() {
        let first = &photons[i];
        let mut j = i;
        if !first.is_point() {
            let a = pos(first);
            let r = radius(a);
            let (max_len, max_off) = (len_r * r, off_r * r);
            while j + 1 < photons.len() {
                let next = &photons[j + 1];
                if next.is_point() || next.position != photons[j].end {
                    break;
                }
                let b = end(next);
                let chord = b - a;
                let len = chord.length();
                if len > max_len || len == 0.0 {
                    break;
                }
                let d = chord / len;
                let mut sum = [0.0f64; 3];
                for q in &photons[i..=j + 1] {
                    for (s, &p) in sum.iter_mut().zip(&q.power) {
                        *s += p as f64;
                    }
                }
                let mut acc = [0.0f64; 3];
                let ok = photons[i..=j].iter().all(|q| {
                    let w = end(q) - a;
                    let t = w.dot(d);
                    let off2 = (w.length_squared() - t * t).max(0.0);
                    let mut even = true;
                    for k in 0..3 {
                        acc[k] += q.power[k] as f64;
                        even &= sum[k] <= 0.0 || (acc[k] / sum[k] - t / len).abs() <= max_cdf;
                    }
                    off2 <= max_off * max_off && even
                });
                if !ok {
                    break;
                }
                j += 1;
            }
        }
        if j == i {
            out.push(*first);
        } else {
            let mut power = [0.0f32; 3];
            for q in &photons[i..=j] {
                for (s, &p) in power.iter_mut().zip(&q.power) {
                    *s += p;
                }
            }
            out.push(Photon::segment(first.position, photons[j].end, power));
        }
        i = j + 1;
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pipeline::photons::kernel::{estimate_brute_force, Kernel};
    use crate::pipeline::photons::test_fixtures::{beam_path, segment_photons};
    use crate::util::rng;
    use rand::Rng;

    /// The parallel merge (chunks cut between beams) gives the one-pass
    /// list: chains of contiguous steps of random lengths, straight and
    /// kinked, across many chunk boundaries, with point photons between.
    #[test]
    fn parallel_merge_equals_one_pass() {
        let mut r = rng::rng(&[17]);
        let mut photons = Vec::new();
        while photons.len() < 3 * MERGE_CHUNK + 777 {
            let mut a: [f32; 3] = std::array::from_fn(|_| r.random_range(-50.0f32..50.0));
            for _ in 0..r.random_range(1..900) {
                // Mostly straight and even (runs merge), now and then a kink.
                let w = if r.random_range(0..10) == 0 { 0.3f32 } else { 0.005 };
                let b = [a[0] + r.random_range(-w..w), a[1] + r.random_range(-w..w), a[2] - 0.5];
                photons.push(Photon::segment(a, b, [1.0; 3]));
                a = b;
            }
            if r.random_range(0..4) == 0 {
                photons.push(Photon::point(a, [1.0; 3]));
            }
        }
        let radius = |_: DVec3| 0.5;
        let one = merge_run_list(&photons, &radius, MERGE_LEN_R, MERGE_OFF_R, MERGE_CDF);
        let par = merge_segments(&photons, radius, MERGE_LEN_R, MERGE_OFF_R, MERGE_CDF);
        assert!(one.len() < photons.len() / 2, "runs merged: {} of {}", one.len(), photons.len());
        assert_eq!(par, one);
    }

    #[test]
    fn merged_runs_keep_the_field_within_their_tolerance() {
        // The merged photons' field (f64 oracle) against the steps' own, on
        // points around the path. Per run, the bound of merge_segments is
        // (0.61 off_r + 2 max_cdf) times the run's peak; summed over the
        // runs overlapping a point it is at most that share of the field's
        // largest value: 0.161 for the gather's tolerances. The measured
        // error is far below (the offsets and CDF misses are random in sign
        // and mostly well inside the limits): 4.7 % of the peak here.
        let steps = beam_path(60, 4);
        let k = Kernel::new(0.5, 2.5);
        let merged = merge_segments(&steps, |_| 0.5, MERGE_LEN_R, MERGE_OFF_R, MERGE_CDF);
        eprintln!("{} steps -> {} photons", steps.len(), merged.len());
        assert!(merged.len() * 2 < steps.len(), "{} -> {}", steps.len(), merged.len());
        let sum = |ps: &[Photon]| ps.iter().fold([0.0f64; 3], |a, p| std::array::from_fn(|c| a[c] + p.power[c] as f64));
        let (s0, s1) = (sum(&steps), sum(&merged));
        for c in 0..3 {
            assert!((s0[c] / s1[c] - 1.0).abs() < 1e-6, "power {s0:?} {s1:?}");
        }
        assert_eq!(merged[0].position, steps[0].position);
        assert_eq!(merged.last().unwrap().end, steps.last().unwrap().end);
        let (mut peak, mut worst) = (0.0f64, 0.0f64);
        let mut r = rng::rng(&[8]);
        let lo = steps.iter().map(end).fold(DVec3::splat(f64::INFINITY), DVec3::min) - DVec3::splat(1.5);
        let hi = steps.iter().map(pos).fold(DVec3::splat(f64::NEG_INFINITY), DVec3::max) + DVec3::splat(1.5);
        for _ in 0..20000 {
            let x = lo + (hi - lo) * DVec3::new(r.random(), r.random(), r.random());
            let (a, b) = (estimate_brute_force(&steps, x, &k), estimate_brute_force(&merged, x, &k));
            for c in 0..3 {
                peak = peak.max(a[c] / s0[c]);
                worst = worst.max((a[c] - b[c]).abs() / s0[c]);
            }
        }
        eprintln!("largest difference {:.4} of the peak", worst / peak);
        assert!(worst < 0.161 * peak, "difference {worst} vs peak {peak}");
        assert!(worst < 0.08 * peak, "difference {worst} vs peak {peak}: well inside the bound expected");
        // Photons that do not touch, and points, are left alone.
        let loose = segment_photons(200, 3);
        assert_eq!(merge_segments(&loose, |_| 0.5, MERGE_LEN_R, MERGE_OFF_R, MERGE_CDF), loose);
        // A kink (joint far off the chord) is not merged.
        let kink =
            [Photon::segment([0.0, 0.0, 0.0], [0.0, 0.0, -0.5], [1.0; 3]), Photon::segment([0.0, 0.0, -0.5], [0.3, 0.0, -1.0], [1.0; 3])];
        assert_eq!(merge_segments(&kink, |_| 0.5, MERGE_LEN_R, MERGE_OFF_R, MERGE_CDF).len(), 2);
        // Uneven power (all of it on the first of two equal steps) is not.
        let uneven =
            [Photon::segment([0.0, 0.0, 0.0], [0.0, 0.0, -0.5], [1.0; 3]), Photon::segment([0.0, 0.0, -0.5], [0.0, 0.0, -1.0], [0.01; 3])];
        assert_eq!(merge_segments(&uneven, |_| 0.5, MERGE_LEN_R, MERGE_OFF_R, MERGE_CDF).len(), 2);
        let even = [uneven[0], Photon::segment([0.0, 0.0, -0.5], [0.0, 0.0, -1.0], [1.0; 3])];
        assert_eq!(
            merge_segments(&even, |_| 0.5, MERGE_LEN_R, MERGE_OFF_R, MERGE_CDF),
            vec![Photon::segment([0.0, 0.0, 0.0], [0.0, 0.0, -1.0], [2.0; 3])]
        );
    }
}
