//! Beam starts over a footprint, in proportion to its energy flux
//! (`beams.starts`).
//!
//! A curtain's beams carry equal power, so their starts must have the
//! density of the footprint's flux: the piecewise-constant density `f` of
//! the cells above threshold, uniform inside each cell.
//!
//! - `random` (for comparison): independent points, a cell
//!   drawn from the flux CDF then a uniform point in it
//!   ([`crate::beams::FootprintCdf`]). The number of starts in a region of
//!   expected count `n` is binomial, `n +- sqrt(n)`: Poisson noise of the
//!   start positions that no kernel removes.
//! - `stratified` (default): beam `i` takes point `i` of the R2 sequence
//!   (Roberts 2018, "The unreasonable effectiveness of quasirandom
//!   sequences"; the additive recurrence `x_i = frac(s + i alpha)` with
//!   `alpha = (1/g, 1/g^2)`, g the plastic number, root of `x^3 = x + 1`),
//!   with a Cranley-Patterson shift `s` hashed from the seeds (Cranley &
//!   Patterson 1976: every point is then uniform on the square, so the
//!   estimator stays unbiased), mapped to the footprint by inverting its
//!   flux distribution: `x_1` through the marginal CDF of the columns (along
//!   the curtain, u), `x_2` through the conditional CDF of the rows of that
//!   column (across it, v), and the remainders place the point inside the
//!   cell (the inversion of pbrt's `PiecewiseConstant2D`). The map is
//!   monotone in each coordinate, so every cell is the image of an
//!   axis-aligned box of the unit square whose area is the cell's share of
//!   the flux, and the count of starts in it is off by the sequence's
//!   discrepancy (`O(log N)` points) instead of `sqrt(n)`.
//!
//! Each block of 2^40 indices has its own shift (`crate::beams`): the
//! pilot's halves (`crate::pilot`) are then independent randomisations, so
//! their difference measures the variance of a stratified bake.
//!
//! The sequence is indexed by the beam index alone, in 64-bit fixed point
//! (`x_i = s + i a mod 2^64`, exact for any index, including the pilot's
//! second half at 2^40): beam `i` is the same beam whatever the beam count,
//! chunking or thread count, so a beam keeps its identity across frames of
//! an animation.

/// R2's generator in 64-bit fixed point: `alpha * 2^64` for
/// `alpha = (1/g, 1/g^2)`, g = 1.324717957244746 (the plastic number).
const R2_A: [u64; 2] = [
    (0.754_877_666_246_692_7 * 18_446_744_073_709_551_616.0) as u64,
    (0.569_840_290_998_053_2 * 18_446_744_073_709_551_616.0) as u64,
];

/// Point `i` of the R2 sequence shifted by `shift` (fixed point, 2^64 =
/// 1), as two numbers in [0, 1).
#[inline]
pub fn r2(i: u64, shift: [u64; 2]) -> [f64; 2] {
    let to_unit = |x: u64| (x >> 11) as f64 * (1.0 / (1u64 << 53) as f64);
    [to_unit(shift[0].wrapping_add(i.wrapping_mul(R2_A[0]))), to_unit(shift[1].wrapping_add(i.wrapping_mul(R2_A[1])))]
}

