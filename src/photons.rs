//! Volumetric photon mapping: from the beams' photons to an emission grid by
//! kernel density estimation.
//!
//! The volume emission rate at x is the density estimate
//!
//! ```text
//! eta(x) = sum_i Phi_i K_r(|x - x_i|)      [photons km^-3 s^-1, per colour]
//! ```
//!
//! with `K_r` the normalised 3D Gaussian of standard deviation r (the kernel
//! radius), truncated at `cutoff * r` and renormalised by the Gaussian mass
//! inside the cutoff, so it still integrates to 1: twice the photons give
//! twice the emission. (The 2014 report divided by the sum of the weights, an
//! average colour that throws the photon density away; `report2014` keeps it
//! for comparison only.) Radiance is `eta / (4 pi)` per steradian; a Rayleigh
//! is a column emission rate, `1 R = 1e6 photons cm^-2 s^-1` = 4 pi times
//! radiance, so the 4 pi cancels and `eta / 1e19` is in kR per km of path
//! (1 kR = 1e9 photons cm^-2 s^-1 = 1e19 photons km^-2 s^-1). That is the
//! unit of the `emission` grid: Y = 1 is 1 kR of 557.7 nm per km.
//!
//! **Segment kernels** (`photons.kernel = "segment"`, default). A beam step
//! deposits its power along the segment from `a` to `b` (length L, unit
//! direction d), not at one point: the photon is a short photon beam
//! (Jarosz, Nowrouzezahrai, Sadeghi & Jensen, "A Comprehensive Theory of
//! Volumetric Radiance Estimation Using Photon Points and Beams", ACM TOG
//! 30(1), 2011), and its kernel is the Gaussian convolved with the uniform
//! density `1/L` on the segment. Write `x - a = s d + p` (s along the
//! segment, p perpendicular to it). The Gaussian factors into `phi_2(p)
//! phi_1(s - t)` for a centre at `a + t d`, so
//!
//! ```text
//! K_seg(x) = (1/L) int_0^L G_r(x - a - t d) dt
//!          = exp(-|p|^2 / 2r^2) / (2 pi r^2)                (across)
//!            * [erf(s / (sqrt2 r)) - erf((s - L) / (sqrt2 r))] / (2 L)   (along)
//! ```
//!
//! (the along factor is `(Phi(s/r) - Phi((s-L)/r)) / L`, Phi the normal
//! CDF). It is truncated where the distance from x to the segment reaches
//! `cutoff * r` (a capsule, the ball of the point kernel swept along the
//! segment) and renormalised by its mass inside, `M_seg(lambda)`, lambda =
//! L / r. With u = s / r and `g(u) = (Phi(u) - Phi(u - lambda)) / lambda` the
//! along density, the capsule splits into its cylinder (0 <= u <= lambda,
//! where the across factor holds `1 - exp(-c^2/2)` of its mass inside radius
//! c) and two half balls (u < 0 and, by symmetry, u > lambda, where the
//! across radius is `sqrt(c^2 - u^2)`):
//!
//! ```text
//! M_seg(lambda) = (1 - e^{-c^2/2}) A(lambda) + 2 int_{-c}^0 g(u) (1 - e^{-(c^2 - u^2)/2}) du
//! A(lambda)     = int_0^lambda g = erf(lambda / sqrt2) - (2 / lambda) (phi(0) - phi(lambda))
//! ```
//!
//! (A from `int Phi = u Phi(u) + phi(u)`; the half-ball integral has no
//! elementary form and is integrated numerically once per bake into a table
//! over lambda, [`SegmentMass`]). As L -> 0, g -> phi, A -> 0 and M_seg ->
//! `int_{-c}^c phi(u) (1 - e^{-(c^2-u^2)/2}) du = M(c)`, the point kernel's
//! mass: a zero-length segment is the point kernel, exactly (the gather
//! takes the point kernel for L = 0, and the midpoint's below lambda =
//! 0.004, where erf's f32 cancellation, 3e-7 / (0.8 lambda) relative, would
//! cost more than the midpoint kernel's difference, `M_seg(lambda) / M(c) -
//! 1 ~ 0.06 lambda` for c = 2.5: both below 1e-4 there). Each segment's kernel integrates to its
//! power, as each point's does. Against points at the deflections, the
//! estimate no longer ripples along the beam path at the step length.
//! `photons.kernel = "point"` puts each step's power at its end (the
//! deflection point), the estimator before segments, kept for comparison.
//!
//! The kernel radius is perturbed by the report's medium-frequency 2D noise,
//! taken at the point's field-line foot so the variation follows B (rays).
//!
//! Gather methods (`photons.gather`):
//! - `kdtree`: a balloon estimator, radius r(x) at the voxel. One
//!   kiddo range query per 8^3 leaf finds the photons that can reach it; each
//!   voxel then sums its photons' kernels in photon-index order. The tree
//!   holds segment midpoints; queries widen by the longest half segment.
//! - `splat` (default): a sample-point estimator, radius r(x_i) at the photon. Photons
//!   are binned per leaf (in photon order), each adds its kernel to the
//!   leaf's voxels within its cutoff. No tree. A segment takes r at its
//!   midpoint. How it is evaluated (the same estimate, for speed: the
//!   default bake's gather went from 7.6 to about 3 CPU seconds,
//!   `examples/gather_bench.rs`): each photon's kernel parameters once
//!   (not once per leaf: the radius noise is a Perlin lookup), and its
//!   leaves from its own reach `c r_i` rather than the largest radius's;
//!   the candidate leaves and the bins in one go on a dense box of leaves
//!   (counts, prefix sum, scatter in photon order: [`bin_photons_dense`];
//!   a stable counting sort through hash maps for boxes too large); per
//!   leaf, a segment's closed form over whole z-rows of 8 voxels (or half
//!   rows of 4 where the leaf's box holds one half) without branches (the
//!   capsule test selects lanes, rows the capsule misses are skipped),
//!   compiled for AVX2 where the CPU has it (runtime check: the same IEEE
//!   operations, so the same bits, 8 lanes in one instruction), the across
//!   factor by [`exp_neg_f32`] and the along factor's two erfs by table
//!   ([`erf_lut`]) with the index arithmetic vectorised; scratch sums
//!   reused per thread. The per-voxel arithmetic is that of the scalar
//!   path, so the tolerances below hold as they are. The merged runs and
//!   kernels ([`GatherInput`]) can be made once for several gathers of
//!   the same photons (the preview's coarse and refined pictures).
//! - `report2014`: the report's estimate, a kernel-weighted *average*
//!   `sum(w Phi) / sum(w)` (w the unnormalised Gaussian) of photons binned in a
//!   uniform grid (the leaves). Not a density: its magnitude is a photon's
//!   power, not comparable with the two others. For comparison only.
//!
//! Both take the same field to the f64 form (tests); the splat needs no tree
//! and gathered the default scene's segments in about two thirds of the
//! kd-tree's CPU time (`examples/smoothness.rs --gather`), so it is the
//! default.
//!
//! **Merged runs.** Before either gather, straight and evenly lit runs of a
//! beam's contiguous steps become one segment each ([`merge_segments`],
//! with its error bounds): a short segment's kernel is mostly its two end
//! caps, so one capsule per run instead of one per step cuts the voxels
//! evaluated. The merge runs in parallel over chunks cut between beams,
//! where no run can continue (the same list as one pass).
//!
//! Every per-voxel sum runs over photons in ascending index order, so the
//! grids are identical whatever the thread count.

use crate::beams::Photon;
use crate::grid::{leaf_offset, Grid, Leaf, Transform, LEAF_DIM, LEAF_NUM_VALUES};
use crate::progress::Progress;
use crate::rng;
use crate::scene::GatherMethod;
use glam::{DVec3, IVec3};
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use noise::Perlin;
use rayon::prelude::*;

/// Photons km^-2 s^-1 in one kR.
pub const PHOTONS_PER_KM2_S_PER_KR: f64 = 1e19;

/// Mass of the standard 3D Gaussian inside radius `c` (in standard
/// deviations): `erf(c / sqrt 2) - sqrt(2 / pi) c exp(-c^2 / 2)`, computed by
/// composite Simpson integration of `4 pi r^2 phi(r)` (4096 intervals: error
/// far below 1e-12 for c <= 6).
pub fn gaussian_mass_inside(c: f64) -> f64 {
    let n = 4096;
    let h = c / n as f64;
    let f = |r: f64| 4.0 * std::f64::consts::PI * r * r * (-0.5 * r * r).exp() / (2.0 * std::f64::consts::PI).powf(1.5);
    let mut s = f(0.0) + f(c);
    for k in 1..n {
        s += f(k as f64 * h) * if k % 2 == 1 { 4.0 } else { 2.0 };
    }
    s * h / 3.0
}

/// Standard normal density.
#[inline]
fn phi(u: f64) -> f64 {
    (-0.5 * u * u).exp() / (2.0 * std::f64::consts::PI).sqrt()
}

/// Standard normal CDF (erfc keeps the lower tail's relative accuracy).
#[inline]
fn big_phi(u: f64) -> f64 {
    0.5 * libm::erfc(-u / std::f64::consts::SQRT_2)
}

/// `A(lambda) = int_0^lambda (Phi(u) - Phi(u - lambda)) / lambda du`: the
/// share of the segment kernel's along-axis mass over the segment itself.
fn along_mass_inside(lambda: f64) -> f64 {
    libm::erf(lambda / std::f64::consts::SQRT_2) - 2.0 / lambda * (phi(0.0) - phi(lambda))
}

/// `int_{-c}^0 h(u) (1 - e^{-(c^2 - u^2)/2}) du` by composite Simpson (128
/// intervals; the integrand is smooth on [-c, 0], error below 1e-9).
fn half_ball(c: f64, h: impl Fn(f64) -> f64) -> f64 {
    let n = 128;
    let dh = c / n as f64;
    let f = |u: f64| h(u) * (1.0 - (-0.5 * (c * c - u * u)).exp());
    let mut s = f(-c) + f(0.0);
    for k in 1..n {
        s += f(-c + k as f64 * dh) * if k % 2 == 1 { 4.0 } else { 2.0 };
    }
    s * dh / 3.0
}

/// `M_seg(lambda)`: mass of the standard Gaussian convolved with a segment of
/// length `lambda` (in standard deviations) inside the capsule of radius `c`
/// around the segment (derived in the module documentation). `M_seg(0) =
/// M(c)`.
pub fn segment_mass_inside(c: f64, lambda: f64) -> f64 {
    if lambda <= 0.0 {
        return gaussian_mass_inside(c);
    }
    let g = |u: f64| (big_phi(u) - big_phi(u - lambda)) / lambda;
    (1.0 - (-0.5 * c * c).exp()) * along_mass_inside(lambda) + 2.0 * half_ball(c, g)
}

/// [`segment_mass_inside`] for one cutoff, tabulated over lambda in [0, 16]
/// at steps of 1/256 and interpolated linearly (|M_seg''| is below 0.1, so
/// the error is below (1/256)^2 / 8 * 0.1 = 2e-7, plus the f32 storage's
/// 6e-8); beyond 16, `Phi(u - lambda)` is below 1e-57 on [-c, 0] and
/// the half balls are `h_inf / lambda`, exactly.
#[derive(Clone, Debug)]
pub struct SegmentMass {
    pub cutoff: f64,
    table: Vec<f32>,
    /// 1 / table, for the gather.
    inv: Vec<f32>,
    h_inf: f64,
}

impl SegmentMass {
    const STEPS_PER_UNIT: f64 = 256.0;
    const LAMBDA_MAX: f64 = 16.0;

    pub fn new(cutoff: f64) -> Self {
        let n = (Self::LAMBDA_MAX * Self::STEPS_PER_UNIT) as usize;
        // In parallel: each entry is a pure function of its lambda (some
        // 500 k erfc calls in all, once per gather).
        let table = (0..=n).into_par_iter().map(|k| segment_mass_inside(cutoff, k as f64 / Self::STEPS_PER_UNIT) as f32).collect();
        let table: Vec<f32> = table;
        let inv = table.iter().map(|&m| 1.0 / m).collect();
        Self { cutoff, table, inv, h_inf: half_ball(cutoff, big_phi) }
    }

    /// 1 / M_seg(lambda) in f32, interpolated linearly in the table of
    /// reciprocals (1/M is as smooth as M, M near 1: the same error bound).
    #[inline(always)]
    pub fn inv_mass_f32(&self, lambda: f32) -> f32 {
        if lambda as f64 >= Self::LAMBDA_MAX {
            return (1.0 / self.mass(lambda as f64)) as f32;
        }
        let x = lambda * Self::STEPS_PER_UNIT as f32;
        let k = x as usize;
        let f = x - k as f32;
        self.inv[k] + f * (self.inv[k + 1] - self.inv[k])
    }

