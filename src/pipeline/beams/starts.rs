//! Beam starts over a footprint, in proportion to its energy flux
//! (`beams.starts`).
//!
//! A curtain's beams carry equal power, so their starts must have the
//! density of the footprint's flux: the piecewise-constant density `f` of
//! the cells above threshold, uniform inside each cell.
//!
//! - `random`: independent points, two uniform random numbers mapped
//!   through the footprint's [`StartMap`]. The number of starts in a region
//!   of expected count `n` is binomial, `n +- sqrt(n)`: Poisson noise of the
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
//!   cell ([`StartMap`], the inversion of pbrt's `PiecewiseConstant2D`).
//!   The map is monotone in each coordinate, so every cell is the image of
//!   an axis-aligned box of the unit square whose area is the cell's share
//!   of the flux, and the count of starts in it is off by the sequence's
//!   discrepancy (`O(log N)` points) instead of `sqrt(n)`.
//!
//! Two samplers of the flux density live here, and they differ:
//! - [`StartMap`] (every bake, both modes): a continuous map of the unit
//!   square, so a beam with a fixed point moves with its footprint from
//!   frame to frame and the R2 points keep their stratification.
//! - [`FootprintCdf`] (no bake uses it): one flat CDF over the cells in row
//!   order and a uniform point in the drawn cell, three random numbers per
//!   start; not continuous in the footprint (a change in one cell shifts
//!   every later start), and an independent construction of the same
//!   density: the tests' reference sampler and random control.
//!
//! Each block of 2^40 indices has its own shift ([`UnitPoints`]): the
//! pilot's halves (`crate::pipeline::bake::pilot`) are then independent randomisations, so
//! their difference measures the variance of a stratified bake.
//!
//! The sequence is indexed by the beam index alone, in 64-bit fixed point
//! (`x_i = s + i a mod 2^64`, exact for any index, including the pilot's
//! second half at 2^40): beam `i` is the same beam whatever the beam count,
//! chunking or thread count, so a beam keeps its identity across frames of
//! an animation.

use crate::pipeline::footprint::Footprint;
use crate::scene::BeamStarts;
use rand::Rng;

/// R2's generator in 64-bit fixed point: `alpha * 2^64` for
/// `alpha = (1/g, 1/g^2)`, g = 1.324717957244746 (the plastic number).
const R2_A: [u64; 2] =
    [(0.754_877_666_246_692_7 * 18_446_744_073_709_551_616.0) as u64, (0.569_840_290_998_053_2 * 18_446_744_073_709_551_616.0) as u64];

/// Point `i` of the R2 sequence shifted by `shift` (fixed point, 2^64 =
/// 1), as two numbers in [0, 1).
#[inline]
pub fn r2(i: u64, shift: [u64; 2]) -> [f64; 2] {
    let to_unit = |x: u64| (x >> 11) as f64 * (1.0 / (1u64 << 53) as f64);
    [to_unit(shift[0].wrapping_add(i.wrapping_mul(R2_A[0]))), to_unit(shift[1].wrapping_add(i.wrapping_mul(R2_A[1])))]
}

/// The Cranley-Patterson shift of a curtain's sequence from its seeds.
pub fn shift(parts: &[u64]) -> [u64; 2] {
    let a = crate::util::rng::stream_seed(parts);
    [a, crate::util::rng::splitmix64(a)]
}

/// The unit-square point of each beam of one curtain (`beams.starts`),
/// which its [`StartMap`] takes to the footprint. Beam `index` draws two
/// numbers from its own stream in either mode (so the rest of its stream,
/// energy and path, is the same in both) and, stratified, takes R2 point
/// `index` instead. Each block of 2^40 indices (the pilot's independent
/// halves live in blocks 1-3) has its own Cranley-Patterson shift, so the
/// blocks are independent randomisations of the sequence; block 0 (every
/// bake) keeps the plain shift of `seeds`.
#[derive(Clone, Copy, Debug)]
pub struct UnitPoints {
    mode: BeamStarts,
    seeds: [u64; 3],
    shift0: [u64; 2],
}

