//! Emissive shadow rays: the aurora lighting the terrain.
//!
//! The volume's emission reaches the terrain along shadow rays
//! (`L = T * Li + Lvi`, the 2014 report, section 2.5). As an estimator, the
//! irradiance at a terrain point `x` with normal `n` is
//!
//! ```text
//! E(x) = int_V e(y) T(x,y) V(x,y) max(0, n . w) / |y - x|^2 dy,   w = (y - x) / |y - x|
//! ```
//!
//! (`T` the volume's transmittance, `V` the terrain's visibility), and the
//! Lambertian terrain sends `L = albedo / pi * E(x)` towards the camera.
//!
//! Sampling `y` in proportion to emission: pick voxel `v` with probability
//! `Y(e_v) / W` (`Y` the Rec.709 luminance, `W = sum_v Y(e_v)`), through a
//! two-level CDF (leaves by their total, then voxels within the leaf, found
//! from the totals at the leaf's mask words: [`EmissionSampler`]), then
//! offset `y` from the voxel centre by a tent-distributed amount `(1 - |u|)`
//! on `[-1, 1]` voxel along each axis: the trilinear basis function of that
//! voxel. The resulting density is
//! `p(y) = sum_v (Y(e_v) / W) tent(y - v) / h^3 = Y(e(y)) / (W h^3)`,
//! because trilinear interpolation is exactly `sum_v e_v tent(y - v)`: the
//! pdf is the interpolated emission luminance itself, known at `y` without
//! any bookkeeping, and non-zero wherever `e(y)` is (emission is >= 0). The
//! estimator `e(y) T V cos / (r^2 p(y)) = e(y) / Y(e(y)) * P * T V cos / r^2`,
//! with `P = W h^3 = int Y(e) dV`, is unbiased.
//!
//! Background radiance does not light the terrain: it is only what camera
//! rays see behind everything. With `[sky] extinction` each sample is also
//! dimmed by the air between the terrain point and the aurora
//! (`crate::physics::air_extinction::Extinction::towards_from`: the air-mass law with the
//! column above the point).
//!
//! The transmittance `T(x, y)` of a shadow ray is itself estimated, by ratio
//! tracking against the medium's largest sigma_t
//! ([`transmittance_ratio_tracking`]; Cramer 1978; Novak, Selle & Jarosz
//! 2014): an unbiased estimate from sigma_t at a few random points (about the
//! majorant optical depth `mu L`) instead of the exact optical depth
//! through every dual cell the ray crosses. Shadow rays go in every
//! direction, so each of those cells would be a cache miss; the estimate's
//! variance is small beside the emission sampling's. A ray whose majorant
//! optical depth through the field's box exceeds
//! [`RATIO_TRACKING_MAX_DEPTH`] takes the exact walk instead (bounded work
//! on extreme densities). The fixed-step integrator
//! (`Integration::FixedStep`, the Cycles-like comparison mode) keeps its
//! own marched transmittance.

use super::dda::{IndexRay, LeafWalker};
use super::march::optical_depth_along_ray;
use super::medium::field::Field;
use super::medium::values::{Stored, Values};
use super::medium::{Channel, Medium};
use super::settings::Integration;
use super::terrain::TerrainModel;
use crate::grid::{offset_to_local, Grid, Transform, LEAF_DIM, LEAF_MASK_WORDS, LEAF_NUM_VALUES};
use crate::util::colour::luminance;
use crate::util::fmath;
use glam::{DVec3, IVec3};
use rand::Rng;

