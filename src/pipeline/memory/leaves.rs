//! The leaves a bake's grids can hold, counted from the plan the bake runs
//! (its footprints, field, kernel and voxel size): the memory budget's
//! grid term ([`super::budget`]).
//!
//! Model: a beam starts where the bake draws it
//! ([`crate::pipeline::beams::start_positions`]: the same points, so the
//! plan's own beams), or, where the budget does not draw them
//! ([`super::budget::draws_starts`]), anywhere in a
//! footprint cell above `footprint.threshold` at most `beams.top_noise_km`
//! off `beams.top_km`. It walks down (and, with Fang's depositions, lays
//! its column up) the straight field line through its start (the plan's
//! [`BakePlan::field_at`], as the trace follows it), never
//! farther across it than the walk's spread
//! ([`super::reach::spread_km`]); its photons' kernels
//! reach `cutoff * r_max` and the Cycles shell one voxel more. Each start
//! is carried along its line to `beams.top_km` and merged onto a grid
//! (a voxel for drawn starts, half a leaf for cells). So every voxel the
//! grids hold lies within
//! `rho = reach + voxel + spread + merge + spacing / 2` (drawn starts: plus
//! the field's turn, the dipole's or IGRF's over a site, between a start
//! and its merged point; cells: plus the
//! cell's half-diagonal and `top_noise cot(I)`)
//! of a point of a column's field line, sampled every `spacing`
//! along it (half a leaf, or an eighth of the widest ball where that is
//! more: wide kernels' balls overlap mostly, and cost their area each), from
//! the deposits' top to their bottom (Fang: where the
//! deposition is complete, less a step; CSDA: the path's length, `L (1 +
//! dt)`, below the lowest start). The count is the union of
//! the leaves each sampled ball touches (a leaf touches when its voxel
//! centres' box lies within `rho`), points mapped to the scene frame by
//! the Earth's map (`crate::geometry::earth`; its horizontal scale at
//! altitude h is `1 + h / R`, which widens `rho`).
//!
//! Unlike a bounding box, the union follows a curtain's band however it
//! bends, so it is within the spread and the kernel of the leaves a bake
//! holds.

use crate::pipeline::footprint::Footprint;
use crate::pipeline::plan::BakePlan;
use crate::util::fmath;
use glam::{DVec3, IVec3};
use rayon::prelude::*;
use std::collections::HashSet;
use std::sync::atomic::{AtomicU64, Ordering};

/// One curtain's field lines: where they start and how far each sampled
/// ball reaches, km.
#[derive(Clone, Debug)]
pub struct Band {
    /// Start columns (curved-frame ground points) at `top_km`.
    pub columns: Vec<[f64; 2]>,
    /// The nominal start altitude the lines pass through, km.
    pub start_km: f64,
    /// The highest and lowest altitude sampled, km.
    pub top_km: f64,
    pub bottom_km: f64,
    /// The ball's radius about each point of the line at and above the
    /// start, km, before the Earth's scale and the samples' half spacing; below it the walk's spread is added,
    /// `spread_per_sqrt_km * sqrt(start_km - h)` (its random walk's
    /// standard deviations grow as the root of the steps taken) up to
    /// `spread_max_km`.
    pub rho_km: f64,
    pub spread_per_sqrt_km: f64,
    pub spread_max_km: f64,
}

impl Band {
    /// The ball's radius at altitude `h`, km.
    pub fn rho_at(&self, h: f64) -> f64 {
        let depth = (self.start_km - h).max(0.0);
        self.rho_km + (self.spread_per_sqrt_km * depth.sqrt()).min(self.spread_max_km)
    }
}

/// The start columns of `fp`: cells above `threshold` collapsed onto a
/// grid of `g` km (the cell centres' grid points' centres), and the largest
/// distance from a start to its column's point: the cell's and the grid's
/// half-diagonals.
pub fn start_columns(fp: &Footprint, threshold: f64, g: f64) -> (Vec<[f64; 2]>, f64) {
    let (du, dv) = fp.cell_size();
    let mut set = HashSet::new();
    for j in 0..fp.ny {
        for i in 0..fp.nx {
            let d = fp.cell(i, j) as f64;
            if d <= 0.0 || d < threshold {
                continue;
            }
            let (u, v) = ((i as f64 + 0.5) * du - 0.5 * fp.length, (j as f64 + 0.5) * dv - 0.5 * fp.width);
            let (x, y) = fp.to_world(u, v);
            set.insert(((x / g).floor() as i64, (y / g).floor() as i64));
        }
    }
    let mut cols: Vec<(i64, i64)> = set.into_iter().collect();
    cols.sort_unstable();
    let pts = cols.into_iter().map(|(a, b)| [(a as f64 + 0.5) * g, (b as f64 + 0.5) * g]).collect();
    (pts, 0.5 * fmath::hypot(du, dv) + std::f64::consts::FRAC_1_SQRT_2 * g)
}

