//! Beam starts over a footprint, in proportion to its energy flux
//! (`beams.starts`).
//!
//! A curtain's beams carry equal power, so their starts must have the
//! density of the footprint's flux: the piecewise-constant density `f` of
//! the cells above threshold, uniform inside each cell.
//!
//! - `random` (the estimator before issue 10): independent points, a cell
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

use crate::footprint::Footprint;

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

/// Inverse-CDF map from the unit square to a footprint's flux density
/// (cells above threshold, weighted by their density).
#[derive(Clone, Debug)]
pub struct FluxMap {
    nx: usize,
    ny: usize,
    /// Cumulative column masses, `col[i]` = sum over columns 0..=i.
    col: Vec<f64>,
    /// Cumulative row masses per column, `row[i * ny + j]` = sum over rows
    /// 0..=j of column i.
    row: Vec<f64>,
    length: f64,
    width: f64,
}

/// Index of the first cumulative entry above `t` in `cum` (entries with
/// zero mass are never chosen), clamped to the last entry with mass; and
/// the remainder of `t` in that entry, in [0, 1).
#[inline]
fn invert(cum: &[f64], t: f64) -> (usize, f64) {
    let total = *cum.last().unwrap();
    let mut k = cum.partition_point(|&c| c <= t);
    if k >= cum.len() {
        // t rounded up to the total: the last entry with mass.
        k = cum.len() - 1;
        while k > 0 && cum[k - 1] == total {
            k -= 1;
        }
    }
    let lo = if k == 0 { 0.0 } else { cum[k - 1] };
    // Kept 1e-9 of a cell from its upper edge, so rounding in the caller's
    // (i + f) du never lands in the next cell.
    let f = ((t - lo) / (cum[k] - lo)).clamp(0.0, 1.0 - 1e-9);
    (k, f)
}

impl FluxMap {
    /// The map of `f`'s cells above `threshold`; None if there is none.
    pub fn new(f: &Footprint, threshold: f64) -> Option<Self> {
        let (nx, ny) = (f.nx, f.ny);
        let mut row = vec![0.0; nx * ny];
        let mut col = vec![0.0; nx];
        let mut acc_col = 0.0;
        for i in 0..nx {
            let mut acc = 0.0;
            for j in 0..ny {
                let d = f.cell(i, j) as f64;
                if d > threshold {
                    acc += d;
                }
                row[i * ny + j] = acc;
            }
            acc_col += acc;
            col[i] = acc_col;
        }
        (acc_col > 0.0).then_some(Self { nx, ny, col, row, length: f.length, width: f.width })
    }

    /// The cell (i, j) and the point (u, v) in the curtain frame, km, that
    /// the unit-square point `x` maps to.
    pub fn map(&self, x: [f64; 2]) -> ((usize, usize), (f64, f64)) {
        let total = self.col[self.nx - 1];
        let (i, fu) = invert(&self.col, x[0] * total);
        let rows = &self.row[i * self.ny..(i + 1) * self.ny];
        let (j, fv) = invert(rows, x[1] * rows[self.ny - 1]);
        let (du, dv) = (self.length / self.nx as f64, self.width / self.ny as f64);
        ((i, j), (-0.5 * self.length + (i as f64 + fu) * du, -0.5 * self.width + (j as f64 + fv) * dv))
    }

    /// The start (u, v) of beam `index` of the stratified sequence with
    /// `shift`.
    #[inline]
    pub fn start(&self, index: u64, shift: [u64; 2]) -> (f64, f64) {
        self.map(r2(index, shift)).1
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::beams::FootprintCdf;
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
        (((u + 0.5 * fp.length) / du) as usize, ((v + 0.5 * fp.width) / dv) as usize)
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
        let map = FluxMap::new(&fp, thr).unwrap();
        let n = 100_000u64;
        let sh = shift(&[1, 2]);
        let strat: Vec<(usize, usize)> = (0..n).map(|i| map.map(r2(i, sh)).0).collect();
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
        // The point inside the cell agrees with the cell the map reports.
        for i in 0..2000 {
            let (c, p) = map.map(r2(i, sh));
            assert_eq!(cell_of(&fp, p), c);
        }
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
    fn unit_square_corners_map_inside_cells_with_flux() {
        let fp = Footprint { nx: 4, ny: 2, data: vec![0.0, 1.0, 0.0, 0.5, 0.0, 0.0, 0.0, 2.0], center: [0.0, 0.0], rotation_rad: 0.0, length: 4.0, width: 2.0 };
        let m = FluxMap::new(&fp, 0.1).unwrap();
        for x in [[0.0, 0.0], [1.0, 1.0], [1.0 - 1e-16, 1.0 - 1e-16], [0.5, 0.999], [0.3, 0.0]] {
            let ((i, j), (u, v)) = m.map(x);
            assert!(fp.cell(i, j) > 0.1, "{x:?} -> {i},{j}");
            assert_eq!(cell_of(&fp, (u, v)), (i, j));
        }
        // Column 1 holds 1 of the 3.5 total: x1 in [0, 1/3.5) maps there.
        assert_eq!(m.map([0.2, 0.5]).0, (1, 0));
        // Column 3: rows 0.5 | 2, so x2 below 0.2 maps to row 0.
        assert_eq!(m.map([0.5, 0.1]).0, (3, 0));
        assert_eq!(m.map([0.5, 0.3]).0, (3, 1));
        assert!(FluxMap::new(&fp, 5.0).is_none());
    }
}
