//! A line's brightness summed along the magnetic field: the column an
//! all-sky camera at the field line's foot sees looking up B, the
//! brightness an International Brightness Coefficient (IBC) class names
//! (Chamberlain 1961: 557.7 nm columns of 1, 10, 100 and 1000 kR for
//! classes I-IV; Hunten et al. 1956 for the rayleigh).
//!
//! Model: a line grid holds rayleigh per km (`grid.lines`), so a column
//! is `int e ds` along B. Each active voxel is moved along its own field
//! line (`field(x, y)`, a unit vector pointing down B) to the reference
//! altitude `z_ref`, and splatted bilinearly into a map of horizontal bins
//! of one voxel; through a stack of voxels one layer thick a line along B
//! runs `v / |b_z|`, so a voxel adds `e v / |b_z|` over one bin's area.
//! [`brightest_column`] is the map's largest bin: a column of one
//! voxel's width, the finest the grid holds.

use crate::grid::Grid;
use crate::util::fmath;
use glam::DVec3;
use std::collections::HashMap;

/// The map of columns, R, by horizontal bin (i, j) of one voxel at the
/// reference altitude.
pub fn column_map(grid: &Grid<f32>, z_ref: f64, field: impl Fn(f64, f64) -> DVec3) -> HashMap<(i64, i64), f64> {
    let v = grid.transform.voxel_size;
    let mut map: HashMap<(i64, i64), f64> = HashMap::new();
    for (ijk, e) in grid.iter_active() {
        if e <= 0.0 {
            continue;
        }
        let p = grid.transform.index_to_world(ijk.as_dvec3());
        let b = field(p.x, p.y);
        if b.z.abs() < 1e-6 {
            continue;
        }
        let foot = p + b * ((z_ref - p.z) / b.z);
        let (gx, gy) = (foot.x / v - 0.5, foot.y / v - 0.5);
        let (i0, j0) = (gx.floor(), gy.floor());
        let (fx, fy) = (gx - i0, gy - j0);
        let w = e as f64 * v / b.z.abs();
        for (di, dj, f) in [(0, 0, (1.0 - fx) * (1.0 - fy)), (1, 0, fx * (1.0 - fy)), (0, 1, (1.0 - fx) * fy), (1, 1, fx * fy)] {
            *map.entry((i0 as i64 + di, j0 as i64 + dj)).or_insert(0.0) += w * f;
        }
    }
    map
}

/// The brightest column of `grid` along the field, R (0 for an empty grid).
pub fn brightest_column(grid: &Grid<f32>, z_ref: f64, field: impl Fn(f64, f64) -> DVec3) -> f64 {
    column_map(grid, z_ref, field).values().cloned().fold(0.0, f64::max)
}

/// The IBC class a brightest 557.7 nm column names (Chamberlain 1961):
/// its column in R, `1e3 * 10^(class - 1)`.
pub fn ibc_column_r(class: u32) -> f64 {
    1e3 * fmath::powi(10f64, class as i32 - 1)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::transform::Transform;
    use glam::IVec3;

    #[test]
    fn a_slab_along_the_field_sums_to_its_closed_form() {
        // A slab 20 voxels high of 1 R/km, tilted along B at 78 degrees:
        // every column through it runs 20 v / sin(78) km of it.
        let v = 0.5;
        let mut g = Grid::new("line_5577", 0.0f32, Transform::new(v, DVec3::ZERO));
        let b = DVec3::new(0.0, fmath::cos((78f64).to_radians()), -fmath::sin((78f64).to_radians()));
        for k in 0..20 {
            let shift = (-(k as f64) * b.y / b.z).round() as i32;
            for i in -30..30 {
                for j in -30..30 {
                    g.set(IVec3::new(i, j - shift, 200 + k), 1.0);
                }
            }
        }
        let map = column_map(&g, 100.0, |_, _| b);
        let mid = map.get(&(0, 0)).copied().unwrap_or(0.0);
        let want = 20.0 * v / fmath::sin((78f64).to_radians());
        assert!((mid / want - 1.0).abs() < 0.05, "{mid} against {want}");
        assert!((brightest_column(&g, 100.0, |_, _| b) / want - 1.0).abs() < 0.08);
        assert_eq!(ibc_column_r(3), 1e5);
    }
}