/// Samples points of the volume in proportion to emitted luminance.
///
/// The sampler keeps, per emitting leaf, the running total of the voxels'
/// luminance at the leaf's end and at the end of each of its eight mask
/// words (64 voxels), not a total per voxel: a sample finds its leaf and
/// word by those, then walks the word's voxels in the medium, adding their
/// luminance to the word's starting total in the same order as the build
/// did. The totals met on the way are the same `f64`s a per-voxel list
/// would hold, so the voxel picked is the same, for 72 bytes a leaf instead
/// of 10 bytes an emitting voxel (190 MB on the default bake, most of it
/// fresh pages the build had to clear).
#[derive(Clone, Debug, PartialEq)]
pub struct EmissionSampler {
    transform: Transform,
    /// Where the emission is in the medium: its field and first channel.
    channel: Channel,
    leaf_origins: Vec<IVec3>,
    /// Per leaf, its block in the field's values.
    leaf_block: Vec<u32>,
    /// Inclusive prefix sums of leaf totals.
    leaf_cdf: Vec<f64>,
    /// Per leaf, the running total (the same sum as `leaf_cdf`) at the end
    /// of each of its mask words.
    word_cdf: Vec<[f64; LEAF_MASK_WORDS]>,
    /// `P = int Y(e) dV` of the scaled emission.
    pub power: f64,
}

/// The unscaled emission of voxel `at` (its first channel) of `v`, if its
/// luminance is positive: the voxels the sampler weighs. All-zero voxels
/// (most of a block's inactive ones) are passed over before their
/// luminance is taken.
#[inline(always)]
fn weight<S: Stored>(v: &[S], at: usize) -> Option<f64> {
    let e = &v[at..at + 3];
    if e.iter().all(|x| x.is_zero_bits()) {
        return None;
    }
    let w = luminance([e[0].to_f32() as f64, e[1].to_f32() as f64, e[2].to_f32() as f64]);
    (w > 0.0).then_some(w)
}

/// Walks voxels `range` (offsets) of block `block` in order (the
/// emission's first channel `ch`), adding each weight to the running total
/// `t`, until the total exceeds `x`: the total reached and the last voxel
/// with a weight (the one that crossed `x`, if one did). With `x` infinite,
/// the range's total and its last emitting voxel.
fn walk(field: &Field, ch: usize, block: usize, range: std::ops::Range<usize>, t: f64, x: f64) -> (f64, Option<usize>) {
    #[inline(always)]
    fn go<S: Stored>(v: &[S], channels: usize, at: usize, range: std::ops::Range<usize>, mut t: f64, x: f64) -> (f64, Option<usize>) {
        let mut last = None;
        for n in range {
            if let Some(w) = weight(v, at + n * channels) {
                t += w;
                last = Some(n);
                if t > x {
                    break;
                }
            }
        }
        (t, last)
    }
    let at = block * LEAF_NUM_VALUES * field.channels + ch;
    match &field.values {
        Values::F32(v) => go(v, field.channels, at, range, t, x),
        Values::Half(v) => go(v, field.channels, at, range, t, x),
    }
}

impl EmissionSampler {
    /// The sampler for an emission grid rendered through `medium` (built
    /// from it): the grid's leaves in the grid's order, their values read
    /// from the medium's blocks (the grid's active values, inactive voxels
    /// 0). None when nothing emits or `volume.emission_scale` is 0.
    pub fn new(emission: &Grid<[f32; 3]>, medium: &Medium) -> Option<EmissionSampler> {
        let c = medium.emission?;
        let f = &medium.fields[c.field];
        let order = emission.leaves().iter().map(|leaf| {
            let o = leaf.origin;
            let b = f
                .block_origins
                .binary_search_by_key(&(o.x, o.y, o.z), |k| (k.x, k.y, k.z))
                .expect("the medium holds every leaf of its grid");
            (o, b + 1)
        });
        EmissionSampler::from_blocks(medium, order)
    }

    /// [`EmissionSampler::new`] from the medium alone (the render from a
    /// file's records has no grid): the same sampler for a grid whose
    /// leaves are in (x, y, z) order (as every grid `crate::io::vdb::read`
    /// returns), since the medium's blocks are the grid's leaves in that
    /// order. `None` when nothing emits or `volume.emission_scale` is 0.
    pub fn from_medium(medium: &Medium) -> Option<EmissionSampler> {
        let c = medium.emission?;
        let f = &medium.fields[c.field];
        EmissionSampler::from_blocks(medium, f.block_origins.iter().enumerate().map(|(b, &o)| (o, b + 1)))
    }

