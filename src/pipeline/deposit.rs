//! What a beam step leaves behind, as plain data: the [`Photon`] the gather
//! (`crate::pipeline::photons`) convolves with its kernel, and the [`StepDeposit`]
//! (altitudes and electron power) that `aurora profile` bins and the energy
//! accounting sums. The beam stage (`crate::pipeline::beams`) makes both, one of each
//! per step; nothing here knows how.
//!
//! Units: positions km (z up), photon power linear Rec.709 RGB in "557.7 nm
//! photons per second" (one photon per second of 557.7 nm has luminance 1;
//! `crate::physics::emission::line_colour`), deposited power keV/s.

use glam::DVec3;

/// A photon of the photon map: a segment from `position` to `end` (km; a
/// point photon has `end == position`) and the power emitted along it,
/// spread uniformly, as linear Rec.709 RGB in "557.7 nm photons per second"
/// (one photon per second of 557.7 nm has luminance 1; see `spectrum`). The
/// gather convolves its kernel with the segment (`crate::pipeline::photons`, photon
/// beams of Jarosz et al. 2011).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Photon {
    pub position: [f32; 3],
    pub end: [f32; 3],
    pub power: [f32; 3],
}

impl Photon {
    /// A point photon at `p`.
    #[inline]
    pub fn point(p: [f32; 3], power: [f32; 3]) -> Self {
        Self { position: p, end: p, power }
    }

    /// A segment photon from `a` to `b`.
    #[inline]
    pub fn segment(a: [f32; 3], b: [f32; 3], power: [f32; 3]) -> Self {
        Self { position: a, end: b, power }
    }

    /// The same power as a point photon at the segment's end (the deflection
    /// point where the point estimator of `photons.kernel = "point"` puts it).
    #[inline]
    pub fn to_point(self) -> Self {
        Self::point(self.end, self.power)
    }

    /// Whether the photon is a point (zero-length segment).
    #[inline]
    pub fn is_point(&self) -> bool {
        self.position == self.end
    }
}

/// A photon's position (its segment's start), f64.
#[inline]
pub fn pos(p: &Photon) -> DVec3 {
    DVec3::new(p.position[0] as f64, p.position[1] as f64, p.position[2] as f64)
}

/// A photon's segment end (its position for a point photon), f64.
#[inline]
pub fn end(p: &Photon) -> DVec3 {
    DVec3::new(p.end[0] as f64, p.end[1] as f64, p.end[2] as f64)
}

/// One step's deposit: from altitude `z_start` to `z_end` km, `power_kev_s`,
/// and the local ionization rate `q` (ion pairs cm^-3 s^-1) its colour was
/// taken at (0 when the colours do not depend on it).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StepDeposit {
    pub z_start: f64,
    pub z_end: f64,
    pub power_kev_s: f64,
    pub q: f64,
}
