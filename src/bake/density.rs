//! The density grid: air extinction on the emission's active voxels, and the
//! aurora indicator that keeps it to where the aurora is.

use crate::earth::Earth;
use crate::grid::{Grid, Leaf};
use crate::photons;
use crate::scene::GridParams;
use crate::spectrum::luminance;
use rayon::prelude::*;

/// `indicator = 1 - exp(-Y / (AURORA_FRACTION * Y_peak))`, about 1 wherever
/// the aurora is within a few percent of its peak, falling smoothly to 0 in
/// its faint fringes.
pub const AURORA_FRACTION: f64 = 0.01;

/// Largest air extinction stored, per km (the top of `density_a`'s range).
/// `density_a exp(-density_b (h - density_base_km))` grows without bound
/// below the base altitude and overflows f32 (and then f64) for steep
/// profiles; at 10^6 per km a metre of path has optical depth 10^3, so any
/// voxel is opaque and larger values change nothing but the risk of
/// infinity. Clamped voxels are reported by a warning.
pub const MAX_EXTINCTION_PER_KM: f64 = 1e6;

/// The density grid on the emission's active voxels:
/// `density_a exp(-density_b (h - density_base_km))` (the report's air
/// density, per km; [`extinction`], clamped at [`MAX_EXTINCTION_PER_KM`]) times an aurora indicator in [0, 1] that saturates
/// smoothly in the emission's luminance relative to [`AURORA_FRACTION`] of the
/// peak. No fog box: only where the aurora is. `h` is the voxel's altitude
/// above `earth` (`crate::earth`: z when flat).
pub fn density_grid(emission: &Grid<[f32; 3]>, params: &GridParams, peak_luminance: f64, earth: &Earth) -> Grid<f32> {
    let tr = emission.transform;
    let scale = AURORA_FRACTION * peak_luminance;
    let inv_scale = if scale > 0.0 { (1.0 / scale) as f32 } else { 0.0 };
    let leaves: Vec<Leaf<f32>> = emission
        .leaves()
        .par_iter()
        .map(|l| {
            // The air depends on the altitude only: on a flat ground once
            // per z of the leaf, on a sphere per voxel.
            let air: [f64; 8] =
                std::array::from_fn(|z| extinction(params, tr.index_to_world((l.origin + glam::IVec3::new(0, 0, z as i32)).as_dvec3()).z));
            let round = !earth.is_flat();
            let mut out = Leaf::new(l.origin, 0.0f32);
            out.mask = l.mask;
            for n in 0..crate::grid::LEAF_NUM_VALUES {
                if l.is_active(n) {
                    let v = l.values[n];
                    let y = luminance([v[0] as f64, v[1] as f64, v[2] as f64]).max(0.0);
                    // 1 - exp(-y / scale) in f32: within 2e-7 of the f64
                    // value (exp_neg_f32's 1.2e-7 relative plus rounding);
                    // 0 when scale is.
                    let indicator = 1.0 - photons::fast_math::exp_neg_f32(-(y as f32) * inv_scale);
                    let a = if round {
                        let ijk = l.origin + crate::grid::offset_to_local(n);
                        extinction(params, earth.altitude(tr.index_to_world(ijk.as_dvec3())))
                    } else {
                        air[n & 7]
                    };
                    out.values[n] = (a * indicator as f64) as f32;
                }
            }
            out
        })
        .collect();
    let mut g = Grid::new("density", 0.0f32, tr);
    for l in leaves {
        g.insert_leaf(l);
    }
    g.sort_leaves();
    g
}

/// The air extinction at altitude `h` km, per km:
/// `density_a exp(-density_b (h - density_base_km))`, at most
/// [`MAX_EXTINCTION_PER_KM`] (and 0, not NaN, when `density_a` is 0).
pub fn extinction(params: &GridParams, h: f64) -> f64 {
    if params.density_a > 0.0 {
        (params.density_a * (-params.density_b * (h - params.density_base_km)).exp()).min(MAX_EXTINCTION_PER_KM)
    } else {
        0.0
    }
}

/// A warning when the air extinction reaches [`MAX_EXTINCTION_PER_KM`] at
/// the lowest altitude `h_min` km of the grid (it decreases with altitude).
pub fn extinction_warning(params: &GridParams, h_min: f64) -> Option<String> {
    let raw = params.density_a * (-params.density_b * (h_min - params.density_base_km)).exp();
    (params.density_a > 0.0 && raw >= MAX_EXTINCTION_PER_KM).then(|| {
        format!(
            "air extinction clamped: grid.density_a exp(-density_b (h - density_base_km)) reaches {raw:.3e} per km at {h_min:.1} km, above the maximum {MAX_EXTINCTION_PER_KM:e} (opaque); density is clamped there"
        )
    })
}