    /// The sampler over the medium's emission, leaf by leaf in `order`
    /// (each its origin and its block): every voxel of positive luminance,
    /// weighted by it, summed in leaf order and offset order.
    fn from_blocks(medium: &Medium, order: impl Iterator<Item = (IVec3, usize)>) -> Option<EmissionSampler> {
        let c = medium.emission?;
        let f = &medium.fields[c.field];
        let max_leaves = f.live_blocks();
        let mut s = EmissionSampler {
            transform: f.transform,
            channel: c,
            leaf_origins: Vec::with_capacity(max_leaves),
            leaf_block: Vec::with_capacity(max_leaves),
            leaf_cdf: Vec::with_capacity(max_leaves),
            word_cdf: Vec::with_capacity(max_leaves),
            power: 0.0,
        };
        let mut total = 0.0;
        for (origin, block) in order {
            let mut any = false;
            let mut ends = [0.0; LEAF_MASK_WORDS];
            for (w, end) in ends.iter_mut().enumerate() {
                let (t, last) = walk(f, c.channel, block, w * 64..(w + 1) * 64, total, f64::INFINITY);
                total = t;
                any |= last.is_some();
                *end = total;
            }
            if any {
                s.leaf_origins.push(origin);
                s.leaf_block.push(block as u32);
                s.leaf_cdf.push(total);
                s.word_cdf.push(ends);
            }
        }
        s.set_scale(medium.emission_scale).then_some(s)
    }

    /// Sets `volume.emission_scale` in place: `P = scale * sum Y(e) h^3`.
    /// False (sampler unchanged) where the power would be zero or overflow
    /// (no sampler: the constructors give `None`, the caller drops it).
    pub fn set_scale(&mut self, emission_scale: f64) -> bool {
        let total = self.leaf_cdf.last().copied().unwrap_or(0.0);
        let h = self.transform.voxel_size;
        let power = emission_scale * total * h * h * h;
        let ok = total > 0.0 && power > 0.0 && power.is_finite();
        if ok {
            self.power = power;
        }
        ok
    }

    /// The voxel (offset in its leaf) of leaf `l` whose running total first
    /// exceeds `x` (the last emitting voxel of the leaf if none does): the
    /// word by its end total, then the word's voxels summed from its start.
    fn voxel_in_leaf(&self, field: &Field, l: usize, x: f64) -> usize {
        let ends = &self.word_cdf[l];
        let block = self.leaf_block[l] as usize;
        let ch = self.channel.channel;
        let w = ends.partition_point(|c| *c <= x);
        if w < LEAF_MASK_WORDS {
            let t = if w == 0 {
                if l == 0 {
                    0.0
                } else {
                    self.leaf_cdf[l - 1]
                }
            } else {
                ends[w - 1]
            };
            if let (_, Some(n)) = walk(field, ch, block, w * 64..(w + 1) * 64, t, x) {
                return n;
            }
        }
        walk(field, ch, block, 0..LEAF_NUM_VALUES, 0.0, f64::INFINITY).1.expect("an emitting leaf has an emitting voxel")
    }

    /// A point `y` (world space) with density `Y(e(y)) / power`; `medium`
    /// is the one the sampler was built from.
    pub fn sample<R: Rng + ?Sized>(&self, medium: &Medium, rng: &mut R) -> DVec3 {
        let total = *self.leaf_cdf.last().expect("non-empty sampler");
        let x = rng.random::<f64>() * total;
        let l = self.leaf_cdf.partition_point(|c| *c <= x).min(self.leaf_cdf.len() - 1);
        let lo = if l == 0 { 0.0 } else { self.leaf_cdf[l - 1] };
        let x = lo + rng.random::<f64>() * (self.leaf_cdf[l] - lo);
        let n = self.voxel_in_leaf(&medium.fields[self.channel.field], l, x);
        let v = self.leaf_origins[l] + offset_to_local(n);
        let u = DVec3::new(tent(rng.random()), tent(rng.random()), tent(rng.random()));
        self.transform.index_to_world(v.as_dvec3() + u)
    }
}