/// Largest number of leaves the bit set of [`band_leaves`] spans (its box
/// in leaves, 32 MB of bits); a larger box is not counted (None).
pub const MAX_BOX_LEAVES: usize = 1 << 28;

/// Most leaf columns the balls of [`band_leaves`] may visit, each a run of
/// leaves set a 64-bit word at a time (about 30 ns a column: 4e8 take some
/// 12 s on one core, measured); a count that would take more is not made
/// (None).
pub const MAX_BALL_COLUMNS: f64 = 4.0e8;

/// The leaf columns the balls of `bands` visit, from each band's columns,
/// its samples along a vertical line (the fewest: a slanted line has more)
/// and its widest ball: the work of [`band_leaves`], known before it.
fn ball_columns(bands: &[Band], leaf: f64) -> f64 {
    bands
        .iter()
        .map(|b| {
            let widest = b.rho_km + b.spread_max_km;
            let spacing = (0.5 * leaf).max(widest / 8.0);
            let samples = ((b.top_km - b.bottom_km) / spacing).ceil().max(0.0) + 1.0;
            let across = 2.0 * (widest + 0.5 * spacing) / leaf + 1.0;
            b.columns.len() as f64 * samples * across * across
        })
        .sum()
}

/// The leaves (8^3 voxels of `voxel_km`) within the bands' balls (module
/// documentation), counted once; None when their box spans more than
/// [`MAX_BOX_LEAVES`] or the balls would visit more than
/// [`MAX_BALL_COLUMNS`] leaf columns (the caller's closed-form bound
/// stands).
pub fn band_leaves(plan: &BakePlan, bands: &[Band], voxel_km: f64) -> Option<usize> {
    let earth = plan.earth();
    let leaf = 8.0 * voxel_km;
    if ball_columns(bands, leaf) > MAX_BALL_COLUMNS {
        return None;
    }
    // Each column's samples, half a leaf apart along its line: scene
    // point and ball radius.
    let samples = |b: &Band, at: [f64; 2], each: &mut dyn FnMut(DVec3, f64)| {
        let field = plan.field_at(at);
        let s = DVec3::new(at[0], at[1], b.start_km);
        let spacing = (0.5 * leaf).max((b.rho_km + b.spread_max_km) / 8.0);
        let dh = spacing * (-field.b.z).max(1e-3);
        let n = ((b.top_km - b.bottom_km) / dh).ceil().max(0.0) as usize;
        for i in 0..=n {
            let h = (b.top_km - i as f64 * dh).max(b.bottom_km);
            let scale = if earth.is_flat() { 1.0 } else { 1.0 + h.max(0.0) / plan.scene.earth.radius_km };
            each(earth.to_scene(field.foot(s, h)), (b.rho_at(h) + 0.5 * spacing) * scale);
        }
    };
    let work: Vec<(usize, [f64; 2])> = bands.iter().enumerate().flat_map(|(k, b)| b.columns.iter().map(move |c| (k, *c))).collect();
    if work.is_empty() {
        return Some(0);
    }
    // The box of every ball, in leaves.
    let (lo, hi) = work
        .par_iter()
        .map(|&(k, at)| {
            let (mut lo, mut hi) = (DVec3::INFINITY, DVec3::NEG_INFINITY);
            samples(&bands[k], at, &mut |p, r| {
                lo = lo.min(p - DVec3::splat(r));
                hi = hi.max(p + DVec3::splat(r));
            });
            (lo, hi)
        })
        .reduce(|| (DVec3::INFINITY, DVec3::NEG_INFINITY), |a, b| (a.0.min(b.0), a.1.max(b.1)));
    let l0 = (lo / voxel_km).floor().as_ivec3().div_euclid(IVec3::splat(8)) - IVec3::ONE;
    let l1 = (hi / voxel_km).ceil().as_ivec3().div_euclid(IVec3::splat(8)) + IVec3::ONE;
    let dims = (l1 - l0 + IVec3::ONE).as_dvec3();
    if dims.x * dims.y * dims.z > MAX_BOX_LEAVES as f64 {
        return None;
    }
    let bits = LeafBits::new(l0, l1);
    work.par_iter().for_each(|&(k, at)| {
        samples(&bands[k], at, &mut |p, r| {
            bits.insert_ball(p, r, voxel_km);
        })
    });
    Some(bits.count())
}

/// One bit per leaf of a box of leaves, set from any thread.
struct LeafBits {
    lo: IVec3,
    dims: IVec3,
    words: Vec<AtomicU64>,
}

