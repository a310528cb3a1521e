//! The kernels of the density estimate and their masses, in f64 (the
//! oracle every gather is tested against) and as the f32 constants the
//! leaf loops read ([`KernelF32`]). Lengths in km; a kernel integrates to 1,
//! so each photon's kernel integrates to its power.
//!
//! **Point kernel** ([`Kernel`], `photons.kernel = "point"`, each step's
//! power at its end): the 3D Gaussian of standard deviation r (the kernel
//! radius), `G_r(d) = exp(-d^2 / 2r^2) / ((2 pi)^(3/2) r^3)`, truncated at
//! the reach `c r` (c the cutoff) and renormalised by its mass inside,
//! `M(c) = erf(c / sqrt2) - sqrt(2 / pi) c e^{-c^2/2}` ([`gaussian_mass_inside`]).
//!
//! **Segment kernel** (`photons.kernel = "segment"`, default): a beam step
//! deposits its power uniformly along the segment from `a` to `b` (length L,
//! direction d), a short photon beam (Jarosz, Nowrouzezahrai, Sadeghi &
//! Jensen, "A Comprehensive Theory of Volumetric Radiance Estimation Using
//! Photon Points and Beams", ACM TOG 30(1), 2011). With `x - a = s d + p`:
//!
//! ```text
//! K_seg(x) = exp(-|p|^2 / 2r^2) / (2 pi r^2)                         (across)
//!          * [erf(s / (sqrt2 r)) - erf((s - L) / (sqrt2 r))] / (2 L)   (along)
//! ```
//!
//! truncated where the distance to the segment reaches `c r` (a capsule)
//! and renormalised by its mass inside; with lambda = L / r, u = s / r,
//! `g(u) = (Phi(u) - Phi(u - lambda)) / lambda` (Phi the normal CDF):
//!
//! ```text
//! M_seg(lambda) = (1 - e^{-c^2/2}) A(lambda) + 2 int_{-c}^0 g(u) (1 - e^{-(c^2 - u^2)/2}) du
//! A(lambda)     = int_0^lambda g = erf(lambda / sqrt2) - (2 / lambda) (phi(0) - phi(lambda))
//! ```
//!
//! (the cylinder and the two half balls; the half-ball integral is tabulated
//! over lambda once per bake, [`SegmentMass`]). `M_seg(0) = M(c)`: a
//! zero-length segment is the point kernel, which the gathers take for L = 0,
//! and the midpoint's below lambda = [`MIDPOINT_LAMBDA`], where f32 erf
//! cancellation costs more than the difference. Unlike points, the estimate
//! does not ripple along the path at the step length. Derivation and error
//! figures: docs/physics.md, "The segment kernel's mass".
//!
//! [`photon_kernel`] and [`estimate_brute_force`] evaluate these in f64 for
//! one photon and for a photon list: the estimate the gathers are held to.

use crate::pipeline::deposit::{end, pos, Photon};
use crate::util::fmath;
use glam::DVec3;
use rayon::prelude::*;

/// Mass of the standard 3D Gaussian inside radius `c` (in standard
/// deviations): `erf(c / sqrt 2) - sqrt(2 / pi) c exp(-c^2 / 2)`, computed by
/// composite Simpson integration of `4 pi r^2 phi(r)` (4096 intervals: error
/// far below 1e-12 for c <= 6).
pub fn gaussian_mass_inside(c: f64) -> f64 {
    let n = 4096;
    let h = c / n as f64;
    let f = |r: f64| 4.0 * std::f64::consts::PI * r * r * fmath::exp(-0.5 * r * r) / fmath::powf(2.0 * std::f64::consts::PI, 1.5);
    let mut s = f(0.0) + f(c);
    for k in 1..n {
        s += f(k as f64 * h) * if k % 2 == 1 { 4.0 } else { 2.0 };
    }
    s * h / 3.0
}

