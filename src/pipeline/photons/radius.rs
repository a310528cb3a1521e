//! The kernel radius as a function of position.
//!
//! The 2014 report perturbs the photon map's kernel radius by a 2D noise of
//! medium frequency: `r(x) = base (1 + amp n)`, n a Perlin gradient noise
//! in [-1, 1] (the `noise` crate's, through [`crate::util::rng::noise2`]) at
//! `freq` cycles per km. The noise is taken at the point's
//! field-line foot, its projection along B onto the altitude `z_ref`, so
//! the variation follows the magnetic field lines: rays along B. The
//! balloon gather takes r at the voxel, the splat at the photon (a
//! segment's at its midpoint).

use crate::util::rng;
use glam::DVec3;
use noise::Perlin;

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