impl UnitPoints {
    /// `seeds`: the scene's seed, the curtain's seed and the stream tag.
    pub fn new(mode: BeamStarts, seeds: [u64; 3]) -> Self {
        Self { mode, seeds, shift0: shift(&seeds) }
    }

    fn shift(&self, index: u64) -> [u64; 2] {
        match index >> 40 {
            0 => self.shift0,
            k => shift(&[self.seeds[0], self.seeds[1], self.seeds[2], k]),
        }
    }

    /// Beam `index`'s point of [0, 1)^2, drawing two numbers from `r`.
    pub fn point(&self, index: u64, r: &mut impl Rng) -> (f64, f64) {
        let (xi1, xi2) = (r.random::<f64>(), r.random::<f64>());
        match self.mode {
            BeamStarts::Random => (xi1, xi2),
            BeamStarts::Stratified => {
                let [a, b] = r2(index, self.shift(index));
                (a, b)
            }
        }
    }
}

/// Where beams start: a continuous map from the unit square onto the
/// footprint's cells above threshold, with density proportional to the
/// footprint's (beams per area follow the energy flux).
///
/// Marginal-conditional inversion (Pharr, Jakob & Humphreys, PBRT 4th ed.,
/// section A.5, "Sampling 2D functions"): xi_1 picks the column (u) through
/// the marginal CDF of the column sums and lands at its linear position
/// inside the column; xi_2 picks v through that column's conditional CDF,
/// again linearly inside the cell. The map is continuous in the footprint's
/// values, so as the footprint moves between frames a beam with fixed
/// (xi_1, xi_2) moves with it instead of jumping (a flat CDF over all cells
/// in row order, [`FootprintCdf`], would shift every beam when any upstream
/// cell changes). The bake's only start sampler, `random` and `stratified`.
#[derive(Clone, Debug)]
pub struct StartMap {
    nx: usize,
    ny: usize,
    /// Marginal CDF over columns, unnormalised; `col_cdf[i]` = mass of columns 0..=i.
    col_cdf: Vec<f64>,
    /// Per column, the conditional CDF over its rows (unnormalised), nx * ny.
    row_cdf: Vec<f64>,
    length: f64,
    width: f64,
}

impl StartMap {
    /// Cells at or below `threshold` weigh nothing.
    pub fn new(f: &Footprint, threshold: f64) -> Self {
        let (nx, ny) = (f.nx, f.ny);
        let mut row_cdf = vec![0.0; nx * ny];
        let mut col_cdf = vec![0.0; nx];
        let mut acc_cols = 0.0;
        for i in 0..nx {
            let mut acc = 0.0;
            for j in 0..ny {
                let d = f.cell(i, j) as f64;
                if d > threshold {
                    acc += d;
                }
                row_cdf[i * ny + j] = acc;
            }
            acc_cols += acc;
            col_cdf[i] = acc_cols;
        }
        Self { nx, ny, col_cdf, row_cdf, length: f.length, width: f.width }
    }

    pub fn is_empty(&self) -> bool {
        self.col_cdf.last().is_none_or(|&m| m <= 0.0)
    }

    /// The point (u, v), curtain frame, km, for (xi_1, xi_2) in [0, 1)^2.
    pub fn map(&self, xi1: f64, xi2: f64) -> (f64, f64) {
        let total = self.col_cdf[self.nx - 1];
        let x = xi1 * total;
        let i = self.col_cdf.partition_point(|&c| c <= x).min(self.nx - 1);
        // Skip empty columns the partition point can land on only at x = 0.
        let before = if i > 0 { self.col_cdf[i - 1] } else { 0.0 };
        let mass = self.col_cdf[i] - before;
        let fu = if mass > 0.0 { ((x - before) / mass).clamp(0.0, 1.0) } else { 0.5 };
        let rows = &self.row_cdf[i * self.ny..(i + 1) * self.ny];
        let y = xi2 * rows[self.ny - 1];
        let j = rows.partition_point(|&c| c <= y).min(self.ny - 1);
        let below = if j > 0 { rows[j - 1] } else { 0.0 };
        let m = rows[j] - below;
        let fv = if m > 0.0 { ((y - below) / m).clamp(0.0, 1.0) } else { 0.5 };
        let (du, dv) = (self.length / self.nx as f64, self.width / self.ny as f64);
        (-0.5 * self.length + (i as f64 + fu) * du, -0.5 * self.width + (j as f64 + fv) * dv)
    }
}