/// Standard normal density.
#[inline]
fn phi(u: f64) -> f64 {
    fmath::exp(-0.5 * u * u) / (2.0 * std::f64::consts::PI).sqrt()
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
    let f = |u: f64| h(u) * (1.0 - fmath::exp(-0.5 * (c * c - u * u)));
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
    (1.0 - fmath::exp(-0.5 * c * c)) * along_mass_inside(lambda) + 2.0 * half_ball(c, g)
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
            return (1.0 - fmath::exp(-0.5 * c * c)) * along_mass_inside(lambda) + 2.0 * self.h_inf / lambda;
        }
        let x = lambda * Self::STEPS_PER_UNIT;
        let k = x as usize;
        let f = x - k as f64;
        self.table[k] as f64 * (1.0 - f) + self.table[k + 1] as f64 * f
    }
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
    let dist2 = if s < 0.0 {
        w.length_squared()
    } else if s > len {
        x.distance_squared(b)
    } else {
        perp2
    };
    if dist2 >= kernel.reach2 {
        return 0.0;
    }
    let r = kernel.r;
    let k = 1.0 / std::f64::consts::SQRT_2 / r;
    fmath::exp(-perp2 * kernel.inv_2r2) / (2.0 * std::f64::consts::PI * r * r) * (libm::erf(s * k) - libm::erf((s - len) * k))
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
        let norm = 1.0 / (fmath::powf(2.0 * std::f64::consts::PI, 1.5) * r * r * r * mass);
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
            self.norm * fmath::exp(-d2 * self.inv_2r2)
        } else {
            0.0
        }
    }

    /// The unnormalised weight exp(-d^2 / 2r^2) inside the cutoff (report2014).
    #[inline]
    pub(super) fn weight_d2(&self, d2: f64) -> f64 {
        if d2 < self.reach2 {
            fmath::exp(-d2 * self.inv_2r2)
        } else {
            0.0
        }
    }
}

/// A [`Kernel`]'s constants in f32, as the leaf loops read them (the point
/// form's and the segment form's), and its reach in f64: the kernel at a
/// voxel in the balloon, a photon's own kernel in the splat (by whose reach
/// the photon is binned).
#[derive(Clone, Copy, Debug, Default)]
pub struct KernelF32 {
    /// 1 / r.
    pub inv_r: f32,
    /// 1 / (sqrt 2 r).
    pub inv_sqrt2r: f32,
    /// 1 / (2 r^2).
    pub inv_2r2: f32,
    /// 1 / (2 pi r^2).
    pub inv_2pi_r2: f32,
    /// (c r)^2.
    pub reach2: f32,
    /// The point kernel's norm, 1 / ((2 pi)^(3/2) r^3 M(c)).
    pub norm: f32,
    /// c r, km.
    pub reach: f64,
}

impl KernelF32 {
    pub fn new(k: &Kernel) -> Self {
        let r = k.r;
        Self {
            inv_r: (1.0 / r) as f32,
            inv_sqrt2r: (1.0 / (std::f64::consts::SQRT_2 * r)) as f32,
            inv_2r2: k.inv_2r2 as f32,
            inv_2pi_r2: (1.0 / (2.0 * std::f64::consts::PI * r * r)) as f32,
            reach2: k.reach2 as f32,
            norm: k.norm as f32,
            reach: k.reach(),
        }
    }
}

/// The photon's kernel at x (point or segment), f64.
#[inline]
pub fn photon_kernel(p: &Photon, kernel: &Kernel, x: DVec3) -> f64 {
    if p.is_point() {
        kernel.eval_d2(pos(p).distance_squared(x))
    } else {
        segment_kernel(kernel, pos(p), end(p), x)
    }
}

/// eta(x) = sum_i Phi_i K_i(x) by brute force over every photon, photons
/// km^-3 s^-1 per colour, in photon order: the oracle of the gathers.
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::util::rng;
    use rand::Rng;

    #[test]
    fn truncated_kernel_integrates_to_one() {
        // Closed form of the truncated mass for c = 3: erf(3/sqrt2) - sqrt(2/pi) 3 e^-4.5.
        let m = gaussian_mass_inside(3.0);
        assert!((m - (0.997_300_203_936_740 - (2.0 / std::f64::consts::PI).sqrt() * 3.0 * fmath::exp(-4.5f64))).abs() < 1e-12, "{m}");
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
            let bound = 4.0 * std::f64::consts::PI * fmath::powi(c * r, 2) * 0.5 * h * jump + 1e-6;
            assert!(bound < 0.5 * (1.0 - gaussian_mass_inside(c)) || c > 5.0, "test too weak for c = {c}");
            assert!((s - 1.0).abs() < bound, "r {r} c {c}: {s} (bound {bound})");
        }
    }

    #[test]
    fn inverse_mass_table_matches_the_direct_mass() {
        // Linear interpolation in the table of 1 / M_seg: below 3e-7 (see
        // SegmentMass); 1e-6 leaves room.
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
            assert!((segment_mass_inside(c, 1e6) - (1.0 - fmath::exp(-0.5 * c * c))).abs() < 1e-5);
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
                let cap = |th: f64, s: f64| big_r * fmath::sin(th) * simpson(0.0, big_r * fmath::sin(th), &|rho| kern(s, rho));
                let caps = simpson(0.0, 0.5 * pi, &|th| cap(th, -big_r * fmath::cos(th)) + cap(th, len + big_r * fmath::cos(th)));
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
            let x = a
                + DVec3::new(rr.random::<f64>() - 0.5, rr.random::<f64>() - 0.5, rr.random::<f64>() - 0.5) * 4.0 * r
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
}
