//! The density grid: air extinction on the emission's active voxels, and the
//! aurora indicator that keeps it to where the aurora is.

use crate::geometry::earth::Earth;
use crate::grid::{Grid, Leaf, Transform};
use crate::pipeline::photons;
use crate::scene::GridParams;
use crate::util::colour::luminance;
use crate::util::fmath;
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
/// above `earth` (`crate::geometry::earth`: z when flat). With
/// `density_a` 0 (the physical, optically thin air) the grid has no
/// leaves: nothing to store, nothing for a renderer to integrate.
pub fn density_grid(emission: &Grid<[f32; 3]>, params: &GridParams, peak_luminance: f64, earth: &Earth) -> Grid<f32> {
    let tr = emission.transform;
    if params.density_a <= 0.0 {
        return Grid::from_leaves("density", 0.0f32, tr, Vec::new());
    }
    let scale = AURORA_FRACTION * peak_luminance;
    let inv_scale = if scale > 0.0 { (1.0 / scale) as f32 } else { 0.0 };
    let leaves: Vec<Leaf<f32>> = emission.leaves().par_iter().map(|l| density_leaf(l, params, inv_scale, earth, tr)).collect();
    Grid::from_leaves("density", 0.0f32, tr, leaves)
}

/// One leaf of [`density_grid`]. The air depends on the altitude only: on a
/// flat ground once per z of the leaf; on a sphere per voxel, the squared
/// distance from the Earth's axis through the voxel's column, `x^2 + y^2`,
/// once per column (the same sum `length` takes first, so the same bits).
fn density_leaf(l: &Leaf<[f32; 3]>, params: &GridParams, inv_scale: f32, earth: &Earth, tr: Transform) -> Leaf<f32> {
    let world = |i: i32, axis: usize| i as f64 * tr.voxel_size + tr.translation[axis];
    let mut out = Leaf::new(l.origin, 0.0f32);
    out.mask = l.mask;
    let air: [f64; 8] = std::array::from_fn(|z| extinction(params, world(l.origin.z + z as i32, 2)));
    let round = !earth.is_flat();
    // The altitude of a voxel in the column at x^2 + y^2 = `xy2`: its
    // distance from the centre (0, 0, -R), less R (`Earth::altitude`).
    let altitude = |xy2: f64, z: i32| {
        let vz = world(l.origin.z + z, 2) - earth.centre().z;
        (xy2 + vz * vz).sqrt() - earth.radius_km
    };
    for x in 0..8usize {
        let word = l.mask[x];
        if word == 0 {
            continue;
        }
        let px = world(l.origin.x + x as i32, 0);
        for y in 0..8usize {
            let mut bits = (word >> (8 * y)) & 0xFF;
            if bits == 0 {
                continue;
            }
            let py = world(l.origin.y + y as i32, 1);
            let xy2 = px * px + py * py;
            while bits != 0 {
                let z = bits.trailing_zeros() as usize;
                bits &= bits - 1;
                let n = 64 * x + 8 * y + z;
                let v = l.values[n];
                let lum = luminance([v[0] as f64, v[1] as f64, v[2] as f64]).max(0.0);
                // 1 - exp(-y / scale) in f32: within 2e-7 of the f64
                // value (exp_neg_f32's 1.2e-7 relative plus rounding); 0
                // when scale is.
                let indicator = 1.0 - photons::fast_math::exp_neg_f32(-(lum as f32) * inv_scale);
                let a = if round { extinction(params, altitude(xy2, z as i32)) } else { air[z] };
                out.values[n] = (a * indicator as f64) as f32;
            }
        }
    }
    out
}

/// The air extinction at altitude `h` km, per km:
/// `density_a exp(-density_b (h - density_base_km))`, at most
/// [`MAX_EXTINCTION_PER_KM`] (and 0, not NaN, when `density_a` is 0).
pub fn extinction(params: &GridParams, h: f64) -> f64 {
    if params.density_a > 0.0 {
        (params.density_a * fmath::exp(-params.density_b * (h - params.density_base_km))).min(MAX_EXTINCTION_PER_KM)
    } else {
        0.0
    }
}

/// A warning when the air extinction reaches [`MAX_EXTINCTION_PER_KM`] at
/// the lowest altitude `h_min` km of the grid (it decreases with altitude).
pub fn extinction_warning(params: &GridParams, h_min: f64) -> Option<String> {
    let raw = params.density_a * fmath::exp(-params.density_b * (h_min - params.density_base_km));
    (params.density_a > 0.0 && raw >= MAX_EXTINCTION_PER_KM).then(|| {
        format!(
            "air extinction clamped: grid.density_a exp(-density_b (h - density_base_km)) reaches {raw:.3e} per km at {h_min:.1} km, above the maximum {MAX_EXTINCTION_PER_KM:e} (opaque); density is clamped there"
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{DVec3, IVec3};

    #[test]
    fn density_leaves_are_the_per_voxel_formula_bit_for_bit() {
        // Random emission on leaves far from the origin, on a round Earth
        // and a flat one: each voxel is extinction(altitude(centre)) times
        // the indicator, the formula voxel by voxel.
        use rand::Rng;
        let mut r = crate::util::rng::rng(&[77]);
        let tr = Transform::new(0.5, DVec3::new(0.25, -0.5, 0.0));
        let params = GridParams { density_a: 0.02, ..GridParams::default() };
        let mut g = Grid::new("emission", [0.0f32; 3], tr);
        for _ in 0..20_000 {
            let ijk = IVec3::new(r.random_range(-900..900), r.random_range(-400..400), r.random_range(150..600));
            g.set(ijk, [r.random_range(0.0..2.0), r.random_range(0.0..5.0), r.random_range(0.0..1.0)]);
        }
        let peak = 3.0;
        let inv_scale = (1.0 / (AURORA_FRACTION * peak)) as f32;
        for earth in [Earth::new(crate::geometry::earth::MEAN_RADIUS_KM), Earth::new(0.0)] {
            let d = density_grid(&g, &params, peak, &earth);
            assert_eq!(d.active_voxel_count(), g.active_voxel_count());
            for (ijk, v) in g.iter_active() {
                let y = luminance([v[0] as f64, v[1] as f64, v[2] as f64]).max(0.0);
                let indicator = 1.0 - photons::fast_math::exp_neg_f32(-(y as f32) * inv_scale);
                let a = extinction(&params, earth.altitude(tr.index_to_world(ijk.as_dvec3())));
                assert_eq!(d.get(ijk).to_bits(), ((a * indicator as f64) as f32).to_bits(), "{ijk}");
            }
        }
    }
}