    /// M_seg(lambda).
    #[inline]
    pub fn mass(&self, lambda: f64) -> f64 {
        if lambda >= Self::LAMBDA_MAX {
            let c = self.cutoff;
            return (1.0 - (-0.5 * c * c).exp()) * along_mass_inside(lambda) + 2.0 * self.h_inf / lambda;
        }
        let x = lambda * Self::STEPS_PER_UNIT;
        let k = x as usize;
        let f = x - k as f64;
        self.table[k] as f64 * (1.0 - f) + self.table[k + 1] as f64 * f
    }
}

/// Entries of the erf table: erf(k / 1024) for k = 0..=4097.
const ERF_LUT_LEN: usize = ERF_LUT_STEPS * 4 + 2;

/// erf on [0, 4] at steps of 1/1024, f32, for [`erf_lut`].
fn erf_table() -> &'static [f32; ERF_LUT_LEN] {
    static T: std::sync::OnceLock<[f32; ERF_LUT_LEN]> = std::sync::OnceLock::new();
    T.get_or_init(|| std::array::from_fn(|k| libm::erf(k as f64 / ERF_LUT_STEPS as f64) as f32))
}

const ERF_LUT_STEPS: usize = 1024;

/// erf in f32 by linear interpolation in a table (steps h = 1/1024 on [0,
/// 4], 1 beyond): error at most h^2 / 8 max|erf''| = 1.2e-7 (|erf''| <=
/// 0.97), plus f32 rounding and erfc(4) = 1.5e-8 beyond. The gather's
/// segment kernel takes two per voxel and photon; a lookup costs far less
/// than a rational approximation's exponential and division (Abramowitz &
/// Stegun 7.1.26, the other f32 erf this module once had, measured slower).
/// The cell index is `|x| / h - 1/2` rounded to nearest by the `1.5 * 2^23`
/// trick of [`exp_neg_f32`] (floor of `|x| / h`, or one less at a cell
/// boundary, where the interpolation weight is then 1: the same value),
/// clamped to the table: no saturating float-to-integer conversion and no
/// bounds check in the gather's inner loop.
#[inline(always)]
pub fn erf_lut(table: &[f32; ERF_LUT_LEN], x: f32) -> f32 {
    const MAGIC: f32 = 12_582_912.0;
    let ax = (x.abs() * ERF_LUT_STEPS as f32).min((ERF_LUT_STEPS * 4) as f32);
    let t = (ax - 0.5) + MAGIC;
    let k = ((t.to_bits() as i32 - MAGIC.to_bits() as i32).max(0) as usize).min(ERF_LUT_LEN - 2);
    let f = ax - k as f32;
    let v = table[k] + f * (table[k + 1] - table[k]);
    v.copysign(x)
}

/// [`erf_lut`] at N arguments (4 or 8: half or whole z-rows), staged so
/// the index and interpolation arithmetic vectorise (only the 2N table
/// reads are scalar); the same operations per lane, so the same values.
#[inline(always)]
fn erf_lut_lanes<const N: usize>(table: &[f32; ERF_LUT_LEN], x: &[f32; N]) -> [f32; N] {
    const MAGIC: f32 = 12_582_912.0;
    let (mut k, mut f) = ([0usize; N], [0.0f32; N]);
    for j in 0..N {
        let ax = (x[j].abs() * ERF_LUT_STEPS as f32).min((ERF_LUT_STEPS * 4) as f32);
        let t = (ax - 0.5) + MAGIC;
        let kj = (t.to_bits() as i32 - MAGIC.to_bits() as i32).max(0).min(ERF_LUT_LEN as i32 - 2);
        k[j] = kj as usize;
        f[j] = ax - kj as f32;
    }
    let (mut a, mut b) = ([0.0f32; N], [0.0f32; N]);
    for j in 0..N {
        let kj = k[j].min(ERF_LUT_LEN - 2);
        (a[j], b[j]) = (table[kj], table[kj + 1]);
    }
    let mut v = [0.0f32; N];
    for j in 0..N {
        v[j] = (a[j] + f[j] * (b[j] - a[j])).copysign(x[j]);
    }
    v
}

/// Below this lambda = L / r a segment is gathered as a point at its
/// midpoint (see the module documentation).
pub const MIDPOINT_LAMBDA: f64 = 0.004;

/// The segment kernel of `kernel` (its r and cutoff) for the segment a-b at
/// x, km^-3, in f64 (the oracle of the gathers): the point kernel at `a` for
/// a = b, else the formula of the module documentation, mass computed
/// afresh.
pub fn segment_kernel(kernel: &Kernel, a: DVec3, b: DVec3, x: DVec3) -> f64 {
    let len = a.distance(b);
    if len == 0.0 {
        return kernel.eval_d2(a.distance_squared(x));
    }
    segment_kernel_with_mass(kernel, segment_mass_inside(kernel.cutoff, len / kernel.r), a, b, x)
}

/// [`segment_kernel`] for a != b given `m = M_seg(|b - a| / r)`.
pub fn segment_kernel_with_mass(kernel: &Kernel, m: f64, a: DVec3, b: DVec3, x: DVec3) -> f64 {
    let len = a.distance(b);
    let d = (b - a) / len;
    let w = x - a;
    let s = w.dot(d);
    let perp2 = (w.length_squared() - s * s).max(0.0);
    let dist2 = if s < 0.0 { w.length_squared() } else if s > len { x.distance_squared(b) } else { perp2 };
    if dist2 >= kernel.reach2 {
        return 0.0;
    }
    let r = kernel.r;
    let k = 1.0 / std::f64::consts::SQRT_2 / r;
    (-perp2 * kernel.inv_2r2).exp() / (2.0 * std::f64::consts::PI * r * r) * (libm::erf(s * k) - libm::erf((s - len) * k))
        / (2.0 * len * m)
}

/// The truncated, renormalised 3D Gaussian kernel of standard deviation `r`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Kernel {
    pub r: f64,
    pub cutoff: f64,
    /// 1 / ((2 pi)^(3/2) r^3 M(cutoff)).
    norm: f64,
    inv_2r2: f64,
    /// (cutoff r)^2.
    reach2: f64,
}

impl Kernel {
    /// `mass` is [`gaussian_mass_inside`]`(cutoff)`, passed in so a kernel
    /// per voxel costs no integration.
    #[inline]
    pub fn with_mass(r: f64, cutoff: f64, mass: f64) -> Self {
        let norm = 1.0 / ((2.0 * std::f64::consts::PI).powf(1.5) * r * r * r * mass);
        Self { r, cutoff, norm, inv_2r2: 0.5 / (r * r), reach2: (cutoff * r) * (cutoff * r) }
    }

    pub fn new(r: f64, cutoff: f64) -> Self {
        Self::with_mass(r, cutoff, gaussian_mass_inside(cutoff))
    }

    /// Support radius, km.
    pub fn reach(&self) -> f64 {
        self.cutoff * self.r
    }

    /// K(d) for squared distance `d2` (km^-3); exactly 0 beyond the cutoff.
    #[inline]
    pub fn eval_d2(&self, d2: f64) -> f64 {
        if d2 < self.reach2 {
            self.norm * (-d2 * self.inv_2r2).exp()
        } else {
            0.0
        }
    }

    /// The unnormalised weight exp(-d^2 / 2r^2) inside the cutoff (report2014).
    #[inline]
    fn weight_d2(&self, d2: f64) -> f64 {
        if d2 < self.reach2 {
            (-d2 * self.inv_2r2).exp()
        } else {
            0.0
        }
    }
}

/// Kernel radius as a function of position: `base * (1 + amp * n)`, n a 2D
/// Perlin noise in [-1, 1] of the field-line foot (x, y) at altitude `z_ref`,
/// at `freq` cycles per km. Bounded by `base * (1 + amp)`.
#[derive(Clone, Debug)]
pub struct RadiusField {
    pub base: f64,
    pub amp: f64,
    pub freq: f64,
    pub b: DVec3,
    pub z_ref: f64,
    noise: Perlin,
}

impl RadiusField {
    pub fn new(base: f64, amp: f64, freq: f64, b: DVec3, z_ref: f64, seed: &[u64]) -> Self {
        let mut parts = seed.to_vec();
        parts.push(rng::tag::RADIUS_NOISE);
        Self { base, amp, freq, b, z_ref, noise: rng::perlin(&parts) }
    }

    /// A constant radius.
    pub fn constant(r: f64) -> Self {
        Self { base: r, amp: 0.0, freq: 0.0, b: DVec3::NEG_Z, z_ref: 0.0, noise: Perlin::new(0) }
    }

    pub fn max(&self) -> f64 {
        self.base * (1.0 + self.amp)
    }

    #[inline]
    pub fn radius(&self, p: DVec3) -> f64 {
        if self.amp == 0.0 {
            return self.base;
        }
        let foot = p + self.b * ((self.z_ref - p.z) / self.b.z);
        self.base * (1.0 + self.amp * rng::noise2(&self.noise, foot.x * self.freq, foot.y * self.freq))
    }
}

#[inline]
fn pos(p: &Photon) -> DVec3 {
    DVec3::new(p.position[0] as f64, p.position[1] as f64, p.position[2] as f64)
}

#[inline]
fn end(p: &Photon) -> DVec3 {
    DVec3::new(p.end[0] as f64, p.end[1] as f64, p.end[2] as f64)
}

/// The photon's kernel at x (point or segment), f64.
#[inline]
fn photon_kernel(p: &Photon, kernel: &Kernel, x: DVec3) -> f64 {
    if p.is_point() {
        kernel.eval_d2(pos(p).distance_squared(x))
    } else {
        segment_kernel(kernel, pos(p), end(p), x)
    }
}

/// Half the longest segment, km (0 for point photons).
pub fn max_half_length(photons: &[Photon]) -> f64 {
    photons.par_iter().map(|p| 0.5 * pos(p).distance(end(p))).reduce(|| 0.0, f64::max)
}

/// Photons with a kd-tree over their positions (kiddo's immutable tree:
/// built once, queried many times).
pub struct PhotonMap<'a> {
    pub photons: &'a [Photon],
    tree: ImmutableKdTree<f32, 3>,
    /// Half the longest segment: the tree holds midpoints.
    max_half: f64,
}

impl<'a> PhotonMap<'a> {
    pub fn new(photons: &'a [Photon]) -> Self {
        let pts: Vec<[f32; 3]> = photons.iter().map(|p| (0.5 * (pos(p) + end(p))).as_vec3().to_array()).collect();
        Self { photons, tree: ImmutableKdTree::new_from_slice(&pts), max_half: max_half_length(photons) }
    }

    /// Indices of the photons whose segment comes within `radius` km of `x`
    /// (a superset: midpoints within `radius` plus the longest half segment,
    /// and the f32 query radius widened by a relative 1e-5 to cover
    /// rounding), ascending.
    pub fn within(&self, x: DVec3, radius: f64) -> Vec<usize> {
        if self.photons.is_empty() {
            return Vec::new();
        }
        let q = [x.x as f32, x.y as f32, x.z as f32];
        let radius = radius + self.max_half;
        let r = (radius * (1.0 + 1e-5) + 1e-5 * x.abs().max_element()) as f32;
        let mut idx: Vec<usize> =
            self.tree.within_unsorted::<SquaredEuclidean>(&q, r * r).into_iter().map(|n| n.item as usize).collect();
        idx.sort_unstable();
        idx
    }

    /// eta(x) = sum_i Phi_i K_i(x) (the point or segment kernel of photon
    /// i), photons km^-3 s^-1 per colour, through the tree. Exactly zero (never NaN) with no photon in reach.
    pub fn estimate(&self, x: DVec3, kernel: &Kernel) -> [f64; 3] {
        let mut acc = [0.0; 3];
        for i in self.within(x, kernel.reach()) {
            let p = &self.photons[i];
            let w = photon_kernel(p, kernel, x);
            for (a, &c) in acc.iter_mut().zip(&p.power) {
                *a += w * c as f64;
            }
        }
        acc
    }
}

/// The same estimate by brute force over every photon (the oracle).
pub fn estimate_brute_force(photons: &[Photon], x: DVec3, kernel: &Kernel) -> [f64; 3] {
    let mut acc = [0.0; 3];
    for p in photons {
        let w = photon_kernel(p, kernel, x);
        if w > 0.0 {
            for (a, &c) in acc.iter_mut().zip(&p.power) {
                *a += w * c as f64;
            }
        }
    }
    acc
}

/// Origins (index space) of the leaves within `reach` km of some photon's
/// segment:
/// every voxel centre a kernel of that reach can touch lies in one of them.
/// Sorted by (x, y, z), the grid's leaf order.
pub fn candidate_leaves(photons: &[Photon], voxel_size: f64, reach: f64) -> Vec<IVec3> {
    candidate_leaves_by(photons, voxel_size, |_| reach)
}

