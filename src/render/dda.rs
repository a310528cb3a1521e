//! Hierarchical DDA over a [`Field`]: the walk that skips empty space.
//!
//! A 3D DDA (Amanatides & Woo 1987) steps a ray through the cells of a
//! regular grid in order of increasing t. As in OpenVDB's `VolumeHDDA` and
//! pbrt-v4's `DDAMajorantIterator`, we run one DDA per tree level: the root
//! (4096-voxel cells, looked up in a hash map; or, with at most
//! [`ROOT_LIST_MAX`] root nodes, a sorted list of the ray's spans through
//! them), each clipped to the box its dual leaves occupy, super nodes (128-voxel
//! blocks), blocks (8-voxel dual leaves) and, inside an occupied dual leaf,
//! its 8^3 dual cells. A level only descends into occupied children, so the
//! cost of a ray is a few steps per 4096 voxels of empty space plus the work
//! inside occupied leaves.
//!
//! [`LeafWalker`] is an `Iterator<Item = LeafSpan>` over occupied dual leaves;
//! [`CellWalker`] is an `Iterator<Item = CellSeg>` over the non-empty dual
//! cells of one leaf span. Together they yield every dual-cell segment of the
//! ray in order, which is what both the exact integrator and shadow rays use.
//!
//! Robustness: every level computes the t of a cell boundary with the same
//! expression `(plane - o) * (1 / d)` (planes are integers in index space), so
//! coinciding boundaries of different levels give identical t; a child DDA
//! starts at its parent cell's entry and clamps its first cell to the parent,
//! which resolves a start exactly on a boundary plane. A ray lying exactly in
//! a plane of voxel centres may be assigned to either neighbouring cell; the
//! trilinear field is continuous there and both cells hold the plane's values
//! (dual leaves share their boundary planes), so the result is the same.

use super::medium::field::Field;
use super::medium::layout::{cell_bit, mask_has, slot, CellMask, BLOCK_LOG2, BLOCK_VOXELS_LOG2, NONE, SUPER_LOG2, SUPER_VOXELS_LOG2};
use crate::grid::LEAF_LOG2DIM;
use glam::{DVec3, IVec3};

/// A ray in a field's index space: `u(t) = o + t d`, with t the world-space
/// ray parameter (so segment lengths in t are world lengths for a unit
/// world direction).
#[derive(Clone, Copy, Debug)]
pub struct IndexRay {
    pub o: [f64; 3],
    pub d: [f64; 3],
    /// `1 / d` per axis (infinite where `d` is 0).
    pub inv_d: [f64; 3],
}

impl IndexRay {
    /// Maps a world ray (origin, direction) into the field's index space.
    pub fn new(field: &Field, origin: DVec3, dir: DVec3) -> Self {
        let o = field.transform.world_to_index(origin);
        let d = dir / field.transform.voxel_size;
        let d = d.to_array();
        IndexRay { o: o.to_array(), d, inv_d: d.map(|v| 1.0 / v) }
    }

    #[inline]
    pub fn at(&self, t: f64) -> DVec3 {
        DVec3::new(self.o[0] + self.d[0] * t, self.o[1] + self.d[1] * t, self.o[2] + self.d[2] * t)
    }

    /// The t at which the ray crosses the plane `u[axis] = p`: `(p - o) / d`,
    /// as a product with the reciprocal (a division would sit on the walk's
    /// critical path once per cell). Every level uses this one expression,
    /// so coinciding planes still give identical t.
    #[inline]
    fn t_plane(&self, axis: usize, p: f64) -> f64 {
        (p - self.o[axis]) * self.inv_d[axis]
    }

    /// The ray's parameter range inside the index box `[lo, hi]`, within
    /// `[t0, t1]` (slab test), or None.
    pub fn clip(&self, lo: IVec3, hi: IVec3, t0: f64, t1: f64) -> Option<(f64, f64)> {
        self.clip_impl(lo, hi, t0, t1, false)
    }

    /// As [`IndexRay::clip`], but a ray parallel to an axis must lie in
    /// `[lo, hi)` along it: boxes that tile space then never both claim a
    /// ray lying exactly in their shared face.
    pub fn clip_half_open(&self, lo: IVec3, hi: IVec3, t0: f64, t1: f64) -> Option<(f64, f64)> {
        self.clip_impl(lo, hi, t0, t1, true)
    }

