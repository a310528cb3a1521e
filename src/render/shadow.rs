//! Emissive shadow rays: the aurora lighting the terrain.
//!
//! The 2014 report (section 2.5) added the volume's emission to shadow rays
//! (`L = T * Li + Lvi`) by calling the volume integrator on them. Done as an
//! estimator, the irradiance at a terrain point `x` with normal `n` is
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
//! two-level CDF (leaves by their total, then voxels within the leaf), then
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
//! rays see behind everything.

use super::march::optical_depth_along_ray;
use super::medium::Medium;
use super::terrain::TerrainModel;
use super::Integration;
use crate::grid::{offset_to_local, Grid, Transform};
use glam::{DVec3, IVec3};
use rand::Rng;

/// Rec.709 luminance weights.
pub const LUMA: [f64; 3] = [0.2126, 0.7152, 0.0722];

#[inline]
pub fn luminance(c: [f64; 3]) -> f64 {
    LUMA[0] * c[0] + LUMA[1] * c[1] + LUMA[2] * c[2]
}

/// Samples points of the volume in proportion to emitted luminance.
#[derive(Clone, Debug)]
pub struct EmissionSampler {
    transform: Transform,
    leaf_origins: Vec<IVec3>,
    /// Inclusive prefix sums of leaf totals.
    leaf_cdf: Vec<f64>,
    /// `voxels[leaf_start[l]..leaf_start[l+1]]` are leaf l's voxels.
    leaf_start: Vec<u32>,
    /// Offset of each sampled voxel within its leaf.
    voxel_offset: Vec<u16>,
    /// Inclusive prefix sums of voxel weights, over all voxels.
    voxel_cdf: Vec<f64>,
    /// `P = int Y(e) dV` of the scaled emission.
    pub power: f64,
}

impl EmissionSampler {
    /// None when nothing emits.
    pub fn new(emission: &Grid<[f32; 3]>, emission_scale: f64) -> Option<EmissionSampler> {
        let mut s = EmissionSampler {
            transform: emission.transform,
            leaf_origins: Vec::new(),
            leaf_cdf: Vec::new(),
            leaf_start: vec![0],
            voxel_offset: Vec::new(),
            voxel_cdf: Vec::new(),
            power: 0.0,
        };
        let mut total = 0.0;
        for leaf in emission.leaves() {
            let before = s.voxel_offset.len();
            for n in 0..crate::grid::LEAF_NUM_VALUES {
                if !leaf.is_active(n) {
                    continue;
                }
                let v = leaf.values[n];
                let w = luminance([v[0] as f64, v[1] as f64, v[2] as f64]);
                if w > 0.0 {
                    total += w;
                    s.voxel_offset.push(n as u16);
                    s.voxel_cdf.push(total);
                }
            }
            if s.voxel_offset.len() > before {
                s.leaf_origins.push(leaf.origin);
                s.leaf_cdf.push(total);
                s.leaf_start.push(s.voxel_offset.len() as u32);
            }
        }
        let h = emission.transform.voxel_size;
        s.power = emission_scale * total * h * h * h;
        (total > 0.0 && s.power > 0.0 && s.power.is_finite()).then_some(s)
    }

    /// [`EmissionSampler::new`] from the medium's emission channels instead
    /// of the grid (the render from a file's records has no grid): the
    /// same sampler for a grid whose leaves are in (x, y, z) order (as every
    /// grid `crate::vdb::read` returns), since the medium's blocks are the
    /// grid's leaves in that order with their values as stored, inactive
    /// voxels 0.
    /// `None` when nothing emits or `volume.emission_scale` is 0.
    pub fn from_medium(medium: &super::Medium) -> Option<EmissionSampler> {
        let c = medium.emission?;
        let f = &medium.fields[c.field];
        let mut s = EmissionSampler {
            transform: f.transform,
            leaf_origins: Vec::new(),
            leaf_cdf: Vec::new(),
            leaf_start: vec![0],
            voxel_offset: Vec::new(),
            voxel_cdf: Vec::new(),
            power: 0.0,
        };
        let mut total = 0.0;
        let per_block = super::medium::BLOCK_VALUES * f.channels;
        for (b, &origin) in f.block_origins.iter().enumerate() {
            let block = &f.values[(b + 1) * per_block..(b + 2) * per_block];
            let before = s.voxel_offset.len();
            for (n, v) in block.chunks_exact(f.channels).enumerate() {
                let v = &v[c.channel..c.channel + 3];
                let w = luminance([v[0] as f64, v[1] as f64, v[2] as f64]);
                if w > 0.0 {
                    total += w;
                    s.voxel_offset.push(n as u16);
                    s.voxel_cdf.push(total);
                }
            }
            if s.voxel_offset.len() > before {
                s.leaf_origins.push(origin);
                s.leaf_cdf.push(total);
                s.leaf_start.push(s.voxel_offset.len() as u32);
            }
        }
        let h = f.transform.voxel_size;
        s.power = medium.emission_scale * total * h * h * h;
        (total > 0.0 && s.power > 0.0 && s.power.is_finite()).then_some(s)
    }

    /// Sets `volume.emission_scale` in place: afterwards the sampler equals
    /// what [`EmissionSampler::new`] gives with that scale. False (sampler
    /// unchanged) where `new` would give `None` (a zero or overflowing
    /// power): the caller drops it.
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

    /// A point `y` (world space) with density `Y(e(y)) / power`.
    pub fn sample<R: Rng + ?Sized>(&self, rng: &mut R) -> DVec3 {
        let total = *self.leaf_cdf.last().expect("non-empty sampler");
        let x = rng.random::<f64>() * total;
        let l = self.leaf_cdf.partition_point(|c| *c <= x).min(self.leaf_cdf.len() - 1);
        let lo = if l == 0 { 0.0 } else { self.leaf_cdf[l - 1] };
        let x = lo + rng.random::<f64>() * (self.leaf_cdf[l] - lo);
        let (a, b) = (self.leaf_start[l] as usize, self.leaf_start[l + 1] as usize);
        let k = a + self.voxel_cdf[a..b].partition_point(|c| *c <= x).min(b - a - 1);
        let v = self.leaf_origins[l] + offset_to_local(self.voxel_offset[k] as usize);
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
}

/// Monte Carlo estimate of the irradiance `E(x)` (see the module doc) from
/// `samples` points, and the number of shadow rays traced.
pub fn estimate_irradiance<R: Rng + ?Sized>(
    scene: &ShadowScene<'_>,
    x: DVec3,
    n: DVec3,
    samples: usize,
    rng: &mut R,
) -> ([f64; 3], u64) {
    let Some(sampler) = scene.sampler else { return ([0.0; 3], 0) };
    let mut e_sum = [0.0; 3];
    let mut rays = 0;
    // Shadow rays start a hair off the surface (relative to the coordinates'
    // magnitude) so they do not hit the triangle they leave.
    let t_min = 1e-9 * (1.0 + x.abs().max_element());
    for _ in 0..samples {
        let y = sampler.sample(rng);
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
        let t = optical_depth_along_ray(scene.medium, x, dir, r, scene.integration, offset).transmittance();
        let k = sampler.power * t * cos / (r2 * lum);
        for c in 0..3 {
            e_sum[c] += e[c] * k;
        }
    }
    let inv = 1.0 / samples.max(1) as f64;
    (e_sum.map(|v| v * inv), rays)
}
