//! Error metrics against a reference, shared by every study.

use crate::grid::{Grid, VoxelValue};

/// Relative RMS error of `test` against `reference`, sampled at the
/// reference's active voxel centres (world space, trilinear, so grids of
/// different voxel sizes compare): sqrt(sum |a - b|^2 / sum |b|^2) over all
/// components. Voxels active in `test` but not in the reference count too
/// (sampled at the test's centres against the reference there).
pub fn grid_rel_rms<T: VoxelValue>(test: &Grid<T>, reference: &Grid<T>) -> f64 {
    let mut num = 0.0f64;
    let mut den = 0.0f64;
    let mut add = |a: [f32; 3], b: [f32; 3]| {
        for c in 0..T::COMPONENTS {
            let d = a[c] as f64 - b[c] as f64;
            num += d * d;
            den += (b[c] as f64).powi(2);
        }
    };
    for (ijk, b) in reference.iter_active() {
        let p = reference.transform.index_to_world(ijk.as_dvec3());
        add(test.sample_world(p).components(), b.components());
    }
    // Mass the test puts where the reference is empty is error too.
    for (ijk, a) in test.iter_active() {
        let p = test.transform.index_to_world(ijk.as_dvec3());
        let b = reference.sample_world(p);
        if b.components()[..T::COMPONENTS].iter().all(|&x| x == 0.0) {
            let scale = (reference.transform.voxel_size / test.transform.voxel_size).powi(3);
            let a = a.components();
            // Weight by voxel volume so a finer test grid is not over-counted.
            for c in 0..T::COMPONENTS {
                num += (a[c] as f64).powi(2) / scale.max(1e-12);
            }
        }
    }
    if den == 0.0 {
        if num == 0.0 {
            0.0
        } else {
            f64::INFINITY
        }
    } else {
        (num / den).sqrt()
    }
}

/// Relative error of two RGB images over pixels where the reference is
/// brighter than `floor` times its peak luminance: mean of |a - b| / b on
/// luminance. Returns (mean relative error, ratio of total fluxes a/b).
pub fn image_rel_error(a: &[[f32; 4]], b: &[[f32; 4]], floor: f64) -> (f64, f64) {
    assert_eq!(a.len(), b.len(), "images differ in size");
    let lum = |p: &[f32; 4]| 0.2126 * p[0] as f64 + 0.7152 * p[1] as f64 + 0.0722 * p[2] as f64;
    let peak = b.iter().map(lum).fold(0.0, f64::max);
    let (mut sum, mut n, mut fa, mut fb) = (0.0, 0usize, 0.0, 0.0);
    for (pa, pb) in a.iter().zip(b) {
        let (la, lb) = (lum(pa), lum(pb));
        fa += la;
        fb += lb;
        if lb > floor * peak && lb > 0.0 {
            sum += (la - lb).abs() / lb;
            n += 1;
        }
    }
    let mean = if n == 0 { 0.0 } else { sum / n as f64 };
    let flux = if fb == 0.0 { if fa == 0.0 { 1.0 } else { f64::INFINITY } } else { fa / fb };
    (mean, flux)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::Transform;
    use glam::{DVec3, IVec3};

    #[test]
    fn identical_grids_have_zero_error_and_scaling_gives_its_factor() {
        let tr = Transform::new(1.0, DVec3::ZERO);
        let mut a = Grid::new("e", 0.0f32, tr);
        let mut b = Grid::new("e", 0.0f32, tr);
        for i in 0..20 {
            a.set(IVec3::new(i, 0, 0), 1.0 + i as f32);
            b.set(IVec3::new(i, 0, 0), 1.1 * (1.0 + i as f32));
        }
        assert_eq!(grid_rel_rms(&a, &a), 0.0);
        // a = b / 1.1 everywhere: relative RMS = 1 - 1/1.1.
        assert!((grid_rel_rms(&a, &b) - (1.0 - 1.0 / 1.1)).abs() < 1e-6);
    }

    #[test]
    fn image_error_ignores_dark_pixels_and_reports_flux() {
        let b = vec![[1.0, 1.0, 1.0, 1.0], [0.001, 0.001, 0.001, 1.0]];
        let a = vec![[1.02, 1.02, 1.02, 1.0], [0.5, 0.5, 0.5, 1.0]];
        let (mean, flux) = image_rel_error(&a, &b, 0.01);
        // f32 inputs: 1.02 is stored to about 1e-7 relative.
        assert!((mean - 0.02).abs() < 1e-6);
        assert!((flux - 1.52 / 1.001).abs() < 1e-6);
    }
}