    fn clip_impl(&self, lo: IVec3, hi: IVec3, t0: f64, t1: f64, half_open: bool) -> Option<(f64, f64)> {
        let (mut a, mut b) = (t0, t1);
        let (lo, hi) = (lo.as_dvec3().to_array(), hi.as_dvec3().to_array());
        for k in 0..3 {
            if self.d[k] == 0.0 {
                if self.o[k] < lo[k] || self.o[k] > hi[k] || (half_open && self.o[k] == hi[k]) {
                    return None;
                }
            } else {
                let (p, q) = (self.t_plane(k, lo[k]), self.t_plane(k, hi[k]));
                let (p, q) = if p <= q { (p, q) } else { (q, p) };
                a = a.max(p);
                b = b.min(q);
            }
        }
        (a < b).then_some((a, b))
    }
}

/// One level's DDA: cells of `2^log2` voxels, restricted to cells `[lo, hi)`
/// (in this level's units) and to `t` in `[t, t_end)`.
#[derive(Clone, Copy, Debug)]
struct Dda {
    cell: [i32; 3],
    lo: [i32; 3],
    hi: [i32; 3],
    step: [i32; 3],
    t_next: [f64; 3],
    t: f64,
    t_end: f64,
    log2: u32,
}

impl Dda {
    fn new(ray: &IndexRay, log2: u32, t0: f64, t1: f64, lo: IVec3, hi: IVec3) -> Self {
        let size = (1u64 << log2) as f64;
        let (lo, hi) = (lo.to_array(), hi.to_array());
        let mut cell = [0; 3];
        let mut step = [0; 3];
        let mut t_next = [f64::INFINITY; 3];
        for a in 0..3 {
            let p = ray.o[a] + ray.d[a] * t0;
            let c = (p / size).floor();
            let c = if c.is_nan() { lo[a] } else { c.clamp(lo[a] as f64, (hi[a] - 1) as f64) as i32 };
            cell[a] = c;
            if ray.d[a] > 0.0 {
                step[a] = 1;
                t_next[a] = ray.t_plane(a, (c as f64 + 1.0) * size);
            } else if ray.d[a] < 0.0 {
                step[a] = -1;
                t_next[a] = ray.t_plane(a, c as f64 * size);
            }
        }
        Dda { cell, lo, hi, step, t_next, t: t0, t_end: t1, log2 }
    }

    /// The current cell and its span `[t0, t1]`, or None when done.
    #[inline]
    fn current(&self) -> Option<(IVec3, f64, f64)> {
        if self.t >= self.t_end {
            return None;
        }
        let t1 = self.t_next[0].min(self.t_next[1]).min(self.t_next[2]).min(self.t_end);
        Some((IVec3::from_array(self.cell), self.t, t1))
    }

    /// The current cell and its span, as [`Dda::current`], the walk then
    /// stepped past it.
    #[inline]
    fn take(&mut self, ray: &IndexRay) -> Option<(IVec3, f64, f64)> {
        let cell = self.current()?;
        self.advance(ray);
        Some(cell)
    }

    /// Steps to the next cell along the axis whose boundary comes first.
    #[inline]
    fn advance(&mut self, ray: &IndexRay) {
        let a = if self.t_next[0] <= self.t_next[1] {
            if self.t_next[0] <= self.t_next[2] {
                0
            } else {
                2
            }
        } else if self.t_next[1] <= self.t_next[2] {
            1
        } else {
            2
        };
        self.t = self.t.max(self.t_next[a]);
        if self.t >= self.t_end {
            return;
        }
        self.cell[a] += self.step[a];
        if self.cell[a] < self.lo[a] || self.cell[a] >= self.hi[a] {
            self.t = f64::INFINITY;
            return;
        }
        let size = (1u64 << self.log2) as f64;
        let plane = if self.step[a] > 0 { self.cell[a] as f64 + 1.0 } else { self.cell[a] as f64 };
        self.t_next[a] = ray.t_plane(a, plane * size);
    }
}

/// The part `[t0, t1]` of a ray inside occupied dual leaf `leaf`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LeafSpan {
    pub t0: f64,
    pub t1: f64,
    pub leaf: u32,
}