/// [`candidate_leaves`] with a reach per photon, `reach(i)` km for photon
/// i (the splat's: `cutoff r_i`, not the largest r's).
pub fn candidate_leaves_by(photons: &[Photon], voxel_size: f64, reach: impl Fn(usize) -> f64 + Sync) -> Vec<IVec3> {
    const CHUNK: usize = 1 << 16;
    // Per chunk a set of origins (each leaf once per chunk however many
    // photons reach it), then one sort of the chunks' few: deterministic.
    let mut keys: Vec<(i32, i32, i32)> = photons
        .par_chunks(CHUNK)
        .enumerate()
        .flat_map_iter(|(c, chunk)| {
            let mut set = crate::grid::OriginMap::<()>::default();
            let mut last: Option<(IVec3, IVec3)> = None;
            for (j, p) in chunk.iter().enumerate() {
                let range = leaf_range(p, voxel_size, reach(c * CHUNK + j));
                if last == Some(range) {
                    continue; // neighbouring photons of a beam share leaves
                }
                last = Some(range);
                for_each_leaf(range, |o| {
                    set.insert(o, ());
                });
            }
            set.into_keys().map(|o| (o.x, o.y, o.z))
        })
        .collect();
    keys.par_sort_unstable();
    keys.dedup();
    keys.into_iter().map(|(x, y, z)| IVec3::new(x, y, z)).collect()
}

/// `ceil` per component as integers, by truncation and a correction
/// (x86-64's baseline has no rounding instruction, so `f64::ceil` is a libm
/// call; the gather takes six per photon and leaf). Exact for |x| < 2^31;
/// NaN gives 0, as `as` does.
#[inline(always)]
fn ceil_i(v: DVec3) -> IVec3 {
    let c = |x: f64| {
        let i = x as i32;
        i + ((i as f64) < x) as i32
    };
    IVec3::new(c(v.x), c(v.y), c(v.z))
}

/// `floor` per component as integers (see [`ceil_i`]).
#[inline(always)]
fn floor_i(v: DVec3) -> IVec3 {
    let f = |x: f64| {
        let i = x as i32;
        i - ((i as f64) > x) as i32
    };
    IVec3::new(f(v.x), f(v.y), f(v.z))
}

/// Leaf origins (first, last) covering the voxel centres within `reach` of
/// the photon's segment (its bounding box widened by `reach`).
#[inline]
fn leaf_range(p: &Photon, voxel_size: f64, reach: f64) -> (IVec3, IVec3) {
    let (a, b) = (pos(p), end(p));
    let lo = ceil_i((a.min(b) - DVec3::splat(reach)) / voxel_size);
    let hi = floor_i((a.max(b) + DVec3::splat(reach)) / voxel_size);
    (crate::grid::leaf_origin(lo), crate::grid::leaf_origin(hi))
}

#[inline]
fn for_each_leaf((lo, hi): (IVec3, IVec3), mut f: impl FnMut(IVec3)) {
    let mut x = lo.x;
    while x <= hi.x {
        let mut y = lo.y;
        while y <= hi.y {
            let mut z = lo.z;
            while z <= hi.z {
                f(IVec3::new(x, y, z));
                z += LEAF_DIM;
            }
            y += LEAF_DIM;
        }
        x += LEAF_DIM;
    }
}

/// Photon indices per candidate leaf: leaf k's photons are
/// `photons[start[k]..start[k + 1]]`, ascending.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Bins {
    pub start: Vec<usize>,
    pub photons: Vec<u32>,
}

impl Bins {
    /// The photons of leaf `k`.
    #[inline]
    pub fn get(&self, k: usize) -> &[u32] {
        &self.photons[self.start[k]..self.start[k + 1]]
    }
}

/// Photon indices per candidate leaf, each list ascending: the uniform
/// grid of `splat` and `report2014`.
///
/// (leaf, photon) pairs from chunks of photons in parallel, collected in
/// photon order, then a stable counting sort by leaf (count, prefix sum,
/// scatter): each leaf's list is in photon order whatever the thread count.
pub fn bin_photons(photons: &[Photon], leaves: &[IVec3], voxel_size: f64, reach: f64) -> Bins {
    bin_photons_by(photons, leaves, voxel_size, |_| reach)
}

/// [`bin_photons`] with a reach per photon (see [`candidate_leaves_by`]).
pub fn bin_photons_by(photons: &[Photon], leaves: &[IVec3], voxel_size: f64, reach: impl Fn(usize) -> f64 + Sync) -> Bins {
    let index: crate::grid::OriginMap<u32> = leaves.iter().enumerate().map(|(i, &o)| (o, i as u32)).collect();
    const CHUNK: usize = 1 << 14;
    let pairs: Vec<(u32, u32)> = photons
        .par_chunks(CHUNK)
        .enumerate()
        .flat_map_iter(|(c, chunk)| {
            let mut v = Vec::with_capacity(chunk.len() * 2);
            for (j, p) in chunk.iter().enumerate() {
                let i = (c * CHUNK + j) as u32;
                for_each_leaf(leaf_range(p, voxel_size, reach(i as usize)), |o| {
                    if let Some(&k) = index.get(&o) {
                        v.push((k, i));
                    }
                });
            }
            v
        })
        .collect();
    let mut start = vec![0usize; leaves.len() + 1];
    for &(k, _) in &pairs {
        start[k as usize + 1] += 1;
    }
    for k in 0..leaves.len() {
        start[k + 1] += start[k];
    }
    let mut next = start.clone();
    let mut out = vec![0u32; pairs.len()];
    for &(k, i) in &pairs {
        out[next[k as usize]] = i;
        next[k as usize] += 1;
    }
    Bins { start, photons: out }
}

/// Largest leaf box (in leaves) that [`bin_photons_dense`] takes: 4 M
/// cells, 32 MB of counts and slots. Beyond it the hashed path.
pub const DENSE_BIN_CELLS: u64 = 1 << 22;

/// [`candidate_leaves_by`] and [`bin_photons_by`] at once, on a dense box
/// of leaves rather than hash maps: the same leaves (sorted by (x, y, z),
/// the box's linear order) and the same bins (each leaf's photons
/// ascending). Each photon's leaf range once; per cell a count (atomic
/// adds: the counts do not depend on the order), the leaves where it is
/// not zero, a prefix sum, then the photon indices scattered in photon
/// order. None when the box holds more than [`DENSE_BIN_CELLS`] leaves.
pub fn bin_photons_dense(photons: &[Photon], voxel_size: f64, reach: impl Fn(usize) -> f64 + Sync) -> Option<(Vec<IVec3>, Bins)> {
    use std::sync::atomic::{AtomicU32, Ordering::Relaxed};
    let ranges: Vec<(IVec3, IVec3)> = photons.par_iter().enumerate().map(|(i, p)| leaf_range(p, voxel_size, reach(i))).collect();
    let (lo, hi) = ranges
        .par_iter()
        .filter(|(a, b)| a.cmple(*b).all())
        .map(|&r| r)
        .reduce(|| (IVec3::MAX, IVec3::MIN), |(a, b), (c, d)| (a.min(c), b.max(d)));
    if lo.x > hi.x {
        return Some((Vec::new(), Bins { start: vec![0], photons: Vec::new() }));
    }
    let dims = ((hi.as_i64vec3() - lo.as_i64vec3()) / LEAF_DIM as i64 + 1).as_u64vec3();
    if dims.x.saturating_mul(dims.y).saturating_mul(dims.z) > DENSE_BIN_CELLS {
        return None;
    }
    let (ny, nz) = (dims.y as usize, dims.z as usize);
    let cells = dims.x as usize * ny * nz;
    let cell = |o: IVec3| {
        let d = (o - lo) / LEAF_DIM;
        (d.x as usize * ny + d.y as usize) * nz + d.z as usize
    };
    let counts: Vec<AtomicU32> = (0..cells).map(|_| AtomicU32::new(0)).collect();
    ranges.par_iter().for_each(|&r| {
        for_each_leaf(r, |o| {
            counts[cell(o)].fetch_add(1, Relaxed);
        })
    });
    let (mut leaves, mut start, mut slot) = (Vec::new(), vec![0usize], vec![u32::MAX; cells]);
    for (c, n) in counts.iter().enumerate() {
        let n = n.load(Relaxed) as usize;
        if n > 0 {
            let (x, y, z) = (c / (ny * nz), (c / nz) % ny, c % nz);
            slot[c] = leaves.len() as u32;
            leaves.push(lo + IVec3::new(x as i32, y as i32, z as i32) * LEAF_DIM);
            start.push(start[start.len() - 1] + n);
        }
    }
    let mut next = start.clone();
    let mut out = vec![0u32; start[start.len() - 1]];
    for (i, &r) in ranges.iter().enumerate() {
        for_each_leaf(r, |o| {
            let k = slot[cell(o)] as usize;
            out[next[k]] = i as u32;
            next[k] += 1;
        });
    }
    Some((leaves, Bins { start, photons: out }))
}

/// exp(x) for x <= 0 in f32, deterministic and branch-free so loops
/// vectorise: `2^(x log2 e)` split into an integer power (exponent bits) and
/// 2^f for f in [-1/2, 1/2] by its degree-6 Taylor polynomial (truncation
/// ln2^7 / 7! / 2^7 = 1.2e-7 relative). Arguments below -87 return 0-ish
/// subnormal-free values (clamped at 2^-126).
#[inline(always)]
pub fn exp_neg_f32(x: f32) -> f32 {
    let y = (x * std::f32::consts::LOG2_E).max(-126.0);
    // Round to nearest by the 1.5 * 2^23 trick (exact for |y| < 2^22): the
    // integer lands in the low mantissa bits of t, so neither libm's round
    // nor a saturating float-to-int conversion is needed (both block
    // vectorisation).
    const MAGIC: f32 = 12_582_912.0;
    let t = y + MAGIC;
    let i_bits = t.to_bits() as i32 - MAGIC.to_bits() as i32;
    let f = y - (t - MAGIC);
    const C: [f32; 7] = [
        1.0,
        std::f32::consts::LN_2,
        0.240_226_5,
        0.055_504_11,
        0.009_618_129,
        0.001_333_355_8,
        0.000_154_035_3,
    ];
    let p = C[0] + f * (C[1] + f * (C[2] + f * (C[3] + f * (C[4] + f * (C[5] + f * C[6])))));
    let scale = f32::from_bits(((i_bits + 127) as u32) << 23);
    p * scale
}

/// Kernel weights of 4 consecutive voxels of a z-row at squared distances
/// `dxy + dz2[z]`: `norm exp(-d^2 inv_2r2)` inside `reach2`, else 0.
#[inline(always)]
fn kernel_lanes(dxy: f32, dz2: &[f32; 4], reach2: &[f32], norm: &[f32], inv_2r2: &[f32]) -> [f32; 4] {
    let (reach2, norm, inv_2r2): (&[f32; 4], &[f32; 4], &[f32; 4]) =
        (reach2.try_into().unwrap(), norm.try_into().unwrap(), inv_2r2.try_into().unwrap());
    let mut w = [0.0f32; 4];
    for z in 0..4 {
        let dd = dxy + dz2[z];
        let e = norm[z] * exp_neg_f32(-dd * inv_2r2[z]);
        w[z] = if dd < reach2[z] { e } else { 0.0 };
    }
    w
}

/// The segment kernel's geometry at N consecutive voxels of a z-row (4 or
/// 8), offsets from the segment's start `w = (wx, wy, wz)` given as `s_xy
/// = wx dx + wy dy` and `w2_xy = wx^2 + wy^2` for the row and `wz dz`,
/// `wz^2` per lane: `s` (along the segment), `perp^2` (across it), and 1
/// where the voxel lies inside the capsule (distance to the segment below
/// `c r`), else 0. Branch-free so it vectorises.
#[inline(always)]
fn segment_lanes<const N: usize>(sxy: f32, w2xy: f32, sz: &[f32; N], w2z: &[f32; N], l: f32, q: &SegParams) -> ([f32; N], [f32; N], [f32; N]) {
    let (mut s4, mut p4, mut inside) = ([0.0f32; N], [0.0f32; N], [0.0f32; N]);
    for j in 0..N {
        let s = sxy + sz[j];
        let w2 = w2xy + w2z[j];
        let perp2 = (w2 - s * s).max(0.0);
        let end2 = (w2 - 2.0 * s * l + l * l).max(0.0);
        let dist2 = if s < 0.0 { w2 } else if s > l { end2 } else { perp2 };
        inside[j] = if dist2 < q.reach2 { 1.0 } else { 0.0 };
        (s4[j], p4[j]) = (s, perp2);
    }
    (s4, p4, inside)
}