impl LeafBits {
    fn new(lo: IVec3, hi: IVec3) -> Self {
        let dims = hi - lo + IVec3::ONE;
        let n = dims.x as usize * dims.y as usize * dims.z as usize;
        Self { lo, dims, words: (0..n.div_ceil(64)).map(|_| AtomicU64::new(0)).collect() }
    }

    fn count(&self) -> usize {
        self.words.iter().map(|w| w.load(Ordering::Relaxed).count_ones() as usize).sum()
    }

    /// Sets the leaves whose voxel centres' box lies within `rho` of `p`:
    /// per leaf column within `rho` across, the leaves within the rest of
    /// `rho` up and down, as one run of bits. Returns the columns it
    /// visited.
    fn insert_ball(&self, p: DVec3, rho: f64, vs: f64) -> usize {
        let lo = ((p - DVec3::splat(rho)) / vs).ceil().as_ivec3();
        let hi = ((p + DVec3::splat(rho)) / vs).floor().as_ivec3();
        if lo.cmpgt(hi).any() {
            return 0;
        }
        let mut columns = 0;
        let (l0, l1) = (lo.div_euclid(IVec3::splat(8)), hi.div_euclid(IVec3::splat(8)));
        let gap = |p: f64, k: i32| {
            let (a, b) = ((8 * k) as f64 * vs, (8 * k + 7) as f64 * vs);
            if p < a {
                a - p
            } else if p > b {
                p - b
            } else {
                0.0
            }
        };
        for x in l0.x..=l1.x {
            let gx = gap(p.x, x);
            for y in l0.y..=l1.y {
                let gy = gap(p.y, y);
                let rest = rho * rho - gx * gx - gy * gy;
                if rest < 0.0 {
                    continue;
                }
                let dz = rest.sqrt();
                let (z0, z1) = (((p.z - dz) / vs).ceil() as i32, ((p.z + dz) / vs).floor() as i32);
                if z0 > z1 {
                    continue;
                }
                self.set_run(x, y, z0.div_euclid(8), z1.div_euclid(8));
                columns += 1;
            }
        }
        columns
    }