/// Root nodes up to which the root level is a sorted list of slab tests
/// rather than a DDA: then a ray's cost does not even grow with the extent
/// of the bounding box (a few leaves far apart cost the same as close).
pub const ROOT_LIST_MAX: usize = 16;

/// The root level of the walk.
enum RootWalk {
    /// Few root nodes: their spans on this ray, sorted by entry, consumed from the back.
    List(Vec<(f64, f64, u32, IVec3)>),
    /// Many root nodes: a DDA over 4096-voxel cells.
    Dda(Dda),
    Done,
}

/// Iterator over the occupied dual leaves a ray crosses, in order.
pub struct LeafWalker<'a> {
    field: &'a Field,
    pub ray: IndexRay,
    root: RootWalk,
    sup: Option<(Dda, u32)>,
    blk: Option<(Dda, u32)>,
    /// Cells visited at all levels (a work measure for tests and stats).
    pub steps: u64,
}

impl<'a> LeafWalker<'a> {
    /// Walks `origin + t dir` for t in `[t0, t1]` (world units).
    pub fn new(field: &'a Field, origin: DVec3, dir: DVec3, t0: f64, t1: f64) -> Self {
        let ray = IndexRay::new(field, origin, dir);
        let clipped = if field.is_empty() { None } else { ray.clip(field.lo, field.hi, t0, t1) };
        let root = match clipped {
            None => RootWalk::Done,
            Some((a, b)) if field.root.len() <= ROOT_LIST_MAX => {
                let mut list: Vec<(f64, f64, u32, IVec3)> = field
                    .root
                    .iter()
                    .filter_map(|(&c, &si)| {
                        // Half-open: a ray in the face shared by two super
                        // nodes belongs to one of them only (the upper, as
                        // the DDA's floor would choose; the shared plane's
                        // values are in both, so either is right).
                        let (lo, hi) = field.super_bounds[si as usize];
                        let (p, q) = ray.clip_half_open(lo, hi, a, b)?;
                        Some((p, q, si, c))
                    })
                    .collect();
                // Root boxes are disjoint, so entry order is ray order; ties
                // (a ray along a shared face) are broken by coordinates so the
                // order never depends on the hash map's.
                list.sort_by(|x, y| y.0.total_cmp(&x.0).then_with(|| (y.3.x, y.3.y, y.3.z).cmp(&(x.3.x, x.3.y, x.3.z))));
                RootWalk::List(list)
            }
            Some((a, b)) => RootWalk::Dda(Dda::new(&ray, SUPER_VOXELS_LOG2, a, b, field.root_lo, field.root_hi)),
        };
        LeafWalker { field, ray, root, sup: None, blk: None, steps: 0 }
    }
}

impl Iterator for LeafWalker<'_> {
    type Item = LeafSpan;

    fn next(&mut self) -> Option<LeafSpan> {
        let f = self.field;
        loop {
            if let Some((dda, bi)) = &mut self.blk {
                if let Some((c, t0, t1)) = dda.take(&self.ray) {
                    self.steps += 1;
                    let li = f.blocks[*bi as usize][slot(c, BLOCK_LOG2)];
                    if li != NONE && t1 > t0 {
                        return Some(LeafSpan { t0, t1, leaf: li });
                    }
                    continue;
                }
                self.blk = None;
            }
            if let Some((dda, si)) = &mut self.sup {
                if let Some((c, t0, t1)) = dda.take(&self.ray) {
                    self.steps += 1;
                    let bi = f.supers[*si as usize][slot(c, SUPER_LOG2)];
                    if bi != NONE && t1 > t0 {
                        let lo = c * (1 << BLOCK_LOG2);
                        let child = Dda::new(&self.ray, LEAF_LOG2DIM, t0, t1, lo, lo + IVec3::splat(1 << BLOCK_LOG2));
                        self.blk = Some((child, bi));
                    }
                    continue;
                }
                self.sup = None;
            }
            let (c, t0, t1, si) = match &mut self.root {
                RootWalk::Done => return None,
                RootWalk::List(list) => {
                    let (t0, t1, si, c) = list.pop()?;
                    (c, t0, t1, si)
                }
                RootWalk::Dda(root) => {
                    let (c, t0, t1) = root.take(&self.ray)?;
                    let clipped = f.root.get(&c).and_then(|&si| {
                        let (lo, hi) = f.super_bounds[si as usize];
                        self.ray.clip(lo, hi, t0, t1).map(|(p, q)| (c, p, q, si))
                    });
                    match clipped {
                        Some(x) => x,
                        None => {
                            self.steps += 1;
                            continue;
                        }
                    }
                }
            };
            self.steps += 1;
            if t1 > t0 {
                let lo = c * (1 << SUPER_LOG2);
                let child = Dda::new(&self.ray, BLOCK_VOXELS_LOG2, t0, t1, lo, lo + IVec3::splat(1 << SUPER_LOG2));
                self.sup = Some((child, si));
            }
        }
    }
}