/// The segment kernel's closed form at N lanes of a z-row from
/// [`segment_lanes`]' `s`, `perp2` and `inside`, times the photon's power
/// `phi`, added to the sums from voxel `n` on: `c inside exp(-perp2 / 2r^2)
/// (erf(s / sqrt2 r) - erf((s - L) / sqrt2 r))`, `c` the constant factor.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn add_segment_lanes<const N: usize>(acc: &mut LeafAcc, n: usize, s4: &[f32; N], perp2: &[f32; N], inside: &[f32; N], q: &SegParams, c: f32, l: f32, phi: &[f32; 3]) {
    let erf = erf_table();
    let (mut ex, mut u0, mut u1) = ([0.0f32; N], [0.0f32; N], [0.0f32; N]);
    for j in 0..N {
        ex[j] = exp_neg_f32(-perp2[j] * q.inv_2r2);
        u0[j] = s4[j] * q.inv_sqrt2r;
        u1[j] = (s4[j] - l) * q.inv_sqrt2r;
    }
    let (e0, e1) = (erf_lut_lanes(erf, &u0), erf_lut_lanes(erf, &u1));
    let mut v = [0.0f32; N];
    for j in 0..N {
        v[j] = c * inside[j] * ex[j] * (e0[j] - e1[j]);
    }
    for (col, &ph) in acc.c.iter_mut().zip(phi) {
        for (a, &vj) in col[n..n + N].iter_mut().zip(&v) {
            *a += vj * ph;
        }
    }
}

/// Scratch space of the splat gather, one per thread: the per-voxel sums
/// (zero between leaves) and the point kernel's per-voxel parameters.
pub struct SplatBuffers {
    acc: Box<LeafAcc>,
    k: Box<LeafKernels>,
}

impl SplatBuffers {
    pub fn new() -> Self {
        Self { acc: GatherSetup::new_acc(), k: GatherSetup::new_kernels() }
    }
}

impl Default for SplatBuffers {
    fn default() -> Self {
        Self::new()
    }
}

/// Per-voxel kernel parameters of one leaf, structure of arrays.
struct LeafKernels {
    /// 1 / ((2 pi)^(3/2) r^3 M(c)), km^-3.
    norm: [f32; LEAF_NUM_VALUES],
    /// 1 / (2 r^2).
    inv_2r2: [f32; LEAF_NUM_VALUES],
    /// (c r)^2.
    reach2: [f32; LEAF_NUM_VALUES],
}

impl LeafKernels {
    fn set(&mut self, n: usize, k: &Kernel) {
        self.norm[n] = k.norm as f32;
        self.inv_2r2[n] = k.inv_2r2 as f32;
        self.reach2[n] = k.reach2 as f32;
    }
}

/// Per-voxel segment-kernel parameters of one leaf.
struct LeafSegKernels {
    /// Smallest and largest r over the leaf, km.
    r_min: f64,
    r_max: f64,
    /// The same parameters per voxel, for the scalar path.
    all: Vec<SegParams>,
}

impl LeafSegKernels {
    #[inline]
    fn params(&self, n: usize) -> SegParams {
        self.all[n]
    }
}

/// Per-voxel sums of one leaf, one array per colour. f32: the sums are of
/// positive terms in a fixed order, so n terms are good to n 2^-24 relative
/// at worst (about sqrt(n) 2^-24 in practice, 1e-5 for 10^4 terms), far
/// below the estimate's Monte Carlo noise; f64 made the gather 30 % slower.
struct LeafAcc {
    c: [[f32; LEAF_NUM_VALUES]; 3],
}

/// Kernel parameters of one voxel for a segment photon, f32.
#[derive(Clone, Copy, Debug, Default)]
struct SegParams {
    /// 1 / r.
    inv_r: f32,
    /// 1 / (sqrt 2 r).
    inv_sqrt2r: f32,
    /// 1 / (2 r^2).
    inv_2r2: f32,
    /// 1 / (2 pi r^2).
    inv_2pi_r2: f32,
    /// (c r)^2.
    reach2: f32,
    /// The point kernel's norm, 1 / ((2 pi)^(3/2) r^3 M(c)).
    norm: f32,
}

impl SegParams {
    fn new(k: &Kernel) -> Self {
        let r = k.r;
        Self {
            inv_r: (1.0 / r) as f32,
            inv_sqrt2r: (1.0 / (std::f64::consts::SQRT_2 * r)) as f32,
            inv_2r2: k.inv_2r2 as f32,
            inv_2pi_r2: (1.0 / (2.0 * std::f64::consts::PI * r * r)) as f32,
            reach2: k.reach2 as f32,
            norm: k.norm as f32,
        }
    }
}

/// What a leaf gather needs.
pub struct GatherSetup<'a> {
    pub photons: &'a [Photon],
    pub transform: Transform,
    pub radius: &'a RadiusField,
    pub cutoff: f64,
    /// gaussian_mass_inside(cutoff)
    pub mass: f64,
    /// Segment kernel masses for `cutoff`.
    pub seg: SegmentMass,
    /// The splat's kernel of each photon (r at the point or the segment's
    /// midpoint), computed once per photon rather than once per leaf it
    /// touches (the radius noise is a Perlin lookup); empty for the other
    /// gathers.
    pub splat_kernels: &'a [SplatKernel],
}

/// A photon's kernel in the splat: its parameters (r at the point, or at
/// the segment's midpoint) and reach `cutoff r`, km, by which it is binned.
#[derive(Clone, Copy, Debug, Default)]
pub struct SplatKernel {
    sp: SegParams,
    reach: f64,
}

impl SplatKernel {
    fn new(kernel: &Kernel) -> Self {
        Self { sp: SegParams::new(kernel), reach: kernel.reach() }
    }
}