    /// Sets the leaves `(x, y, z0..=z1)` within the box: consecutive bits
    /// (z varies fastest), so a word at a time.
    fn set_run(&self, x: i32, y: i32, z0: i32, z1: i32) {
        let (dx, dy) = (x - self.lo.x, y - self.lo.y);
        if dx < 0 || dy < 0 || dx >= self.dims.x || dy >= self.dims.y {
            return;
        }
        let (a, b) = ((z0 - self.lo.z).max(0), (z1 - self.lo.z).min(self.dims.z - 1));
        if a > b {
            return;
        }
        let base = (dx as usize * self.dims.y as usize + dy as usize) * self.dims.z as usize;
        let (i0, i1) = (base + a as usize, base + b as usize);
        for w in i0 / 64..=i1 / 64 {
            let from = if w == i0 / 64 { i0 % 64 } else { 0 };
            let to = if w == i1 / 64 { i1 % 64 } else { 63 };
            self.words[w].fetch_or((u64::MAX >> (63 - to)) & (u64::MAX << from), Ordering::Relaxed);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_ball_touches_the_leaves_its_voxels_lie_in() {
        // A ball of 1 km about the origin on 0.5 km voxels: the voxel
        // centres within 1 km are indices -2..=2 per axis, in leaves -1 and 0.
        let bits = LeafBits::new(IVec3::splat(-3), IVec3::splat(3));
        bits.insert_ball(DVec3::ZERO, 1.0, 0.5);
        assert_eq!(bits.count(), 8);
        // Just inside a leaf's middle: one leaf.
        let bits = LeafBits::new(IVec3::splat(-3), IVec3::splat(3));
        bits.insert_ball(DVec3::splat(1.75), 0.3, 0.5);
        assert_eq!(bits.count(), 1);
        // At a voxel centre's height, a leaf whose voxel box is 0.3 km
        // away in x and y (0.42 km) is outside a ball of 0.4 km and inside
        // one of 0.45 km; those 0.2 km away in one axis are inside both.
        let p = DVec3::new(-0.3, -0.3, 2.0);
        let bits = LeafBits::new(IVec3::splat(-3), IVec3::splat(3));
        bits.insert_ball(p, 0.4, 0.5);
        assert_eq!(bits.count(), 3);
        let bits = LeafBits::new(IVec3::splat(-3), IVec3::splat(3));
        bits.insert_ball(p, 0.45, 0.5);
        assert_eq!(bits.count(), 4);
    }

    /// The leaves of a ball set one at a time, as [`LeafBits::insert_ball`]
    /// chooses them: the oracle of its runs.
    fn insert_ball_leaf_by_leaf(bits: &LeafBits, p: DVec3, rho: f64, vs: f64) {
        let lo = ((p - DVec3::splat(rho)) / vs).ceil().as_ivec3();
        let hi = ((p + DVec3::splat(rho)) / vs).floor().as_ivec3();
        if lo.cmpgt(hi).any() {
            return;
        }
        let (l0, l1) = (lo.div_euclid(IVec3::splat(8)), hi.div_euclid(IVec3::splat(8)));
        let gap = |p: f64, k: i32| (8.0 * k as f64 * vs - p).max(p - (8 * k + 7) as f64 * vs).max(0.0);
        for x in l0.x..=l1.x {
            for y in l0.y..=l1.y {
                for z in l0.z..=l1.z {
                    let (gx, gy) = (gap(p.x, x), gap(p.y, y));
                    let rest = rho * rho - gx * gx - gy * gy;
                    // A voxel centre of the leaf's column within the rest, up or down.
                    let near = rest >= 0.0 && (8 * z..8 * z + 8).any(|v| (v as f64 * vs - p.z).abs() <= rest.sqrt());
                    let d = IVec3::new(x, y, z) - bits.lo;
                    if near && !(d.cmplt(IVec3::ZERO).any() || d.cmpge(bits.dims).any()) {
                        let i = (d.x as usize * bits.dims.y as usize + d.y as usize) * bits.dims.z as usize + d.z as usize;
                        bits.words[i / 64].fetch_or(1 << (i % 64), Ordering::Relaxed);
                    }
                }
            }
        }
    }

    #[test]
    fn runs_of_bits_set_the_leaves_one_at_a_time_would() {
        // 300 balls from 0.1 to 40 km across on 0.5 km voxels, some reaching
        // out of a box whose z extent is not a multiple of 64 (runs that
        // cross words and are clipped at the box): the same bits as the
        // leaf-by-leaf oracle.
        use rand::{Rng, SeedableRng};
        let mut r = rand_pcg::Pcg64Mcg::seed_from_u64(7);
        let (lo, hi) = (IVec3::new(-6, -5, -40), IVec3::new(5, 6, 45));
        let (runs, oracle) = (LeafBits::new(lo, hi), LeafBits::new(lo, hi));
        for _ in 0..300 {
            let p = DVec3::new(r.random_range(-30.0..30.0), r.random_range(-30.0..30.0), r.random_range(-200.0..200.0));
            let rho = fmath::exp(r.random_range(fmath::ln(0.05)..fmath::ln(20.0)));
            runs.insert_ball(p, rho, 0.5);
            insert_ball_leaf_by_leaf(&oracle, p, rho, 0.5);
        }
        let words = |b: &LeafBits| b.words.iter().map(|w| w.load(Ordering::Relaxed)).collect::<Vec<_>>();
        assert!(oracle.count() > 1000, "{}", oracle.count());
        assert_eq!(words(&runs), words(&oracle));
    }

    #[test]
    fn the_columns_foreseen_bound_the_columns_visited() {
        // One column of a vertical line, 40 km deep, on 0.5 km voxels (4 km
        // leaves), its balls from 1 km to 60 km wide (a wide pitch-angle
        // spread): the foreseen columns are never fewer than those visited,
        // and within 2x of them (a square of columns against a disc:
        // 4/pi = 1.27 for wide balls). Each column is one run of bits, so
        // the work grows with the columns, not with the ball's height: a
        // 60 km spread once spent minutes setting leaves one at a time.
        let (vs, leaf) = (0.5f64, 4.0f64);
        for widest in [1.0f64, 5.0, 20.0, 60.0] {
            let band = Band {
                columns: vec![[0.0, 0.0]],
                start_km: 120.0,
                top_km: 120.0,
                bottom_km: 80.0,
                rho_km: widest,
                spread_per_sqrt_km: 0.0,
                spread_max_km: 0.0,
            };
            let spacing = (0.5 * leaf).max(widest / 8.0);
            let n = ((band.top_km - band.bottom_km) / spacing).ceil() as usize;
            let bits = LeafBits::new(IVec3::splat(-40), IVec3::splat(60));
            let made: usize = (0..=n)
                .map(|i| {
                    let h = (band.top_km - i as f64 * spacing).max(band.bottom_km);
                    bits.insert_ball(DVec3::new(0.0, 0.0, h), widest + 0.5 * spacing, vs)
                })
                .sum();
            let foreseen = ball_columns(std::slice::from_ref(&band), leaf);
            assert!(foreseen >= made as f64 && foreseen <= 2.0 * made as f64, "{widest} km: {foreseen} foreseen, {made} made");
        }
    }
}