/// The part `[t0, t1]` of a ray inside one non-empty dual cell.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CellSeg {
    pub t0: f64,
    pub t1: f64,
    /// Index in `Field::values` of each of the cell's 8 corners, channel 0
    /// (`Field::corner_indices`).
    pub at: [usize; 8],
    /// Index-space position of the cell's (0,0,0) corner (a voxel centre).
    pub corner: IVec3,
}

/// Which channels make a dual cell non-empty for the walk.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CellFilter {
    /// Channel 0 (sigma_t when the field holds it first): transmittance.
    First,
    /// Any channel: radiance.
    Any,
}

/// Iterator over the non-empty dual cells of one dual leaf along a span.
///
/// It runs one cell ahead of what it has returned: when it hands out a
/// cell, it has already found the next non-empty one and asked the CPU to
/// prefetch that cell's 8 corners ([`Values::prefetch`](super::medium::values::Values::prefetch)). The caller's work on the
/// current cell (the cubics, the quadrature) then overlaps the memory
/// latency of the next one's values, which on a large volume is most of a
/// cell's cost (the corners of a ray's cells are rarely in cache). The
/// cells and their order are the same as without the lookahead.
pub struct CellWalker<'a> {
    field: &'a Field,
    ray: IndexRay,
    dda: Dda,
    leaf: u32,
    origin: IVec3,
    mask: &'a CellMask,
    ahead: Option<CellSeg>,
}

impl<'a> CellWalker<'a> {
    pub fn new(field: &'a Field, ray: IndexRay, span: LeafSpan, filter: CellFilter) -> Self {
        let origin = field.keys[span.leaf as usize] * (1 << LEAF_LOG2DIM);
        let dda = Dda::new(&ray, 0, span.t0, span.t1, origin, origin + IVec3::splat(1 << LEAF_LOG2DIM));
        let mask = match filter {
            CellFilter::First => &field.mask_first[span.leaf as usize],
            CellFilter::Any => &field.mask_any[span.leaf as usize],
        };
        let mut w = CellWalker { field, ray, dda, leaf: span.leaf, origin, mask, ahead: None };
        w.ahead = w.find();
        w
    }

    /// The next non-empty cell of the DDA, its corners prefetched.
    #[inline]
    fn find(&mut self) -> Option<CellSeg> {
        loop {
            let (c, t0, t1) = self.dda.take(&self.ray)?;
            let l = c - self.origin;
            if t1 > t0 && mask_has(self.mask, cell_bit(l.x, l.y, l.z)) {
                let at = self.field.corner_indices(self.leaf, l.x as usize, l.y as usize, l.z as usize);
                for &i in &at {
                    self.field.values.prefetch(i);
                }
                return Some(CellSeg { t0, t1, at, corner: c });
            }
        }
    }
}

impl Iterator for CellWalker<'_> {
    type Item = CellSeg;

    #[inline]
    fn next(&mut self) -> Option<CellSeg> {
        let seg = self.ahead?;
        self.ahead = self.find();
        Some(seg)
    }
}

/// Every non-empty dual-cell segment of `origin + t dir`, t in `[t0, t1]`, in order.
pub fn segments<'a>(
    field: &'a Field,
    origin: DVec3,
    dir: DVec3,
    t0: f64,
    t1: f64,
    filter: CellFilter,
) -> impl Iterator<Item = CellSeg> + 'a {
    let walker = LeafWalker::new(field, origin, dir, t0, t1);
    let ray = walker.ray;
    walker.flat_map(move |span| CellWalker::new(field, ray, span, filter))
}