impl GatherSetup<'_> {
    fn centre(&self, ijk: IVec3) -> DVec3 {
        self.transform.index_to_world(ijk.as_dvec3())
    }

    /// Index range (inclusive, leaf-local, clamped to 0..8) of the voxels
    /// whose centres can lie within `reach` of `q`.
    #[inline]
    fn local_range(&self, origin: IVec3, q: DVec3, reach: f64) -> Option<(IVec3, IVec3)> {
        let qi = self.transform.world_to_index(q);
        let r = reach / self.transform.voxel_size;
        let lo = ceil_i(qi - DVec3::splat(r)) - origin;
        let hi = floor_i(qi + DVec3::splat(r)) - origin;
        let lo = lo.max(IVec3::ZERO);
        let hi = hi.min(IVec3::splat(LEAF_DIM - 1));
        (lo.x <= hi.x && lo.y <= hi.y && lo.z <= hi.z).then_some((lo, hi))
    }

    /// Adds photon `p`'s kernel, with the per-voxel parameters `k`, to the
    /// voxels of the leaf at `origin` within `reach` of it:
    /// `acc[n] += Phi * norm[n] exp(-d^2 / 2 r_n^2)` where `d^2 < (c r_n)^2`.
    /// Distances are taken in f64 then rounded to f32; the kernel value is f32
    /// (relative error below 1e-6 for |exponent| <= c^2 / 2 <= 18).
    #[inline]
    fn accumulate(&self, origin: IVec3, p: &Photon, reach: f64, k: &LeafKernels, acc: &mut LeafAcc) {
        let q = pos(p);
        let Some((lo, hi)) = self.local_range(origin, q, reach) else { return };
        let vs = self.transform.voxel_size;
        let t = self.transform.translation;
        let d2 = |axis: usize, l: i32| -> f32 {
            let c = (origin[axis] + l) as f64 * vs + t[axis];
            let d = c - q[axis];
            (d * d) as f32
        };
        // Whole z-rows of 8 voxels at a time, voxels out of range given an
        // infinite distance (weight exactly 0, and adding 0 changes no sum):
        // fixed-length, branch-free loops the compiler vectorises.
        let mut dz2 = [f32::INFINITY; LEAF_DIM as usize];
        for z in lo.z..=hi.z {
            dz2[z as usize] = d2(2, z);
        }
        let phi = p.power;
        let reach2 = (reach * reach) as f32;
        // Nearest z of each half row (lanes 0-3, 4-7): a half whose nearest
        // voxel is out of reach is skipped whole.
        let near = [dz2[..4].iter().cloned().fold(f32::INFINITY, f32::min), dz2[4..].iter().cloned().fold(f32::INFINITY, f32::min)];
        for x in lo.x..=hi.x {
            let dx2 = d2(0, x);
            for y in lo.y..=hi.y {
                let dxy = dx2 + d2(1, y);
                let row = ((x << 6) | (y << 3)) as usize;
                for (half, &nz) in near.iter().enumerate() {
                    if dxy + nz >= reach2 {
                        continue; // this half row misses the reach sphere
                    }
                    let (b, o) = (row + 4 * half, 4 * half);
                    let dz: &[f32; 4] = dz2[o..o + 4].try_into().unwrap();
                    let w = kernel_lanes(dxy, dz, &k.reach2[b..b + 4], &k.norm[b..b + 4], &k.inv_2r2[b..b + 4]);
                    for (col, &ph) in acc.c.iter_mut().zip(&phi) {
                        for (a, &wz) in col[b..b + 4].iter_mut().zip(&w) {
                            *a += wz * ph;
                        }
                    }
                }
            }
        }
    }

    /// Adds segment photon `p`'s kernel to the voxels of the leaf at
    /// `origin` within `reach` of its segment, with the parameters `sp(n)`
    /// of voxel n: the closed form of the module documentation, or the
    /// point kernel at the midpoint below [`MIDPOINT_LAMBDA`]. Offsets from
    /// the segment's start are taken in f64 then rounded to f32.
    #[inline]
    fn accumulate_segment(&self, origin: IVec3, p: &Photon, reach: f64, sp: impl Fn(usize) -> SegParams, acc: &mut LeafAcc) {
        let (a, b) = (pos(p), end(p));
        let Some((lo, hi)) = self.local_box(origin, a.min(b), a.max(b), reach) else { return };
        let len = a.distance(b);
        let dir = ((b - a) / len).as_vec3();
        let l = len as f32;
        let vs = self.transform.voxel_size;
        let t = self.transform.translation;
        let off = |axis: usize, i: i32| -> f32 { ((origin[axis] + i) as f64 * vs + t[axis] - a[axis]) as f32 };
        let mut wz = [0.0f32; LEAF_DIM as usize];
        for z in lo.z..=hi.z {
            wz[z as usize] = off(2, z);
        }
        let wz0 = off(2, 0);
        let phi = p.power;
        let inv_2l = 0.5 / l;
        let erf = erf_table();
        // Rows along z: a voxel within `reach` of the segment lies within it
        // in (x, y) of the segment's (x, y) projection, at a distance e, and
        // within sqrt(reach^2 - e^2) in z of the segment's z range. Rows and
        // voxels outside are skipped (their kernel is 0 there anyway).
        let (px, py) = (l * dir.x, l * dir.y);
        let pxy2 = px * px + py * py;
        let reach2 = (reach * reach) as f32;
        let vs32 = vs as f32;
        let (za, zb) = (0.0f32.min(l * dir.z), 0.0f32.max(l * dir.z));
        for x in lo.x..=hi.x {
            let wx = off(0, x);
            for y in lo.y..=hi.y {
                let wy = off(1, y);
                let t = if pxy2 > 0.0 { ((wx * px + wy * py) / pxy2).clamp(0.0, 1.0) } else { 0.0 };
                let e2 = (wx - t * px).powi(2) + (wy - t * py).powi(2);
                if e2 >= reach2 {
                    continue;
                }
                let h = (reach2 - e2).sqrt() * (1.0 + 1e-5) + 1e-5;
                // Voxel z offsets from a are wz[0] + k vs, k = 0..8.
                // Rounding toward zero then widening by one voxel: a
                // superset without libm's ceil and floor.
                let z0 = (((za - h - wz0) / vs32).max(-1.0) as i32).max(lo.z);
                let z1 = (((zb + h - wz0) / vs32).min(9.0) as i32 + 1).min(hi.z);
                let sxy = wx * dir.x + wy * dir.y;
                let w2xy = wx * wx + wy * wy;
                for z in z0..=z1 {
                    let n = ((x << 6) | (y << 3) | z) as usize;
                    let q = sp(n);
                    let wzz = wz[z as usize];
                    let s = sxy + wzz * dir.z;
                    let w2 = w2xy + wzz * wzz;
                    let lam = l * q.inv_r;
                    let v = if (lam as f64) < MIDPOINT_LAMBDA {
                        // |w - d L/2|^2.
                        let dm2 = (w2 - s * l + 0.25 * l * l).max(0.0);
                        if dm2 >= q.reach2 {
                            continue;
                        }
                        q.norm * exp_neg_f32(-dm2 * q.inv_2r2)
                    } else {
                        let perp2 = (w2 - s * s).max(0.0);
                        let dist2 = if s < 0.0 {
                            w2
                        } else if s > l {
                            (w2 - 2.0 * s * l + l * l).max(0.0)
                        } else {
                            perp2
                        };
                        if dist2 >= q.reach2 {
                            continue;
                        }
                        q.inv_2pi_r2 * inv_2l * self.seg.inv_mass_f32(lam)
                            * exp_neg_f32(-perp2 * q.inv_2r2)
                            * (erf_lut(erf, s * q.inv_sqrt2r) - erf_lut(erf, (s - l) * q.inv_sqrt2r))
                    };
                    for (col, &ph) in acc.c.iter_mut().zip(&phi) {
                        col[n] += v * ph;
                    }
                }
            }
        }
    }

    /// The splat's segment path: photon `p`'s segment kernel, with its one
    /// set of parameters `sk`, added to the voxels of the leaf at `origin`
    /// within its reach. A segment shorter than [`MIDPOINT_LAMBDA`] r goes
    /// to the point path at its midpoint. Otherwise the closed form of the
    /// module documentation, evaluated over whole half z-rows (4 voxels)
    /// without branches: the capsule test `dist2 < (c r)^2` selects the
    /// lanes (the same test, in the same f32 arithmetic, as
    /// [`Self::accumulate_segment`], so the same voxels get a term), the
    /// rows the capsule misses and the half rows outside the segment's box
    /// widened by the reach are skipped whole. Offsets from the segment's
    /// start are taken in f64 then rounded to f32.
    #[inline(always)]
    fn splat_segment(&self, origin: IVec3, p: &Photon, sk: &SplatKernel, k: &mut LeafKernels, acc: &mut LeafAcc) {
        let (a, b) = (pos(p), end(p));
        let q = sk.sp;
        let reach = sk.reach;
        let len = a.distance(b);
        let l = len as f32;
        let lam = l * q.inv_r;
        if (lam as f64) < MIDPOINT_LAMBDA {
            let mid = 0.5 * (a + b);
            let Some((lo, hi)) = self.local_range(origin, mid, reach) else { return };
            for x in lo.x..=hi.x {
                for y in lo.y..=hi.y {
                    let row = ((x << 6) | (y << 3)) as usize;
                    for n in row..row + 8 {
                        (k.norm[n], k.inv_2r2[n], k.reach2[n]) = (q.norm, q.inv_2r2, q.reach2);
                    }
                }
            }
            let mid = Photon::point(mid.as_vec3().to_array(), p.power);
            return self.accumulate(origin, &mid, reach, k, acc);
        }
        let Some((lo, hi)) = self.local_box(origin, a.min(b), a.max(b), reach) else { return };
        let dir = ((b - a) / len).as_vec3();
        let vs = self.transform.voxel_size;
        let t = self.transform.translation;
        let off = |axis: usize, i: i32| -> f32 { ((origin[axis] + i) as f64 * vs + t[axis] - a[axis]) as f32 };
        let (mut sz, mut w2z) = ([0.0f32; 8], [0.0f32; 8]);
        for z in 0..8 {
            let w = off(2, z as i32);
            (sz[z], w2z[z]) = (w * dir.z, w * w);
        }
        let phi = p.power;
        // The closed form's constant factor: 1 / (2 pi r^2) / (2 L M_seg).
        let c = q.inv_2pi_r2 * (0.5 / l) * self.seg.inv_mass_f32(lam);
        let (px, py) = (l * dir.x, l * dir.y);
        let pxy2 = px * px + py * py;
        let reach2 = (reach * reach) as f32;
        let inv_pxy2 = if pxy2 > 0.0 { 1.0 / pxy2 } else { 0.0 };
        let wys: [f32; 8] = std::array::from_fn(|y| off(1, y as i32));
        // Half rows (lanes 0-3, 4-7) meeting the z range lo.z..=hi.z.
        let halves = (if lo.z < 4 { 0 } else { 4 }..if hi.z >= 4 { 8 } else { 4 }).step_by(4);
        let whole_rows = lo.z < 4 && hi.z >= 4;
        for x in lo.x..=hi.x {
            let wx = off(0, x);
            for y in lo.y..=hi.y {
                let wy = wys[y as usize];
                // The row's distance e in (x, y) from the segment's
                // projection: rows with e >= reach miss the capsule. (A z
                // range per row, as in accumulate_segment, costs a square
                // root per row and saved less than it cost: the half rows
                // are those of the leaf's z range `lo.z..=hi.z`.)
                let tt = ((wx * px + wy * py) * inv_pxy2).clamp(0.0, 1.0);
                let e2 = (wx - tt * px).powi(2) + (wy - tt * py).powi(2);
                if e2 >= reach2 {
                    continue;
                }
                let sxy = wx * dir.x + wy * dir.y;
                let w2xy = wx * wx + wy * wy;
                let row = ((x << 6) | (y << 3)) as usize;
                if whole_rows {
                    // Both halves at once (one 8-lane pass with AVX2,
                    // `GatherSetup::leaf_splat`); a half the capsule misses
                    // adds exact zeros (inside 0, every other factor finite
                    // and e0 >= e1: erf_lut is monotone), which leaves the
                    // non-negative sums as they are: the same values as
                    // half rows.
                    let (s8, perp2, inside) = segment_lanes(sxy, w2xy, &sz, &w2z, l, &q);
                    if inside != [0.0; 8] {
                        add_segment_lanes(acc, row, &s8, &perp2, &inside, &q, c, l, &phi);
                    }
                    continue;
                }
                for o in halves.clone() {
                    let (sz4, w2z4) = (sz[o..o + 4].try_into().unwrap(), w2z[o..o + 4].try_into().unwrap());
                    let (s4, perp2, inside) = segment_lanes::<4>(sxy, w2xy, sz4, w2z4, l, &q);
                    if inside == [0.0; 4] {
                        continue; // the half row misses the capsule
                    }
                    add_segment_lanes(acc, row + o, &s4, &perp2, &inside, &q, c, l, &phi);
                }
            }
        }
    }

    /// The balloon gather's segment path: a segment shorter than
    /// [`MIDPOINT_LAMBDA`] times r at every voxel of the leaf goes to the
    /// (vectorised) point path at its midpoint, any other to
    /// [`Self::accumulate_segment`]. (A branch-free 8-lane version of the
    /// latter was slower: it evaluates the voxels of each z-row that the
    /// scalar loop's z range skips.)
    #[inline]
    fn accumulate_segment_rows(&self, origin: IVec3, p: &Photon, reach: f64, k: &LeafKernels, sk: &LeafSegKernels, acc: &mut LeafAcc) {
        let (a, b) = (pos(p), end(p));
        if a.distance(b) < MIDPOINT_LAMBDA * sk.r_min {
            let mid = Photon::point((0.5 * (a + b)).as_vec3().to_array(), p.power);
            return self.accumulate(origin, &mid, reach, k, acc);
        }
        self.accumulate_segment(origin, p, reach, |n| sk.params(n), acc)
    }

    /// Index range (inclusive, leaf-local, clamped to 0..8) of the voxels
    /// whose centres can lie within `reach` of the box [lo, hi].
    #[inline]
    fn local_box(&self, origin: IVec3, lo: DVec3, hi: DVec3, reach: f64) -> Option<(IVec3, IVec3)> {
        let (li, hi_) = (self.transform.world_to_index(lo), self.transform.world_to_index(hi));
        let r = reach / self.transform.voxel_size;
        let lo = (ceil_i(li - DVec3::splat(r)) - origin).max(IVec3::ZERO);
        let hi = (floor_i(hi_ + DVec3::splat(r)) - origin).min(IVec3::splat(LEAF_DIM - 1));
        (lo.x <= hi.x && lo.y <= hi.y && lo.z <= hi.z).then_some((lo, hi))
    }

    /// Turns per-voxel sums into a leaf: value = sum * scale as f32, active
    /// where nonzero, and clears the sums for the next leaf. None if nothing
    /// is active. The leaf's values are written once (no zeroed buffer
    /// first).
    fn finish(origin: IVec3, acc: &mut LeafAcc, scale: f64) -> Option<Leaf<[f32; 3]>> {
        // Structure of arrays first (loops that vectorise), then the mask,
        // then the leaf's interleaved values.
        let mut v = [[0.0f32; LEAF_NUM_VALUES]; 3];
        for (vk, ck) in v.iter_mut().zip(&acc.c) {
            for (x, &c) in vk.iter_mut().zip(ck) {
                *x = (c as f64 * scale) as f32;
            }
        }
        acc.c = [[0.0; LEAF_NUM_VALUES]; 3];
        // Active where some component is nonzero (`!= 0.0`: any bit but
        // the sign set), bit by bit from the top of each word.
        let mut mask = [0u64; crate::grid::LEAF_MASK_WORDS];
        for (w, m) in mask.iter_mut().enumerate() {
            let mut bits = 0u64;
            for n in (w * 64..w * 64 + 64).rev() {
                let on = ((v[0][n].to_bits() | v[1][n].to_bits() | v[2][n].to_bits()) << 1) != 0;
                bits = (bits << 1) | on as u64;
            }
            *m = bits;
        }
        if mask.iter().all(|&w| w == 0) {
            return None;
        }
        let mut leaf = Leaf::new(origin, [0.0f32; 3]);
        leaf.mask = mask;
        for (n, x) in leaf.values.iter_mut().enumerate() {
            if leaf.mask[n >> 6] >> (n & 63) & 1 == 1 {
                *x = [v[0][n], v[1][n], v[2][n]];
            }
        }
        Some(leaf)
    }

    fn new_acc() -> Box<LeafAcc> {
        Box::new(LeafAcc { c: [[0.0f32; LEAF_NUM_VALUES]; 3] })
    }

    fn new_kernels() -> Box<LeafKernels> {
        Box::new(LeafKernels { norm: [0.0; LEAF_NUM_VALUES], inv_2r2: [0.0; LEAF_NUM_VALUES], reach2: [0.0; LEAF_NUM_VALUES] })
    }

    /// Balloon estimate for the voxels of one leaf from the given photons
    /// (ascending indices; a superset of those in reach). Kernel radius at
    /// each voxel: r(x_v).
    pub fn leaf_balloon(&self, origin: IVec3, candidates: impl Iterator<Item = usize>) -> Option<Leaf<[f32; 3]>> {
        let mut k = Self::new_kernels();
        let mut sk = Box::new(LeafSegKernels {
            r_min: f64::INFINITY,
            r_max: 0.0,
            all: vec![SegParams::default(); LEAF_NUM_VALUES],
        });
        for n in 0..LEAF_NUM_VALUES {
            let c = self.centre(origin + crate::grid::offset_to_local(n));
            let kernel = Kernel::with_mass(self.radius.radius(c), self.cutoff, self.mass);
            k.set(n, &kernel);
            let sp = SegParams::new(&kernel);
            sk.r_min = sk.r_min.min(kernel.r);
            sk.r_max = sk.r_max.max(kernel.r);
            sk.all[n] = sp;
        }
        let reach = self.cutoff * self.radius.max();
        let mut acc = Self::new_acc();
        for i in candidates {
            let p = &self.photons[i];
            if p.is_point() {
                self.accumulate(origin, p, reach, &k, &mut acc);
            } else {
                self.accumulate_segment_rows(origin, p, reach, &k, &sk, &mut acc);
            }
        }
        Self::finish(origin, &mut acc, 1.0 / PHOTONS_PER_KM2_S_PER_KR)
    }

    /// Sample-point estimate (splat): kernel radius r(x_i) at each photon.
    /// `bufs` is scratch space, reused from leaf to leaf (one per thread):
    /// the sums are cleared after each leaf, and the per-voxel kernel rows
    /// are written before they are read.
    pub fn leaf_splat(&self, origin: IVec3, photons: &[u32], bufs: &mut SplatBuffers) -> Option<Leaf<[f32; 3]>> {
        #[cfg(target_arch = "x86_64")]
        if std::is_x86_feature_detected!("avx2") {
            // SAFETY: the CPU has AVX2 (checked just above).
            return unsafe { self.leaf_splat_avx2(origin, photons, bufs) };
        }
        self.leaf_splat_body(origin, photons, bufs)
    }

    /// [`Self::leaf_splat`] compiled for AVX2: the 8-lane z-rows of the
    /// segment path in one pass. IEEE arithmetic is the same at any vector
    /// width and Rust fuses no multiply-add, so the values are the same
    /// bits as without AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn leaf_splat_avx2(&self, origin: IVec3, photons: &[u32], bufs: &mut SplatBuffers) -> Option<Leaf<[f32; 3]>> {
        self.leaf_splat_body(origin, photons, bufs)
    }

    #[inline(always)]
    fn leaf_splat_body(&self, origin: IVec3, photons: &[u32], bufs: &mut SplatBuffers) -> Option<Leaf<[f32; 3]>> {
        let SplatBuffers { acc, k } = bufs;
        for &i in photons {
            let p = &self.photons[i as usize];
            if !p.is_point() {
                self.splat_segment(origin, p, &self.splat_kernels[i as usize], k, acc);
                continue;
            }
            let q = pos(p);
            let kernel = Kernel::with_mass(self.radius.radius(q), self.cutoff, self.mass);
            let Some((lo, hi)) = self.local_range(origin, q, kernel.reach()) else { continue };
            // The photon's kernel in the rows it can touch (whole z-rows:
            // accumulate reads them 4 lanes at a time).
            for x in lo.x..=hi.x {
                for y in lo.y..=hi.y {
                    let row = ((x << 6) | (y << 3)) as usize;
                    for n in row..row + 8 {
                        k.set(n, &kernel);
                    }
                }
            }
            self.accumulate(origin, p, kernel.reach(), k, acc);
        }
        Self::finish(origin, acc, 1.0 / PHOTONS_PER_KM2_S_PER_KR)
    }

    /// The 2014 report's weighted average colour, sum(w Phi) / sum(w), with
    /// w = exp(-d^2 / 2 r^2) inside the cutoff (r at the voxel).
    pub fn leaf_report2014(&self, origin: IVec3, photons: &[u32]) -> Option<Leaf<[f32; 3]>> {
        let mut acc = Self::new_acc();
        let mut wsum = vec![0.0f64; LEAF_NUM_VALUES];
        let reach = self.cutoff * self.radius.max();
        let kernels: Vec<Kernel> = (0..LEAF_NUM_VALUES)
            .map(|n| Kernel::with_mass(self.radius.radius(self.centre(origin + crate::grid::offset_to_local(n))), self.cutoff, self.mass))
            .collect();
        for &i in photons {
            let p = &self.photons[i as usize];
            let q = pos(p);
            let Some((lo, hi)) = self.local_range(origin, q, reach) else { continue };
            for x in lo.x..=hi.x {
                for y in lo.y..=hi.y {
                    for z in lo.z..=hi.z {
                        let ijk = origin + IVec3::new(x, y, z);
                        let n = leaf_offset(ijk);
                        let w = kernels[n].weight_d2(self.centre(ijk).distance_squared(q));
                        if w > 0.0 {
                            wsum[n] += w;
                            for k in 0..3 {
                                acc.c[k][n] += (w * p.power[k] as f64) as f32;
                            }
                        }
                    }
                }
            }
        }
        for (n, &w) in wsum.iter().enumerate() {
            if w > 0.0 {
                for k in 0..3 {
                    acc.c[k][n] = (acc.c[k][n] as f64 / w) as f32;
                }
            }
        }
        Self::finish(origin, &mut acc, 1.0 / PHOTONS_PER_KM2_S_PER_KR)
    }
}

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
    let parts: Vec<Vec<Photon>> = cuts.par_windows(2).map(|w| merge_run_list(&photons[w[0]..w[1]], &radius, len_r, off_r, max_cdf)).collect();
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
                    for k in 0..3 {
                        sum[k] += q.power[k] as f64;
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
                for k in 0..3 {
                    power[k] += q.power[k];
                }
            }
            out.push(Photon::segment(first.position, photons[j].end, power));
        }
        i = j + 1;
    }
    out
}