/// The Cranley-Patterson shift of a curtain's sequence from its seeds.
pub fn shift(parts: &[u64]) -> [u64; 2] {
    let a = crate::rng::stream_seed(parts);
    [a, crate::rng::splitmix64(a)]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::beams::FootprintCdf;
    use crate::footprint::{Footprint, StartMap};
    use crate::scene::{Curtain, FootprintParams};

    fn footprint() -> Footprint {
        let c = Curtain::default();
        let fpp = FootprintParams { resolution: [128, 48], steps: 6, pressure_iterations: 30, ..FootprintParams::default() };
        crate::footprint::simulate(&c, &fpp, 9)
    }

    /// Chi-square of cell counts against the flux shares over the cells
    /// above threshold, and the number of cells.
    fn chi2(fp: &Footprint, thr: f64, cells: &[(usize, usize)]) -> (f64, usize) {
        let mut hits = vec![0usize; fp.data.len()];
        for &(i, j) in cells {
            hits[j * fp.nx + i] += 1;
        }
        let total: f64 = fp.data.iter().map(|&d| d as f64).filter(|&d| d > thr).sum();
        let n = cells.len() as f64;
        let (mut x2, mut k) = (0.0, 0);
        for (c, &d) in fp.data.iter().enumerate() {
            let d = d as f64;
            if d > thr {
                let e = n * d / total;
                x2 += (hits[c] as f64 - e).powi(2) / e;
                k += 1;
            } else {
                assert_eq!(hits[c], 0, "a start in a cell at or below threshold");
            }
        }
        (x2, k)
    }

    fn cell_of(fp: &Footprint, (u, v): (f64, f64)) -> (usize, usize) {
        let (du, dv) = fp.cell_size();
        // A point on the last cell's outer edge (the map's image of x = 1 -
        // 2^-53, rounded) belongs to that cell.
        ((((u + 0.5 * fp.length) / du) as usize).min(fp.nx - 1), (((v + 0.5 * fp.width) / dv) as usize).min(fp.ny - 1))
    }

    #[test]
    fn starts_follow_the_flux_with_less_than_poisson_scatter() {
        // N starts over the K cells above threshold. Independent starts give
        // a multinomial: chi^2 has mean K - 1 and sd sqrt(2 (K - 1)), so the
        // random control must lie within 5 sd of K - 1. Stratified starts
        // miss each cell's count (the image of a box of the unit square) by
        // the sequence's local discrepancy, O(1) points, not sqrt(n): their
        // chi^2 must be far below the multinomial's (a quarter of its mean,
        // itself many sd below it), yet every start lies in a cell above
        // threshold and in proportion (chi^2 bounded, so no cell is missed).
        let fp = footprint();
        let thr = 0.2;
        let map = StartMap::new(&fp, thr);
        assert!(!map.is_empty());
        let n = 100_000u64;
        let sh = shift(&[1, 2]);
        let start = |i: u64| {
            let [a, b] = r2(i, sh);
            map.map(a, b)
        };
        let strat: Vec<(usize, usize)> = (0..n).map(|i| cell_of(&fp, start(i))).collect();
        let cdf = FootprintCdf::new(&fp, thr);
        let mut r = crate::rng::rng(&[5]);
        let random: Vec<(usize, usize)> = (0..n).map(|_| cell_of(&fp, cdf.sample(&fp, &mut r))).collect();
        let (xs, k) = chi2(&fp, thr, &strat);
        let (xr, _) = chi2(&fp, thr, &random);
        let dof = (k - 1) as f64;
        eprintln!("{k} cells: chi2 stratified {xs:.1}, random {xr:.1} (multinomial mean {dof})");
        assert!(k > 300, "{k} cells");
        assert!((xr - dof).abs() < 5.0 * (2.0 * dof).sqrt(), "random control {xr} vs {dof}");
        assert!(xs < 0.25 * dof, "stratified chi2 {xs} vs multinomial mean {dof}");
    }

    #[test]
    fn r2_has_lower_discrepancy_than_random_points() {
        // Star discrepancy estimated on a 64 x 64 grid of anchored boxes
        // [0, a) x [0, b): for N independent points each count is binomial,
        // so the largest deviation over the boxes is some sqrt(N) / 2 points
        // (about 0.5 / sqrt(N) in D*; 1000 points: ~0.016 to 0.05); R2's D*
        // is O(log N / N), below 0.01 here.
        let n = 1000;
        let sh = shift(&[3]);
        let pts: Vec<[f64; 2]> = (0..n).map(|i| r2(i, sh)).collect();
        let mut r = crate::rng::rng(&[6]);
        use rand::Rng;
        let rnd: Vec<[f64; 2]> = (0..n).map(|_| [r.random(), r.random()]).collect();
        let disc = |p: &[[f64; 2]]| {
            let mut worst = 0.0f64;
            for a in 1..=64 {
                for b in 1..=64 {
                    let (a, b) = (a as f64 / 64.0, b as f64 / 64.0);
                    let c = p.iter().filter(|q| q[0] < a && q[1] < b).count() as f64;
                    worst = worst.max((c / p.len() as f64 - a * b).abs());
                }
            }
            worst
        };
        let (ds, dr) = (disc(&pts), disc(&rnd));
        eprintln!("D* R2 {ds:.4}, random {dr:.4}");
        assert!(ds < 0.01 && ds < 0.5 * dr, "R2 {ds} random {dr}");
    }

    #[test]
    fn the_sequence_is_exact_for_any_index() {
        // Fixed point: x_{i + 2^40} - x_i = 2^40 a mod 1, exactly, so far
        // indices are as well spread as near ones (f64 i * alpha would keep
        // only 13 fractional bits at i = 2^40).
        let sh = shift(&[7]);
        let (a, b) = (r2(5, sh), r2(5 + (1 << 40), sh));
        let d = 0.754_877_666_246_692_7 * (1u64 << 40) as f64;
        let off = (b[0] - a[0] - d.fract()).rem_euclid(1.0);
        // d itself is f64 (2^40 a has 13 fractional bits): 1e-3 covers it.
        assert!(off.min(1.0 - off) < 1e-3, "{off}");
        assert_eq!(r2(12345, sh), r2(12345, sh));
        assert_ne!(r2(1, shift(&[1])), r2(1, shift(&[2])));
        for i in [0u64, 1, 1 << 20, 1 << 40, u64::MAX] {
            let x = r2(i, sh);
            assert!((0.0..1.0).contains(&x[0]) && (0.0..1.0).contains(&x[1]));
        }
    }

    #[test]
    fn the_unit_square_maps_inside_cells_with_flux() {
        let fp = Footprint { nx: 4, ny: 2, data: vec![0.0, 1.0, 0.0, 0.5, 0.0, 0.0, 0.0, 2.0], center: [0.0, 0.0], rotation_rad: 0.0, length: 4.0, width: 2.0 };
        let m = StartMap::new(&fp, 0.1);
        // The map's domain is [0, 1)^2 (what r2 returns).
        for x in [[0.0, 0.0], [1.0 - 1e-16, 1.0 - 1e-16], [0.5, 0.999], [0.3, 0.0]] {
            let (i, j) = cell_of(&fp, m.map(x[0], x[1]));
            assert!(fp.cell(i, j) > 0.1, "{x:?} -> {i},{j}");
        }
        // Column 1 holds 1 of the 3.5 total: x1 in [0, 1/3.5) maps there.
        assert_eq!(cell_of(&fp, m.map(0.2, 0.5)), (1, 0));
        // Column 3: rows 0.5 | 2, so x2 below 0.2 maps to row 0.
        assert_eq!(cell_of(&fp, m.map(0.5, 0.1)), (3, 0));
        assert_eq!(cell_of(&fp, m.map(0.5, 0.3)), (3, 1));
        assert!(StartMap::new(&fp, 5.0).is_empty());
    }
}