/// Maps a uniform `u` in [0,1) to the tent density `1 - |x|` on [-1, 1]
/// (inverse CDF).
#[inline]
pub fn tent(u: f64) -> f64 {
    if u < 0.5 {
        (2.0 * u).sqrt() - 1.0
    } else {
        1.0 - (2.0 * (1.0 - u)).sqrt()
    }
}

/// What a shadow ray needs.
pub struct ShadowScene<'a> {
    pub medium: &'a Medium,
    pub terrain: &'a TerrainModel,
    pub sampler: Option<&'a EmissionSampler>,
    pub integration: Integration,
    /// The air between the terrain and the volume (`crate::physics::air_extinction`).
    pub air: Option<&'a crate::physics::air_extinction::Extinction>,
}

/// Monte Carlo estimate of the irradiance `E(x)` (see the module doc) from
/// `samples` points, and the number of shadow rays traced.
pub fn estimate_irradiance<R: Rng + ?Sized>(scene: &ShadowScene<'_>, x: DVec3, n: DVec3, samples: usize, rng: &mut R) -> ([f64; 3], u64) {
    let Some(sampler) = scene.sampler else { return ([0.0; 3], 0) };
    let mut e_sum = [0.0; 3];
    let mut rays = 0;
    // Shadow rays start a hair off the surface (relative to the coordinates'
    // magnitude) so they do not hit the triangle they leave.
    let t_min = 1e-9 * (1.0 + x.abs().max_element());
    for _ in 0..samples {
        let y = sampler.sample(scene.medium, rng);
        let offset: f64 = rng.random();
        let e = scene.medium.emission_at(y);
        let lum = luminance(e);
        if !(lum > 0.0) {
            continue;
        }
        let w = y - x;
        let r2 = w.length_squared();
        let r = r2.sqrt();
        if !(r > 0.0) {
            continue;
        }
        let dir = w / r;
        let cos = n.dot(dir);
        if cos <= 0.0 {
            continue;
        }
        rays += 1;
        if scene.terrain.intersect(x, dir, t_min, r).is_some() {
            continue;
        }
        let t = match scene.integration {
            Integration::Exact => {
                let mu = scene.medium.sigma_t_majorant();
                transmittance_ratio_tracking(scene.medium, x, dir, r, mu, rng)
            }
            Integration::FixedStep(_) => optical_depth_along_ray(scene.medium, x, dir, r, scene.integration, offset).transmittance(),
        };
        let k = sampler.power * t * cos / (r2 * lum);
        // The aurora's light crosses the air above the terrain point: the
        // observer's air mass law at the point's altitude (an emission
        // point far above the layer, seen from `x`).
        let air = scene.air.map_or([1.0; 3], |a| a.towards_from(x, dir));
        for c in 0..3 {
            e_sum[c] += e[c] * k * air[c];
        }
    }
    let inv = 1.0 / samples.max(1) as f64;
    (e_sum.map(|v| v * inv), rays)
}

/// Majorant optical depth through the field's bounding box above which a
/// shadow ray takes the exact walk instead of ratio tracking (bounds the
/// lookups per ray; the default bake's rays stay far below it).
pub const RATIO_TRACKING_MAX_DEPTH: f64 = 32.0;