/// Cumulative distribution over the footprint cells above threshold, each
/// cell weighted by its density (beams per area follow the energy flux).
///
/// The same density as [`StartMap`], built differently: one flat CDF over
/// the cells in row order, then a uniform point in the drawn cell (three
/// random numbers per start, no unit-square map, so not continuous in the
/// footprint and not stratifiable). No bake uses it: it is the independent
/// reference the tests check [`StartMap`] and the stratified starts against.
#[derive(Clone, Debug)]
pub struct FootprintCdf {
    cells: Vec<u32>,
    cdf: Vec<f64>,
}

impl FootprintCdf {
    pub fn new(f: &Footprint, threshold: f64) -> Self {
        let mut cells = Vec::new();
        let mut cdf = Vec::new();
        let mut acc = 0.0;
        for (k, &d) in f.data.iter().enumerate() {
            if d as f64 > threshold {
                acc += d as f64;
                cells.push(k as u32);
                cdf.push(acc);
            }
        }
        Self { cells, cdf }
    }

    pub fn is_empty(&self) -> bool {
        self.cells.is_empty()
    }

    /// A point (u, v) in the curtain frame: a cell drawn from the CDF, then a
    /// uniform point inside it (no rejection).
    pub fn sample(&self, f: &Footprint, r: &mut impl Rng) -> (f64, f64) {
        let total = *self.cdf.last().unwrap_or(&0.0);
        let x = r.random::<f64>() * total;
        let i = self.cdf.partition_point(|&c| c <= x).min(self.cells.len() - 1);
        let k = self.cells[i] as usize;
        let (ci, cj) = (k % f.nx, k / f.nx);
        let (du, dv) = f.cell_size();
        let u = -0.5 * f.length + (ci as f64 + r.random::<f64>()) * du;
        let v = -0.5 * f.width + (cj as f64 + r.random::<f64>()) * dv;
        (u, v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Curtain, FootprintParams};
    use crate::util::fmath;

    /// The 2014 fluid's broad folded band: hundreds of cells above the
    /// tests' thresholds, which the sampling statistics need.
    fn footprint() -> Footprint {
        let c = Curtain::default();
        crate::pipeline::footprint::simulate(&c, &crate::pipeline::footprint::small_params(), 9)
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
                x2 += fmath::powi(hits[c] as f64 - e, 2) / e;
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
        let mut r = crate::util::rng::rng(&[5]);
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
        let mut r = crate::util::rng::rng(&[6]);
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
        let fp = Footprint {
            nx: 4,
            ny: 2,
            data: vec![0.0, 1.0, 0.0, 0.5, 0.0, 0.0, 0.0, 2.0],
            center: [0.0, 0.0],
            rotation_rad: 0.0,
            length: 4.0,
            width: 2.0,
            path: None,
            flux_scale: 1.0,
            filament_share: None,
        };
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

    /// The start map's oracle: mapping a uniform grid of (xi1, xi2) must put
    /// into each cell a share of points equal to its share of the mass (cells
    /// above threshold only). With an n x n stratified grid the column gets
    /// n c +- 1 points across (c its share of the mass) and the cell
    /// n q +- 1 of them along (q its share of the column), so the count is
    /// exact to a relative 1 / (n c) + 1 / (n q) (plus a point for rounding).
    #[test]
    fn start_map_follows_the_density_and_is_continuous() {
        let f = crate::pipeline::footprint::simulate(
            &Curtain::default(),
            &FootprintParams { resolution: [64, 24], steps: 4, pressure_iterations: 20, ..FootprintParams::default() },
            3,
        );
        let thr = 0.03;
        let m = StartMap::new(&f, thr);
        let n = 2000;
        let mut counts = vec![0usize; f.nx * f.ny];
        let (du, dv) = f.cell_size();
        for a in 0..n {
            for b in 0..n {
                let (u, v) = m.map((a as f64 + 0.5) / n as f64, (b as f64 + 0.5) / n as f64);
                let i = ((u + 0.5 * f.length) / du).floor() as usize;
                let j = ((v + 0.5 * f.width) / dv).floor() as usize;
                counts[j * f.nx + i] += 1;
            }
        }
        let total: f64 = f.data.iter().map(|&d| d as f64).filter(|&d| d > thr).sum();
        for (k, &d) in f.data.iter().enumerate() {
            let share = if d as f64 > thr { d as f64 / total } else { 0.0 };
            let got = counts[k] as f64 / (n * n) as f64;
            if share == 0.0 {
                assert_eq!(counts[k], 0, "cell {k} below threshold got points");
            } else {
                let i = k % f.nx;
                let col: f64 = (0..f.ny).map(|j| f.cell(i, j) as f64).filter(|&d| d > thr).sum::<f64>();
                let (c, q) = (col / total, d as f64 / col);
                let tol = share * (1.0 / (n as f64 * c) + 1.0 / (n as f64 * q)) + 1.0 / (n * n) as f64;
                assert!((got - share).abs() <= tol, "cell {k}: share {share}, got {got}, tolerance {tol}");
            }
        }
        // Continuity in the footprint: scaling every value keeps every point.
        let mut g = f.clone();
        for d in &mut g.data {
            *d *= 0.5;
        }
        let m2 = StartMap::new(&g, thr * 0.5);
        for &(a, b) in &[(0.1, 0.2), (0.5, 0.5), (0.93, 0.07)] {
            let (p, q) = (m.map(a, b), m2.map(a, b));
            assert!((p.0 - q.0).abs() < 1e-9 && (p.1 - q.1).abs() < 1e-9);
        }
    }

    #[test]
    fn start_points_land_only_above_threshold() {
        let c = Curtain::default();
        let fpp = FootprintParams { resolution: [128, 48], steps: 6, pressure_iterations: 30, ..FootprintParams::default() };
        let fp = crate::pipeline::footprint::simulate(&c, &fpp, 9);
        let thr = 0.2;
        let cdf = FootprintCdf::new(&fp, thr);
        let mut r = crate::util::rng::rng(&[4]);
        let mut hits = vec![0usize; fp.data.len()];
        for _ in 0..20_000 {
            let (u, v) = cdf.sample(&fp, &mut r);
            let (x, y) = fp.to_world(u, v);
            assert!(fp.cell_value_world(x, y) > thr);
            let (du, dv) = fp.cell_size();
            let k = ((v + 0.5 * fp.width) / dv) as usize * fp.nx + ((u + 0.5 * fp.length) / du) as usize;
            hits[k] += 1;
        }
        // Cells are drawn in proportion to density: compare the hit share of
        // the densest half of the eligible mass with its expected share, to
        // 5 sigma of a binomial with N = 20000.
        let mut eligible: Vec<(f64, usize)> =
            fp.data.iter().enumerate().filter(|(_, &d)| d as f64 > thr).map(|(k, &d)| (d as f64, k)).collect();
        eligible.sort_by(|a, b| b.0.total_cmp(&a.0));
        let total: f64 = eligible.iter().map(|e| e.0).sum();
        let top: Vec<_> = eligible.iter().take(eligible.len() / 4).collect();
        let p: f64 = top.iter().map(|e| e.0).sum::<f64>() / total;
        let got = top.iter().map(|e| hits[e.1]).sum::<usize>() as f64 / 20_000.0;
        let sigma = (p * (1.0 - p) / 20_000.0).sqrt();
        assert!((got - p).abs() < 5.0 * sigma, "{got} vs {p} +- {sigma}");
    }
}