/// Builds the emission grid (kR per km, linear Rec.709) from the photons
/// with the chosen gather method. Leaves are gathered in parallel, collected
/// in leaf order and sorted, so the grid does not depend on the thread count.
pub fn gather_grid(
    photons: &[Photon],
    transform: Transform,
    radius: &RadiusField,
    cutoff: f64,
    method: GatherMethod,
    progress: &dyn Progress,
) -> Grid<[f32; 3]> {
    gather_prepared(&GatherInput::new(photons, radius, cutoff, method), transform, radius, cutoff, method, progress)
}

/// The photons as the gathers take them, made once for several gathers of
/// the same photons (the preview's coarse picture and the refined one):
/// straight, evenly lit runs of beam steps merged into one segment each
/// ([`merge_segments`], all but `report2014`) and, for the splat, each
/// photon's kernel (r at the point or the segment's midpoint: a Perlin
/// lookup per photon).
#[derive(Clone, Debug)]
pub struct GatherInput {
    pub photons: Vec<Photon>,
    splat_kernels: Vec<SplatKernel>,
    /// The segment kernel's masses for the cutoff (a table of some 4 k
    /// numerical integrals).
    seg: SegmentMass,
}

impl GatherInput {
    pub fn new(photons: &[Photon], radius: &RadiusField, cutoff: f64, method: GatherMethod) -> Self {
        let photons = if method == GatherMethod::Report2014 {
            photons.to_vec()
        } else {
            merge_segments(photons, |p| radius.radius(p), MERGE_LEN_R, MERGE_OFF_R, MERGE_CDF)
        };
        let mass = gaussian_mass_inside(cutoff);
        let splat_kernels = if method == GatherMethod::Splat {
            photons
                .par_iter()
                .map(|p| SplatKernel::new(&Kernel::with_mass(radius.radius(if p.is_point() { pos(p) } else { 0.5 * (pos(p) + end(p)) }), cutoff, mass)))
                .collect()
        } else {
            Vec::new()
        };
        Self { photons, splat_kernels, seg: SegmentMass::new(cutoff) }
    }

    /// Every `k`-th photon (from the first), its power multiplied by `k`:
    /// the same expected emission from `1/k` of the photons (the preview's
    /// coarse picture). Kernels are kept.
    pub fn every(&self, k: usize) -> Self {
        let k = k.max(1);
        let photons = self.photons.iter().step_by(k).map(|p| Photon { power: p.power.map(|c| c * k as f32), ..*p }).collect();
        let splat_kernels = self.splat_kernels.iter().step_by(k).copied().collect();
        Self { photons, splat_kernels, seg: self.seg.clone() }
    }
}