/// sigma_t of `field` (channel `ch`) at index-space point `u` inside dual
/// leaf `leaf` (trilinear in the leaf's dual cell holding `u`).
#[inline]
fn sigma_in_leaf(field: &Field, leaf: u32, ch: usize, u: DVec3) -> f64 {
    let origin = (field.keys[leaf as usize] * LEAF_DIM).as_dvec3();
    let l = (u - origin).floor().clamp(DVec3::ZERO, DVec3::splat(7.0));
    let f = u - origin - l;
    let at = field.corner_indices(leaf, l.x as usize, l.y as usize, l.z as usize);
    let scale = field.scale[ch];
    let v = |k: usize| field.values.get(at[k] + ch) as f64 * scale;
    let (fx, fy, fz) = (f.x.clamp(0.0, 1.0), f.y.clamp(0.0, 1.0), f.z.clamp(0.0, 1.0));
    let lerp = |a: f64, b: f64, t: f64| a + t * (b - a);
    let x00 = lerp(v(0), v(4), fx);
    let x01 = lerp(v(1), v(5), fx);
    let x10 = lerp(v(2), v(6), fx);
    let x11 = lerp(v(3), v(7), fx);
    lerp(lerp(x00, x10, fy), lerp(x01, x11, fy), fz)
}

/// Unbiased estimate of the transmittance `exp(-int_0^r sigma_t)` along
/// `x + s dir` by ratio tracking (Cramer 1978; Novak, Selle & Jarosz 2014,
/// "Residual ratio tracking"): tentative collisions form a Poisson process
/// of rate `mu >= sigma_t` on the occupied dual leaves (rate 0 elsewhere,
/// where sigma_t is 0), and the estimate is the product of `1 - sigma_t/mu`
/// over them. For a Poisson process of rate `mu(s)`,
/// `E[prod f(s_i)] = exp(-int mu (1 - f))`, which with `f = 1 - sigma_t/mu`
/// is the transmittance. It looks sigma_t up at about `mu L` points
/// (`L` the occupied length) instead of in every dual cell crossed: on the
/// default bake (sigma_t <= 0.04 per km, 0.5 km voxels) a few points per
/// shadow ray instead of hundreds of cells, each a cache miss on rays that
/// go in every direction. The price is variance: `Var/T^2 = exp(int sigma_t^2/mu) - 1
/// <= exp(tau) - 1`, small beside the emission sampling's own.
pub fn transmittance_ratio_tracking<R: Rng + ?Sized>(medium: &Medium, x: DVec3, dir: DVec3, r: f64, mu: f64, rng: &mut R) -> f64 {
    let Some(c) = medium.sigma_t else { return 1.0 };
    if !(mu > 0.0) {
        return 1.0;
    }
    let field = &medium.fields[c.field];
    if field.is_empty() {
        return 1.0;
    }
    // Expected lookups: at most mu times the length inside the field's box.
    // Past RATIO_TRACKING_MAX_DEPTH (or for a non-finite mu) the exact walk
    // is cheaper and bounded: it is used instead (also unbiased).
    let Some((a, b)) = IndexRay::new(field, x, dir).clip(field.lo, field.hi, 0.0, r) else { return 1.0 };
    if !(mu * (b - a) <= RATIO_TRACKING_MAX_DEPTH) {
        return optical_depth_along_ray(medium, x, dir, r, Integration::Exact, 0.5).transmittance();
    }
    let leaves = LeafWalker::new(field, x, dir, 0.0, r);
    let ray = leaves.ray;
    let mut t = 1.0;
    // Distance to the next tentative collision, in occupied length.
    let mut gap = -fmath::ln(1.0 - rng.random::<f64>()) / mu;
    for span in leaves {
        let mut pos = span.t0;
        while gap < span.t1 - pos {
            pos += gap;
            let sigma = sigma_in_leaf(field, span.leaf, c.channel, ray.at(pos));
            t *= 1.0 - (sigma / mu).min(1.0);
            if !(t > 0.0) {
                return 0.0;
            }
            gap = -fmath::ln(1.0 - rng.random::<f64>()) / mu;
        }
        gap -= span.t1 - pos;
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::{Grid, Transform};
    use rand::SeedableRng;

    /// The largest sigma_t value stored in `medium`, by scanning every
    /// value: the oracle of `Medium::sigma_t_majorant`.
    fn sigma_t_majorant(medium: &Medium) -> f64 {
        let Some(c) = medium.sigma_t else { return 0.0 };
        let f = &medium.fields[c.field];
        let n = f.channels;
        let unit = f.values.iter().skip(c.channel).step_by(n).fold(0.0f32, f32::max) as f64;
        let o = unit * f.scale[c.channel];
        assert_eq!(medium.sigma_t_majorant(), o, "the stored peak times the scale is the scan's maximum");
        o
    }

    /// The sampler's points equal those of the per-voxel list it replaced
    /// (the oracle below: every emitting voxel's running total, the voxel
    /// found by bisection), draw for draw, on a medium of 32-bit values and
    /// on one of half floats, with all-zero, zero-luminance and tiny voxels
    /// and leaves whose words end on the totals they start with; and its
    /// power is that list's total.
    #[test]
    fn the_sampler_picks_the_voxel_a_per_voxel_list_picks() {
        let tr = Transform::new(0.5, DVec3::ZERO);
        let mut r = rand_pcg::Pcg64::seed_from_u64(11);
        let mut e = Grid::new("emission", [0.0f32; 3], tr);
        for x in -9..23 {
            for y in 0..17 {
                for z in 0..9 {
                    let u = r.random::<f64>();
                    let v = if u < 0.4 {
                        [0.0; 3]
                    } else if u < 0.45 {
                        [1e-30, 0.0, 0.0]
                    } else {
                        [r.random::<f32>(), r.random::<f32>() * 2.0, r.random::<f32>() * 0.5]
                    };
                    let v = v.map(|c| half::f16::from_f32(c).to_f32());
                    e.set(IVec3::new(x, y, z), v);
                }
            }
        }
        let m32 = Medium::new(None, Some(&e), 1.0, 3.0).unwrap();
        let mut m16 = m32.clone();
        let f = &mut m16.fields[0];
        f.values = Values::Half(f.values.iter().map(crate::render::medium::values::f32_to_half).collect());
        // The oracle: the list as it was, from the grid's leaves.
        let (mut origins, mut leaf_cdf, mut starts, mut offsets, mut cdf) = (vec![], vec![], vec![0usize], vec![], vec![]);
        let mut total = 0.0;
        for leaf in e.leaves() {
            let before = offsets.len();
            for n in 0..crate::grid::LEAF_NUM_VALUES {
                let v = leaf.values[n];
                let w = luminance([v[0] as f64, v[1] as f64, v[2] as f64]);
                if leaf.is_active(n) && w > 0.0 {
                    total += w;
                    offsets.push(n);
                    cdf.push(total);
                }
            }
            if offsets.len() > before {
                origins.push(leaf.origin);
                leaf_cdf.push(total);
                starts.push(offsets.len());
            }
        }
        let oracle = |rng: &mut rand_pcg::Pcg64| {
            let x = rng.random::<f64>() * total;
            let l = leaf_cdf.partition_point(|c: &f64| *c <= x).min(leaf_cdf.len() - 1);
            let lo = if l == 0 { 0.0 } else { leaf_cdf[l - 1] };
            let x = lo + rng.random::<f64>() * (leaf_cdf[l] - lo);
            let (a, b) = (starts[l], starts[l + 1]);
            let k = a + cdf[a..b].partition_point(|c: &f64| *c <= x).min(b - a - 1);
            let v = origins[l] + offset_to_local(offsets[k]);
            let u = DVec3::new(tent(rng.random()), tent(rng.random()), tent(rng.random()));
            tr.index_to_world(v.as_dvec3() + u)
        };
        for m in [&m32, &m16] {
            let s = EmissionSampler::from_medium(m).unwrap();
            assert_eq!(s, EmissionSampler::new(&e, m).unwrap());
            assert_eq!(s.power, 3.0 * total * 0.125);
            let (mut a, mut b) = (rand_pcg::Pcg64::seed_from_u64(3), rand_pcg::Pcg64::seed_from_u64(3));
            for _ in 0..200_000 {
                assert_eq!(s.sample(m, &mut a), oracle(&mut b));
            }
        }
    }

    /// Ratio tracking averages to the exact transmittance (the walker's
    /// optical depth) on a lumpy medium, within 4 standard errors, on rays
    /// that cross it at several depths; and a medium without extinction
    /// gives exactly 1.
    #[test]
    fn ratio_tracking_is_unbiased() {
        let tr = Transform::new(0.5, DVec3::ZERO);
        let mut d = Grid::new("density", 0.0f32, tr);
        let mut e = Grid::new("emission", [0.0f32; 3], tr);
        let mut r = rand_pcg::Pcg64::seed_from_u64(7);
        for x in 0..24 {
            for y in 0..20 {
                for z in 0..16 {
                    let v = if r.random::<f64>() < 0.7 { r.random::<f32>() * 0.8 } else { 0.0 };
                    d.set(IVec3::new(x, y, z), v);
                    e.set(IVec3::new(x, y, z), [0.1, 0.2, 0.1]);
                }
            }
        }
        let m = Medium::new(Some(&d), Some(&e), 1.0, 1.0).unwrap();
        let mu = sigma_t_majorant(&m);
        assert!(mu > 0.7 && mu <= 0.8, "{mu}");
        for (o, to) in [
            (DVec3::new(-3.0, 4.1, 3.3), DVec3::new(14.0, 5.3, 4.9)),
            (DVec3::new(2.2, -5.0, 1.7), DVec3::new(9.1, 12.0, 6.5)),
            (DVec3::new(6.0, 5.0, -2.0), DVec3::new(6.3, 4.8, 3.0)),
        ] {
            let w = to - o;
            let (dir, len) = (w.normalize(), w.length());
            let exact = optical_depth_along_ray(&m, o, dir, len, Integration::Exact, 0.5).transmittance();
            let n = 20000;
            let (mut sum, mut sum2) = (0.0, 0.0);
            for _ in 0..n {
                let t = transmittance_ratio_tracking(&m, o, dir, len, mu, &mut r);
                assert!((0.0..=1.0).contains(&t));
                sum += t;
                sum2 += t * t;
            }
            let mean = sum / n as f64;
            let se = ((sum2 / n as f64 - mean * mean) / n as f64).sqrt();
            assert!(exact > 0.02 && exact < 0.98, "the ray must cross some medium: T = {exact}");
            assert!((mean - exact).abs() < 4.0 * se + 1e-12, "{mean} +- {se} vs {exact}");
        }
        // Past RATIO_TRACKING_MAX_DEPTH: the exact walk's value itself (no
        // endless lookups on an extreme density).
        let dense = Medium::new(Some(&d), Some(&e), 1e6, 1.0).unwrap();
        let (o, dir) = (DVec3::new(-3.0, 4.1, 3.3), DVec3::X);
        let exact = optical_depth_along_ray(&dense, o, dir, 20.0, Integration::Exact, 0.5).transmittance();
        let mu = sigma_t_majorant(&dense);
        assert_eq!(transmittance_ratio_tracking(&dense, o, dir, 20.0, mu, &mut r), exact);
        let none = Medium::new(None, Some(&e), 1.0, 1.0).unwrap();
        assert_eq!(sigma_t_majorant(&none), 0.0);
        let t = transmittance_ratio_tracking(&none, DVec3::ZERO, DVec3::X, 10.0, 0.0, &mut r);
        assert_eq!(t, 1.0);
    }
}
