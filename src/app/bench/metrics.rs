//! Error metrics against a reference, shared by every study.

use crate::grid::{Grid, VoxelValue};
use crate::util::fmath;

/// Visits the (test, reference) component pairs [`grid_rel_rms`] compares,
/// with their weights: every reference voxel centre (test sampled there,
/// trilinear, so grids of different voxel sizes compare), then every test
/// voxel where the reference samples to 0, weighted by the ratio of voxel
/// volumes so a finer test grid is not over-counted.
fn visit_pairs<T: VoxelValue>(test: &Grid<T>, reference: &Grid<T>, mut f: impl FnMut(f64, f64, f64)) {
    for (ijk, b) in reference.iter_active() {
        let p = reference.transform.index_to_world(ijk.as_dvec3());
        let (a, b) = (test.sample_world(p).components(), b.components());
        for c in 0..T::COMPONENTS {
            f(a[c] as f64, b[c] as f64, 1.0);
        }
    }
    // Mass the test puts where the reference is empty is error too.
    let w = fmath::powi(test.transform.voxel_size / reference.transform.voxel_size, 3);
    for (ijk, a) in test.iter_active() {
        let p = test.transform.index_to_world(ijk.as_dvec3());
        let b = reference.sample_world(p);
        if b.components()[..T::COMPONENTS].iter().all(|&x| x == 0.0) {
            for &x in &a.components()[..T::COMPONENTS] {
                f(x as f64, 0.0, w);
            }
        }
    }
}

/// Relative RMS error of `test` against `reference`, sampled at the
/// reference's active voxel centres (world space, trilinear, so grids of
/// different voxel sizes compare): sqrt(sum |a - b|^2 / sum |b|^2) over all
/// components. Voxels active in `test` but not in the reference count too
/// (sampled at the test's centres against the reference there).
pub fn grid_rel_rms<T: VoxelValue>(test: &Grid<T>, reference: &Grid<T>) -> f64 {
    let mut num = 0.0f64;
    let mut den = 0.0f64;
    visit_pairs(test, reference, |a, b, w| {
        num += w * (a - b) * (a - b);
        den += w * b * b;
    });
    ratio(num, den)
}

/// [`grid_rel_rms`] after scaling `test` by the least-squares factor
/// `s = sum(w a b) / sum(w a^2)`: the error of the *shape* alone, for an
/// estimate whose magnitude means something else (the 2014 report's
/// average). Returns (error, s).
pub fn grid_rel_rms_best_scale<T: VoxelValue>(test: &Grid<T>, reference: &Grid<T>) -> (f64, f64) {
    let (mut aa, mut ab, mut bb) = (0.0f64, 0.0f64, 0.0f64);
    visit_pairs(test, reference, |a, b, w| {
        aa += w * a * a;
        ab += w * a * b;
        bb += w * b * b;
    });
    let s = if aa > 0.0 { ab / aa } else { 0.0 };
    // sum w (s a - b)^2 = s^2 aa - 2 s ab + bb = bb - ab^2 / aa at the optimum;
    // clamp the rounding of that difference at 0.
    let num = (s * s * aa - 2.0 * s * ab + bb).max(0.0);
    (ratio(num, bb), s)
}

fn ratio(num: f64, den: f64) -> f64 {
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
    let lum = |p: &[f32; 4]| crate::util::colour::luminance([p[0] as f64, p[1] as f64, p[2] as f64]);
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
    let flux = if fb == 0.0 {
        if fa == 0.0 {
            1.0
        } else {
            f64::INFINITY
        }
    } else {
        fa / fb
    };
    (mean, flux)
}

/// [`image_rel_error`] over the pixels where `mask` is true (e.g. terrain).
pub fn image_rel_error_masked(a: &[[f32; 4]], b: &[[f32; 4]], mask: &[bool], floor: f64) -> (f64, f64) {
    assert!(a.len() == mask.len() && b.len() == mask.len(), "images and mask differ in size");
    let pick = |img: &[[f32; 4]]| -> Vec<[f32; 4]> { img.iter().zip(mask).filter(|(_, &m)| m).map(|(p, _)| *p).collect() };
    image_rel_error(&pick(a), &pick(b), floor)
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
        // A pure scale is no shape error: best factor 1.1, error 0 (to the
        // f32 rounding of 1.1 x, about 1e-7 relative).
        let (e, s) = grid_rel_rms_best_scale(&a, &b);
        assert!(e < 1e-6 && (s - 1.1).abs() < 1e-6, "{e} {s}");
    }

    #[test]
    fn best_scale_matches_brute_force_minimum() {
        // Oracle: scan the scale factor finely; the closed form must be at
        // least as good as every scanned factor (to rounding).
        let tr = Transform::new(0.5, DVec3::ZERO);
        let mut a = Grid::new("e", [0.0f32; 3], tr);
        let mut b = Grid::new("e", [0.0f32; 3], tr);
        for i in 0..30 {
            let x = i as f32;
            a.set(IVec3::new(i, 1, 0), [fmath::sin(x).abs() + 0.1, 0.3, 0.0]);
            b.set(IVec3::new(i, 1, 0), [2.0 * fmath::cos(x).abs(), 0.5, 0.1]);
        }
        a.set(IVec3::new(40, 0, 0), [1.0, 1.0, 1.0]); // only in the test grid
        let (e, s) = grid_rel_rms_best_scale(&a, &b);
        for k in 0..=400 {
            let f = k as f32 * 0.01;
            let mut scaled = a.clone();
            for (ijk, v) in a.iter_active() {
                scaled.set(ijk, [v[0] * f, v[1] * f, v[2] * f]);
            }
            assert!(e <= grid_rel_rms(&scaled, &b) + 1e-6, "factor {f} beats the closed form {s}");
        }
    }

    #[test]
    fn masked_image_error_uses_only_masked_pixels() {
        let b = vec![[1.0, 1.0, 1.0, 1.0], [1.0, 1.0, 1.0, 1.0]];
        let a = vec![[1.5, 1.5, 1.5, 1.0], [1.0, 1.0, 1.0, 1.0]];
        assert_eq!(image_rel_error_masked(&a, &b, &[false, true], 0.0), (0.0, 1.0));
        assert!((image_rel_error_masked(&a, &b, &[true, false], 0.0).0 - 0.5).abs() < 1e-12);
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