/// [`gather_grid`] of photons made ready by [`GatherInput::new`] with the
/// same radius field, cutoff and method.
pub fn gather_prepared(
    input: &GatherInput,
    transform: Transform,
    radius: &RadiusField,
    cutoff: f64,
    method: GatherMethod,
    progress: &dyn Progress,
) -> Grid<[f32; 3]> {
    let mut grid = Grid::new("emission", [0.0f32; 3], transform);
    let photons = &input.photons[..];
    let mass = gaussian_mass_inside(cutoff);
    let splat_kernels = &input.splat_kernels[..];
    let setup = GatherSetup { photons, transform, radius, cutoff, mass, seg: input.seg.clone(), splat_kernels };
    let reach = cutoff * radius.max();
    // The splat bins each photon by its own reach (cutoff r_i, r at the
    // point or the segment's midpoint, as leaf_splat evaluates it); the
    // balloon's kernel takes r at the voxel, so the largest r's reach.
    let (leaves, dense_bins) = if method == GatherMethod::Splat {
        match bin_photons_dense(photons, transform.voxel_size, |i| setup.splat_kernels[i].reach) {
            Some((leaves, bins)) => (leaves, Some(bins)),
            None => (candidate_leaves_by(photons, transform.voxel_size, |i| setup.splat_kernels[i].reach), None),
        }
    } else {
        (candidate_leaves(photons, transform.voxel_size, reach), None)
    };
    progress.start("gather", leaves.len() as u64);
    let out: Vec<Option<Leaf<[f32; 3]>>> = match method {
        GatherMethod::Kdtree => {
            let map = PhotonMap::new(photons);
            // Voxel centres of a leaf lie within 3.5 voxels (per axis) of its
            // middle: a sphere of radius 3.5 sqrt(3) voxels plus the reach.
            // (PhotonMap::within adds the longest half segment.)
            let half_diag = 3.5 * 3f64.sqrt() * transform.voxel_size;
            leaves
                .par_iter()
                .map(|&o| {
                    let mid = transform.index_to_world(o.as_dvec3() + DVec3::splat(3.5));
                    let cand = map.within(mid, half_diag + reach);
                    progress.inc(1);
                    setup.leaf_balloon(o, cand.into_iter())
                })
                .collect()
        }
        GatherMethod::Splat | GatherMethod::Report2014 => {
            let bins = if let Some(b) = dense_bins {
                b
            } else if method == GatherMethod::Splat {
                bin_photons_by(photons, &leaves, transform.voxel_size, |i| setup.splat_kernels[i].reach)
            } else {
                bin_photons(photons, &leaves, transform.voxel_size, reach)
            };
            leaves
                .par_iter()
                .enumerate()
                .map_init(SplatBuffers::new, |bufs, (k, &o)| {
                    let b = bins.get(k);
                    progress.inc(1);
                    if method == GatherMethod::Splat {
                        setup.leaf_splat(o, b, bufs)
                    } else {
                        setup.leaf_report2014(o, b)
                    }
                })
                .collect()
        }
    };
    for leaf in out.into_iter().flatten() {
        grid.insert_leaf(leaf);
    }
    grid.sort_leaves();
    progress.finish();
    grid
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::progress::NoProgress;
    use rand::Rng;

    fn uniform_box(n: usize, lo: f64, hi: f64, power: f32, seed: u64) -> Vec<Photon> {
        let mut r = rng::rng(&[seed]);
        (0..n)
            .map(|_| {
                let mut p = [0.0f32; 3];
                for c in &mut p {
                    *c = (lo + (hi - lo) * r.random::<f64>()) as f32;
                }
                Photon::point(p, [power, 0.5 * power, 0.25 * power])
            })
            .collect()
    }

    /// The dense binning gives the hashed path's leaves and bins: random
    /// segments and points with a reach per photon, including negative
    /// coordinates and leaves shared by many photons.
    #[test]
    fn dense_bins_equal_hashed_bins() {
        let mut r = rng::rng(&[91]);
        let photons: Vec<Photon> = (0..3000)
            .map(|i| {
                let a: [f32; 3] = std::array::from_fn(|_| r.random_range(-20.0f32..15.0));
                if i % 3 == 0 {
                    Photon::point(a, [1.0; 3])
                } else {
                    let b = std::array::from_fn(|k| a[k] + r.random_range(-2.0f32..2.0));
                    Photon::segment(a, b, [1.0; 3])
                }
            })
            .collect();
        let reach: Vec<f64> = (0..photons.len()).map(|_| r.random_range(0.2..2.5)).collect();
        for vs in [0.25, 0.5, 1.3] {
            let leaves = candidate_leaves_by(&photons, vs, |i| reach[i]);
            let bins = bin_photons_by(&photons, &leaves, vs, |i| reach[i]);
            let (dl, db) = bin_photons_dense(&photons, vs, |i| reach[i]).unwrap();
            assert_eq!(dl, leaves, "voxel {vs}");
            assert_eq!(db, bins, "voxel {vs}");
        }
        let (l, b) = bin_photons_dense(&[], 0.5, |_| 1.0).unwrap();
        assert!(l.is_empty() && b.photons.is_empty() && b.start == [0]);
    }

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
    fn fast_exp_matches_std_exp() {
        // Relative error budget: polynomial 1.2e-7 + f32 rounding of the
        // product chain (~6 operations x 2^-24 = 3.6e-7) + the argument's
        // own rounding, |x| 2^-24 <= 1.1e-6 at x = -18 (c = 6).
        let mut worst = 0.0f64;
        for i in 0..=200_000 {
            let x = -18.0f32 * i as f32 / 200_000.0;
            let got = exp_neg_f32(x) as f64;
            let want = (x as f64).exp();
            worst = worst.max((got / want - 1.0).abs());
        }
        assert!(worst < 1.5e-6, "worst relative error {worst}");
        assert_eq!(exp_neg_f32(0.0), 1.0);
        assert!(exp_neg_f32(-200.0) >= 0.0 && exp_neg_f32(-200.0) < 1e-37);
    }

    #[test]
    fn truncated_kernel_integrates_to_one() {
        // Closed form of the truncated mass for c = 3: erf(3/sqrt2) - sqrt(2/pi) 3 e^-4.5.
        let m = gaussian_mass_inside(3.0);
        assert!((m - (0.997_300_203_936_740 - (2.0 / std::f64::consts::PI).sqrt() * 3.0 * (-4.5f64).exp())).abs() < 1e-12, "{m}");
        for (r, c) in [(0.5, 3.0), (1.3, 1.5), (0.2, 6.0)] {
            let k = Kernel::new(r, c);
            // Midpoint rule on a grid of h = r / 8 over the cube [-c r, c r]^3.
            // The smooth part is integrated to ~1e-6; the cutoff is a jump of
            // height K(c r) on the sphere, and each cell it cuts is wrong by at
            // most its mass there: |error| <= 4 pi (c r)^2 (h / 2) K(c r).
            // (Without the renormalisation the error would be 1 - M(c):
            // 0.029 for c = 3, 0.52 for c = 1.5, far above these bounds.)
            let h = r / 8.0;
            let m = (c * r / h).ceil() as i32;
            let mut s = 0.0;
            for i in -m..=m {
                for j in -m..=m {
                    for l in -m..=m {
                        let d2 = (i * i + j * j + l * l) as f64 * h * h;
                        s += k.eval_d2(d2);
                    }
                }
            }
            s *= h * h * h;
            let jump = k.eval_d2((c * r) * (c * r) * (1.0 - 1e-12));
            let bound = 4.0 * std::f64::consts::PI * (c * r).powi(2) * 0.5 * h * jump + 1e-6;
            assert!(bound < 0.5 * (1.0 - gaussian_mass_inside(c)) || c > 5.0, "test too weak for c = {c}");
            assert!((s - 1.0).abs() < bound, "r {r} c {c}: {s} (bound {bound})");
        }
    }

    #[test]
    fn integer_ceil_and_floor_match_libm() {
        let mut rng = crate::rng::rng(&[9]);
        for k in 0..100_000 {
            let x: f64 = match k % 3 {
                0 => rng.random_range(-1e6..1e6),
                1 => (rng.random_range(-100..100) as f64) * 0.5,
                _ => rng.random_range(-3.0..3.0),
            };
            let v = DVec3::new(x, -x, x * 0.25);
            assert_eq!(ceil_i(v), v.ceil().as_ivec3(), "{v}");
            assert_eq!(floor_i(v), v.floor().as_ivec3(), "{v}");
        }
    }

    #[test]
    fn erf_table_matches_libm() {
        // h^2 / 8 max|erf''| = 1.2e-7, f32 storage and interpolation 1.2e-7.
        let t = erf_table();
        for i in -100_000..=100_000 {
            let x = 6.0 * i as f64 / 100_000.0;
            let err = (erf_lut(t, x as f32) as f64 - libm::erf(x as f32 as f64)).abs();
            assert!(err < 2.5e-7, "erf({x}): error {err}");
        }
        let m = SegmentMass::new(2.5);
        for i in 0..300 {
            let lam = 0.004 + i as f64 * 0.071;
            let (a, b) = (m.inv_mass_f32(lam as f32) as f64, 1.0 / segment_mass_inside(2.5, lam));
            assert!((a - b).abs() < 1e-6, "lambda {lam}: {a} vs {b}");
        }
    }

    #[test]
    fn segment_mass_has_the_point_limit_and_its_table_interpolates() {
        for c in [1.5, 2.5, 6.0] {
            let m0 = gaussian_mass_inside(c);
            assert_eq!(segment_mass_inside(c, 0.0), m0);
            // First order: M_seg = M(c) + lambda e^{-c^2/2} c^2 / (2 sqrt(2 pi))
            // (module documentation); at lambda = 1e-6 the difference is below 1e-6.
            assert!((segment_mass_inside(c, 1e-6) - m0).abs() < 1e-6, "c {c}");
            // Long segments: the cylinder dominates, M_seg -> 1 - e^{-c^2/2}.
            assert!((segment_mass_inside(c, 1e6) - (1.0 - (-0.5 * c * c).exp())).abs() < 1e-5);
            let t = SegmentMass::new(c);
            // Linear interpolation at steps of 1/256 plus f32 storage: below
            // 3e-7 (see SegmentMass); 1e-6 leaves room.
            for i in 0..400 {
                let lam = 0.013 + i as f64 * 0.0517;
                let (a, b) = (t.mass(lam), segment_mass_inside(c, lam));
                assert!((a - b).abs() < 1e-6, "c {c} lambda {lam}: table {a} direct {b}");
            }
            assert!((t.mass(40.0) - segment_mass_inside(c, 40.0)).abs() < 1e-9);
        }
    }

    #[test]
    fn segment_kernel_integrates_to_one() {
        // Quadrature in coordinates along the segment (s) and across it
        // (rho), where the capsule is exact: int K dV = int ds int 2 pi rho
        // K(s, rho) drho, rho < R on the cylinder 0 <= s <= L, rho < R sin th
        // on the caps (s = -R cos th, s = L + R cos th, ds = R sin th dth, no
        // square-root end point). Simpson with 200 intervals on smooth
        // integrands: error below 1e-8. This checks M_seg (the derivation
        // of the module documentation) independently of its own quadrature;
        // without it the integral would be M_seg, 6e-4 to 0.4 short.
        let pi = std::f64::consts::PI;
        let simpson = |lo: f64, hi: f64, f: &dyn Fn(f64) -> f64| {
            let n = 200;
            let h = (hi - lo) / n as f64;
            let mut s = f(lo) + f(hi);
            for k in 1..n {
                s += f(lo + k as f64 * h) * if k % 2 == 1 { 4.0 } else { 2.0 };
            }
            s * h / 3.0
        };
        for (r, c) in [(0.5, 2.5), (0.3, 1.5), (0.8, 4.0)] {
            for lam in [0.01, 0.1, 1.0, 3.0, 20.0] {
                let k = Kernel::new(r, c);
                let len = lam * r;
                let a = DVec3::new(0.1, -0.2, 0.3);
                let d = DVec3::new(1.0, 2.0, -0.5).normalize();
                let b = a + d * len;
                let perp = d.any_orthonormal_vector();
                let m = segment_mass_inside(c, lam);
                let big_r = c * r * (1.0 - 1e-12);
                let kern = |s: f64, rho: f64| 2.0 * pi * rho * segment_kernel_with_mass(&k, m, a, b, a + d * s + perp * rho);
                let cyl = simpson(0.0, len, &|s| simpson(0.0, big_r, &|rho| kern(s, rho)));
                let cap = |th: f64, s: f64| big_r * th.sin() * simpson(0.0, big_r * th.sin(), &|rho| kern(s, rho));
                let caps = simpson(0.0, 0.5 * pi, &|th| cap(th, -big_r * th.cos()) + cap(th, len + big_r * th.cos()));
                let total = cyl + caps;
                assert!((total - 1.0).abs() < 1e-7, "r {r} c {c} lambda {lam}: {total}");
                assert!(1.0 - m > 1e-4, "test too weak: M_seg = {m}");
            }
        }
    }

    #[test]
    fn segment_kernel_is_the_limit_of_point_photons_along_it() {
        // n point photons of power 1/n at the midpoints of n equal pieces of
        // the segment. With c = 6 the truncations differ by less than
        // e^{-18} = 1.5e-8 of the peak, so this tests the closed form; the
        // midpoint rule's error is (L/n)^2 / 24 max|d^2 G / ds^2| <= (L/n)^2
        // / 24 * 2 G_max / r^2: below 2e-7 of the peak for L = 3 r, n = 2000.
        let (r, c) = (0.4, 6.0);
        let k = Kernel::new(r, c);
        let peak = k.eval_d2(0.0);
        let a = DVec3::new(3.0, 1.0, 100.0);
        let b = a + DVec3::new(0.3, -0.5, -1.0).normalize() * 3.0 * r;
        let n = 2000;
        let pts: Vec<Photon> = (0..n)
            .map(|i| {
                let p = a + (b - a) * ((i as f64 + 0.5) / n as f64);
                Photon::point(p.as_vec3().to_array(), [1.0 / n as f32; 3])
            })
            .collect();
        // The f32 photon positions move the points by ~1e-5 km: the kernel's
        // gradient (G / r per r) makes that 3e-5 of the peak.
        let mut rr = rng::rng(&[21]);
        for _ in 0..200 {
            let x = a + DVec3::new(rr.random::<f64>() - 0.5, rr.random::<f64>() - 0.5, rr.random::<f64>() - 0.5) * 4.0 * r
                + (b - a) * rr.random::<f64>();
            let want = estimate_brute_force(&pts, x, &k)[0];
            let got = segment_kernel(&k, a, b, x);
            assert!((got - want).abs() < 5e-5 * peak, "{x}: segment {got} points {want} (peak {peak})");
        }
        // Zero length: the point kernel, exactly; a tiny segment: within its
        // first-order mass change (0.06 lambda) plus f64 cancellation.
        for x in [a, a + DVec3::splat(0.2), a + DVec3::X * 0.9] {
            assert_eq!(segment_kernel(&k, a, a, x), k.eval_d2(a.distance_squared(x)));
            let k25 = Kernel::new(r, 2.5);
            let tiny = segment_kernel(&k25, a, a + DVec3::Z * 1e-6 * r, x);
            let point = k25.eval_d2(a.distance_squared(x));
            assert!((tiny - point).abs() <= 1e-6 * k25.eval_d2(0.0), "{tiny} vs {point}");
        }
    }

    fn segment_photons(n: usize, seed: u64) -> Vec<Photon> {
        // Beam-like steps of 0 to 1.2 km along a tilted direction in a 6 km
        // box, a few points among them.
        let mut r = rng::rng(&[seed]);
        (0..n)
            .map(|i| {
                let a = DVec3::new(r.random::<f64>() * 6.0, r.random::<f64>() * 6.0, r.random::<f64>() * 6.0);
                let d = DVec3::new(r.random::<f64>() - 0.5, r.random::<f64>() - 0.5, -2.0).normalize();
                let len = if i % 10 == 0 { 0.0 } else { 1.2 * r.random::<f64>() };
                let b = a + d * len;
                Photon::segment(a.as_vec3().to_array(), b.as_vec3().to_array(), [1e19, 5e18, 2e18])
            })
            .collect()
    }

    /// One beam-like path: `n` contiguous steps of 0 to 1 km, each 2 to 5
    /// degrees off a steep B, power per step proportional to its drop in
    /// altitude times a smooth profile (like Fang's per-step deposits).
    fn beam_path(n: usize, seed: u64) -> Vec<Photon> {
        let mut r = rng::rng(&[seed]);
        let b = DVec3::new(0.0, 0.22, -0.975).normalize();
        let u = b.cross(DVec3::X).normalize();
        let v = b.cross(u);
        let mut p = DVec3::new(3.0, 3.0, 40.0);
        (0..n)
            .map(|_| {
                let s = r.random::<f64>();
                let alpha = (2.0 + 3.0 * r.random::<f64>()).to_radians();
                let beta = std::f64::consts::TAU * r.random::<f64>();
                let q = p + b * s + (u * beta.cos() + v * beta.sin()) * s * alpha.tan();
                let rate = 1.0 + 0.5 * (0.3 * q.z).sin();
                let w = (p.z - q.z) * rate * 1e19;
                let ph = Photon::segment(p.as_vec3().to_array(), q.as_vec3().to_array(), [w as f32, (0.5 * w * (1.0 + 0.01 * q.z)) as f32, (0.2 * w) as f32]);
                p = q;
                ph
            })
            .collect()
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
        let kink = [
            Photon::segment([0.0, 0.0, 0.0], [0.0, 0.0, -0.5], [1.0; 3]),
            Photon::segment([0.0, 0.0, -0.5], [0.3, 0.0, -1.0], [1.0; 3]),
        ];
        assert_eq!(merge_segments(&kink, |_| 0.5, MERGE_LEN_R, MERGE_OFF_R, MERGE_CDF).len(), 2);
        // Uneven power (all of it on the first of two equal steps) is not.
        let uneven = [
            Photon::segment([0.0, 0.0, 0.0], [0.0, 0.0, -0.5], [1.0; 3]),
            Photon::segment([0.0, 0.0, -0.5], [0.0, 0.0, -1.0], [0.01; 3]),
        ];
        assert_eq!(merge_segments(&uneven, |_| 0.5, MERGE_LEN_R, MERGE_OFF_R, MERGE_CDF).len(), 2);
        let even = [uneven[0], Photon::segment([0.0, 0.0, -0.5], [0.0, 0.0, -1.0], [1.0; 3])];
        assert_eq!(merge_segments(&even, |_| 0.5, MERGE_LEN_R, MERGE_OFF_R, MERGE_CDF), vec![Photon::segment([0.0, 0.0, 0.0], [0.0, 0.0, -1.0], [2.0; 3])]);
    }

    #[test]
    fn segment_gathers_match_the_f64_oracle_and_each_other() {
        let photons = segment_photons(1500, 22);
        let rf = RadiusField::new(0.4, 0.3, 0.2, DVec3::new(0.0, 0.2, -1.0).normalize(), 10.0, &[1]);
        let tr = Transform::new(0.5, DVec3::ZERO);
        let g = gather_grid(&photons, tr, &rf, 2.5, GatherMethod::Kdtree, &NoProgress);
        assert!(g.active_voxel_count() > 1000);
        let vmax = g.iter_active().map(|(_, v)| v[0]).fold(0.0f32, f32::max) as f64;
        // Per voxel: each term's f32 kernel is within 1e-5 relative of the
        // f64 closed form where the erf difference is large (erf 2.5e-7
        // absolute, exp 1e-6, the table 1e-6), within 1e-4 of the point
        // kernel's peak for lambda below MIDPOINT_LAMBDA (module
        // documentation); so 1e-4 of the voxel plus an absolute 1e-6 of the
        // grid's largest value for the erf's absolute error at the caps.
        let mut checked = 0;
        for (ijk, v) in g.iter_active().step_by(5) {
            let b = voxel_brute(&photons, &g, &rf, 2.5, ijk);
            for k in 0..3 {
                let tol = 1e-4 * b[k].abs() + 1e-6 * vmax;
                assert!((v[k] as f64 - b[k]).abs() <= tol, "{ijk}: {v:?} vs {b:?}");
            }
            checked += 1;
        }
        assert!(checked > 200);
        // Completeness: voxels outside the grid's leaves see no photon.
        for i in -6..20 {
            for j in [-6, 19] {
                let ijk = IVec3::new(i, j, i.rem_euclid(13));
                if !g.is_active(ijk) {
                    assert_eq!(voxel_brute(&photons, &g, &rf, 2.5, ijk), [0.0; 3], "{ijk}");
                }
            }
        }
        // Constant radius: balloon and splat are the same sum in the same
        // order, through different f32 code (row lanes, the midpoint via the
        // point path, against the scalar path): each within the oracle's
        // tolerance of the other.
        let rc = RadiusField::constant(0.35);
        let a = gather_grid(&photons, tr, &rc, 2.5, GatherMethod::Kdtree, &NoProgress);
        let s = gather_grid(&photons, tr, &rc, 2.5, GatherMethod::Splat, &NoProgress);
        assert_eq!(a.active_voxel_count(), s.active_voxel_count());
        let amax = a.iter_active().map(|(_, v)| v[0]).fold(0.0f32, f32::max);
        for (ijk, v) in a.iter_active() {
            let w = s.get(ijk);
            for k in 0..3 {
                assert!((v[k] - w[k]).abs() <= 2e-4 * w[k].abs() + 2e-6 * amax, "{ijk}: {v:?} vs {w:?}");
            }
        }
    }

    #[test]
    fn segment_grid_holds_the_photons_power() {
        // Sum of the grid times the voxel volume = total power / 1e19 (kR per
        // km), photons well inside: the midpoint rule on voxels of r / 4 has
        // the capsule-surface error of `segment_kernel_integrates_to_one`,
        // under 2 % per photon at h = r / 4, and it averages over photons.
        let photons = segment_photons(300, 23);
        let rf = RadiusField::constant(0.4);
        let vs = 0.1;
        let g = gather_grid(&photons, Transform::new(vs, DVec3::ZERO), &rf, 2.5, GatherMethod::Splat, &NoProgress);
        let sum: f64 = g.iter_active().map(|(_, v)| v[0] as f64).sum::<f64>() * vs * vs * vs;
        let want = photons.len() as f64;
        assert!((sum / want - 1.0).abs() < 0.01, "{sum} vs {want}");
    }

    #[test]
    fn uniform_photons_give_a_constant_estimate() {
        // N photons of power P uniform in a box of volume V: E[eta] = N P / V
        // inside (the kernel integrates to 1 and is fully inside), and
        // Var[eta] = N (E[(P K)^2] - E[P K]^2) = (N P^2 / V) int K^2 - (N P^2 / V^2),
        // with int K^2 = 1 / (M(c)^2 (4 pi)^(3/2) r^3) * M(c sqrt 2) (the
        // square of a Gaussian of sd r is one of sd r / sqrt 2). Test at 5 sigma.
        let (n, side, r, c) = (200_000usize, 20.0f64, 1.0, 3.0);
        let photons = uniform_box(n, 0.0, side, 2.0, 7);
        let k = Kernel::new(r, c);
        let map = PhotonMap::new(&photons);
        let v = side.powi(3);
        let mean = n as f64 * 2.0 / v;
        let mc = gaussian_mass_inside(c);
        let int_k2 = gaussian_mass_inside(c * 2f64.sqrt()) / (mc * mc * (4.0 * std::f64::consts::PI).powf(1.5) * r.powi(3));
        let var = n as f64 * 4.0 / v * int_k2 - n as f64 * 4.0 / (v * v);
        let sigma = var.sqrt();
        let mut r_ = rng::rng(&[8]);
        for _ in 0..20 {
            // Points at least c r from every face.
            let x = DVec3::new(
                4.0 + 12.0 * r_.random::<f64>(),
                4.0 + 12.0 * r_.random::<f64>(),
                4.0 + 12.0 * r_.random::<f64>(),
            );
            let e = map.estimate(x, &k);
            assert!((e[0] - mean).abs() < 5.0 * sigma, "{} vs {mean} +- {sigma}", e[0]);
            assert!((e[1] - 0.5 * e[0]).abs() < 1e-12 * e[0]);
        }
    }

    #[test]
    fn doubling_the_photons_doubles_the_estimate() {
        let photons = uniform_box(5_000, 0.0, 10.0, 1.0, 9);
        let doubled: Vec<Photon> = photons.iter().chain(photons.iter()).cloned().collect();
        let k = Kernel::new(0.8, 3.0);
        let (a, b) = (PhotonMap::new(&photons), PhotonMap::new(&doubled));
        for x in [DVec3::splat(5.0), DVec3::new(2.0, 7.0, 4.0)] {
            let (ea, eb) = (a.estimate(x, &k), b.estimate(x, &k));
            // Same terms, each twice: equal to 2x up to summation rounding.
            assert!((eb[0] - 2.0 * ea[0]).abs() < 1e-12 * eb[0], "{ea:?} {eb:?}");
        }
    }

    #[test]
    fn kdtree_gather_matches_brute_force() {
        // Clustered photons (a thin sheet, like a curtain) and random queries.
        let mut r = rng::rng(&[10]);
        let photons: Vec<Photon> = (0..20_000)
            .map(|_| {
                Photon::point(
                    [(r.random::<f64>() * 30.0) as f32, (r.random::<f64>() * 1.5) as f32, (100.0 + r.random::<f64>() * 30.0) as f32],
                    [r.random::<f32>(), r.random::<f32>(), r.random::<f32>()],
                )
            })
            .collect();
        let map = PhotonMap::new(&photons);
        for i in 0..200 {
            let k = Kernel::new(0.3 + 0.01 * (i % 50) as f64, 3.0);
            let x = DVec3::new(r.random::<f64>() * 30.0, r.random::<f64>() * 3.0 - 0.75, 100.0 + r.random::<f64>() * 30.0);
            let (a, b) = (map.estimate(x, &k), estimate_brute_force(&photons, x, &k));
            // Same photons in the same (index) order: identical sums.
            assert_eq!(a, b, "query {i} at {x}");
        }
    }

    #[test]
    fn empty_neighbourhood_gives_zero_not_nan() {
        let photons = uniform_box(100, 0.0, 1.0, 1.0, 11);
        let k = Kernel::new(0.1, 3.0);
        assert_eq!(PhotonMap::new(&photons).estimate(DVec3::splat(50.0), &k), [0.0; 3]);
        assert_eq!(PhotonMap::new(&[]).estimate(DVec3::ZERO, &k), [0.0; 3]);
        let empty = gather_grid(&[], Transform::new(0.5, DVec3::ZERO), &RadiusField::constant(0.5), 3.0, GatherMethod::Kdtree, &NoProgress);
        assert_eq!(empty.leaf_count(), 0);
    }

    fn voxel_brute(photons: &[Photon], g: &Grid<[f32; 3]>, rf: &RadiusField, cutoff: f64, ijk: IVec3) -> [f64; 3] {
        let x = g.transform.index_to_world(ijk.as_dvec3());
        let e = estimate_brute_force(photons, x, &Kernel::new(rf.radius(x), cutoff));
        e.map(|v| v / PHOTONS_PER_KM2_S_PER_KR)
    }

    fn terms_in_reach(photons: &[Photon], g: &Grid<[f32; 3]>, rf: &RadiusField, cutoff: f64, ijk: IVec3) -> usize {
        let x = g.transform.index_to_world(ijk.as_dvec3());
        let k = Kernel::new(rf.radius(x), cutoff);
        photons.iter().filter(|p| k.eval_d2(pos(p).distance_squared(x)) > 0.0).count()
    }

    #[test]
    fn grid_gather_matches_per_voxel_brute_force_and_is_complete() {
        let photons = {
            let mut v = uniform_box(3_000, 0.0, 6.0, 1e19, 12);
            v.truncate(3_000);
            v
        };
        let rf = RadiusField::new(0.4, 0.3, 0.2, DVec3::new(0.0, 0.2, -1.0).normalize(), 10.0, &[1]);
        let tr = Transform::new(0.5, DVec3::ZERO);
        let g = gather_grid(&photons, tr, &rf, 3.0, GatherMethod::Kdtree, &NoProgress);
        assert!(g.active_voxel_count() > 1000);
        // Every active voxel equals the brute-force balloon estimate (f32
        // rounding of the stored value: relative 2^-24, plus summation order
        // which is the same).
        for (ijk, v) in g.iter_active().step_by(7) {
            let b = voxel_brute(&photons, &g, &rf, 3.0, ijk);
            let n = terms_in_reach(&photons, &g, &rf, 3.0, ijk) as f64;
            for k in 0..3 {
                // The grid evaluates each kernel in f32 (exponent |x| <= 4.5
                // rounded to 2^-24 relative, fast exp 1.2e-7, norm 2^-24: each
                // term within 1e-6 relative) and sums the n positive terms in
                // f32 (at most n 2^-24 relative), then rounds to f32.
                let tol = 1e-6 + (n + 1.0) * 2f64.powi(-24);
                assert!((v[k] as f64 - b[k]).abs() <= tol * b[k].abs(), "{ijk}: {v:?} vs {b:?} ({n} terms)");
            }
        }
        // And no voxel outside the grid's leaves has any photon in reach:
        // probe a shell of voxels around the photon box.
        for i in -6..20 {
            for j in [-6, 19] {
                let ijk = IVec3::new(i, j, i.rem_euclid(13));
                if !g.is_active(ijk) {
                    assert_eq!(voxel_brute(&photons, &g, &rf, 3.0, ijk), [0.0; 3], "{ijk}");
                }
            }
        }
    }

    #[test]
    fn splat_and_kdtree_agree_for_a_constant_radius() {
        // With r(x) constant the balloon and sample-point estimators are the
        // same sum; only the f64 terms' order could differ, and it does not.
        let photons = uniform_box(4_000, 0.0, 5.0, 3e19, 13);
        let rf = RadiusField::constant(0.35);
        let tr = Transform::new(0.25, DVec3::ZERO);
        let a = gather_grid(&photons, tr, &rf, 3.0, GatherMethod::Kdtree, &NoProgress);
        let b = gather_grid(&photons, tr, &rf, 3.0, GatherMethod::Splat, &NoProgress);
        assert_eq!(a, b);
        // report2014 averages: inside the box its value is about one photon's
        // power (3e19 / 1e19 = 3 in red), whatever the photon count.
        let c = gather_grid(&photons, tr, &rf, 3.0, GatherMethod::Report2014, &NoProgress);
        let v = c.get(IVec3::splat(10));
        assert!((v[0] - 3.0).abs() < 1e-3, "{v:?}");
    }

    #[test]
    fn gather_is_independent_of_thread_count() {
        // Points, loose segments and beam paths (merged runs), with more
        // photons than one binning chunk (2^14).
        let mut photons = uniform_box(5_000, 0.0, 8.0, 1e19, 14);
        photons.extend(segment_photons(2_000, 15));
        for k in 0..200 {
            photons.extend(beam_path(60, 100 + k));
        }
        assert!(photons.len() > 1 << 14);
        let rf = RadiusField::new(0.5, 0.3, 0.1, DVec3::NEG_Z, 0.0, &[3]);
        let tr = Transform::new(0.5, DVec3::ZERO);
        for method in [GatherMethod::Kdtree, GatherMethod::Splat] {
            let run = |threads| {
                rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap().install(|| gather_grid(&photons, tr, &rf, 3.0, method, &NoProgress))
            };
            let (a, b) = (run(1), run(3));
            assert_eq!(a, b, "{method:?}");
            let la: Vec<_> = a.leaves().iter().map(|l| l.origin).collect();
            let lb: Vec<_> = b.leaves().iter().map(|l| l.origin).collect();
            assert_eq!(la, lb);
        }
    }
}
