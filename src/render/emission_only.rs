//! The primary ray through a medium without extinction: the emission's
//! plain line integral, exact per dual cell, with no transmittance to carry.
//!
//! Model. With sigma_t = 0 everywhere (no density grid, an empty one, or
//! `volume.density_scale = 0`) the emission-absorption integral of the
//! renderer's module doc reduces to `L = int_0^d e(s) ds`: the order of the
//! cells no longer matters and no `exp` is needed. Inside a dual cell the
//! field is trilinear (Cycles' lookup, docs/guide.md, "How Cycles reads the
//! VDB"), so on the ray's segment `[t0, t1]` of the cell it is a cubic in
//! the segment parameter, and its integral is a fixed linear form in the 8
//! corner values: `int = len * sum_k w_k v_k` with `w_k` the integral of
//! corner k's trilinear weight along the segment. That weight is a product
//! of three linear functions (a cubic), so Simpson's rule on the segment's
//! ends and midpoint gives it exactly (Abramowitz & Stegun 25.4.5: the rule
//! is exact for cubics). The three channels share the weights: per cell,
//! 24 multiply-adds after the weights, against the general walk's three
//! cubics and its transmittance.
//!
//! The cells are the general walk's ([`LeafWalker`], [`CellWalker`] with
//! [`CellFilter::Any`]): the same segments, so the same support, and the
//! result equals the general path's up to rounding (both integrate the cubic
//! exactly). The air's transmittance and what lies behind the volume are
//! applied per sample by the pixel loop, as on the general path.

use super::dda::{CellFilter, CellSeg, CellWalker, IndexRay, LeafWalker};
use super::medium::field::Field;
use glam::DVec3;

/// `int_0^t_max e(origin + s dir) ds` (unit-length `dir`) of the three
/// emission channels starting at `channel` of `field`, scaled by the
/// field's scales, and the dual cells walked.
pub fn emission_integral(field: &Field, channel: usize, origin: DVec3, dir: DVec3, t_max: f64) -> ([f64; 3], u64) {
    let mut sum = [0.0f64; 3];
    let mut cells = 0u64;
    if !(t_max > 0.0) {
        return (sum, 0);
    }
    let leaves = LeafWalker::new(field, origin, dir, 0.0, t_max);
    let ray = leaves.ray;
    for span in leaves {
        for seg in CellWalker::new(field, ray, span, CellFilter::Any) {
            let len = seg.t1 - seg.t0;
            if !(len > 0.0) {
                continue;
            }
            let w = segment_weights(&ray, &seg);
            let mut s = [0.0f64; 3];
            for (k, &i) in seg.at.iter().enumerate() {
                for c in 0..3 {
                    s[c] += w[k] * field.values.get(i + channel + c) as f64;
                }
            }
            for c in 0..3 {
                sum[c] += len * s[c];
            }
            cells += 1;
        }
    }
    let k = &field.scale[channel..channel + 3];
    ([sum[0] * k[0], sum[1] * k[1], sum[2] * k[2]], cells)
}

/// The mean over the segment of each corner's trilinear weight (corner
/// order 000, 001, ..., 111 in (x, y, z), as [`CellSeg::at`]): Simpson's
/// rule on the segment's ends and midpoint, exact for the cubic each is.
#[inline]
fn segment_weights(ray: &IndexRay, seg: &CellSeg) -> [f64; 8] {
    let corner = seg.corner.as_dvec3();
    let at = |t: f64| (ray.at(t) - corner).to_array();
    let (a, m, b) = (at(seg.t0), at(0.5 * (seg.t0 + seg.t1)), at(seg.t1));
    let (wa, wm, wb) = (weights(a), weights(m), weights(b));
    std::array::from_fn(|k| (wa[k] + 4.0 * wm[k] + wb[k]) * (1.0 / 6.0))
}

/// The 8 trilinear weights at local point `p` of a dual cell.
#[inline]
fn weights(p: [f64; 3]) -> [f64; 8] {
    let [x, y, z] = p;
    let (x0, y0, z0) = (1.0 - x, 1.0 - y, 1.0 - z);
    let (a, b, c, d) = (x0 * y0, x0 * y, x * y0, x * y);
    [a * z0, a * z, b * z0, b * z, c * z0, c * z, d * z0, d * z]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Simpson's weights integrate a trilinear function along a line
    /// exactly: against the cubic's own integral, to rounding.
    #[test]
    fn segment_weights_integrate_the_trilinear_cubic() {
        use crate::render::segment::Cubic;
        let v = [0.3, 1.7, 0.0, 2.5, 0.9, 0.1, 3.3, 1.2];
        for (ua, ub) in [([0.0, 0.2, 0.9], [1.0, 0.7, 0.1]), ([0.5, 0.0, 0.5], [0.5, 1.0, 0.5]), ([0.1, 0.1, 0.1], [0.9, 0.95, 0.8])] {
            let want = Cubic::along(v, ua, ub).integral();
            let (wa, wm, wb) = (weights(ua), weights([0.5 * (ua[0] + ub[0]), 0.5 * (ua[1] + ub[1]), 0.5 * (ua[2] + ub[2])]), weights(ub));
            let got: f64 = (0..8).map(|k| (wa[k] + 4.0 * wm[k] + wb[k]) / 6.0 * v[k]).sum();
            assert!((got - want).abs() <= 1e-14 * want.abs(), "{got} vs {want}");
        }
    }
}
