//! Contribution-based pruning: leaves (8^3 blocks) whose light at the scene's
//! camera is below an error budget are not stored.
//!
//! A voxel of emission `epsilon` (luminance, kR per km) and volume `V` at
//! distance `d` adds `epsilon V / d^2` to the radiance integrated over the
//! frame, `sum L_p Omega_p`. A pinhole camera's pixels do not all subtend the
//! same solid angle (`Omega_p = Omega_0 cos^3 theta`, `theta` off the optical
//! axis), so to the plain sum of pixel values (what the image's flux and a
//! per-pixel error see) it adds `epsilon V / (d^2 cos^3 theta)`. In general
//! a leaf's contribution ([`leaf_contributions`]) is `sum Y V w` over its
//! active voxels with `w = 1 / (d^2 Omega_p / Omega_0)`, the pixel's solid
//! angle relative to the centre pixel's from the camera
//! ([`crate::geometry::camera::CameraModel::relative_pixel_solid_angle`]):
//! `cos^3 theta` for perspective, `sin theta / theta` for the equidistant
//! fisheye, `cos beta` (latitude) for the equirectangular panorama; an
//! orthographic camera has `w = 1` (every pixel the same area, no `d^2`).
//!
//! [`prune`] drops leaves in increasing order of contribution while the
//! dropped total stays within `budget` of the grid's total, so the removed
//! light is at most `budget` of what reaches the camera. Both simplifications
//! stay on the safe side of that bound: extinction is ignored (air in front
//! of a leaf only lowers its contribution), and off-screen voxels count as if
//! on the frame's corner (`cos theta` clamped there; for a fisheye, the image
//! circle's edge), since off-screen aurora lights the terrain in frame and a
//! shot may be re-framed: a block is dropped for being faint, not for being
//! off screen. With all the aurora in frame the bound holds on the image's
//! flux up to the reconstruction filter: trilinear interpolation also fades
//! the cells straddling a dropped leaf's faces, so the flux removed may
//! exceed the budget by a fraction of it. `aurora bench` measures the
//! per-pixel error. A bake pruned for one camera may miss faint leaves in
//! another view; `grid.prune = 0` keeps every leaf.
//!
//! The density grid is built afterwards on the kept voxels, so both grids
//! lose the same leaves. The per-line grids (`grid.lines`) follow the
//! emission leaf by leaf ([`prune_like`]): a line grid keeps exactly those of
//! its leaves whose origin the emission kept, because the emission (the
//! lines' sum) is what the render shows: a line grid must neither hold light
//! the picture lost nor drop light it shows. It may still lack a leaf the
//! emission has (a line that is zero there, such as the green in the red
//! trail's earlier samples): the rule never adds a leaf.

use crate::geometry::camera::CameraModel;
use crate::grid::{offset_to_local, Grid, Leaf, Transform, LEAF_DIM, LEAF_NUM_VALUES};
use crate::scene::Projection;
use crate::util::colour::luminance;
use crate::util::fmath;
use glam::{DVec3, IVec3};
use rayon::prelude::*;
use serde::Serialize;

/// What pruning removed.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PruneStats {
    /// The scene's `grid.prune`: the largest fraction of the light at the
    /// camera that may be removed.
    pub budget: f64,
    pub leaves_before: usize,
    pub leaves_removed: usize,
    pub voxels_before: u64,
    pub voxels_removed: u64,
    /// Fraction of the light at the camera actually removed (extinction
    /// ignored; at most `budget`).
    pub removed_fraction: f64,
}

/// The weight `w` of the module documentation for one camera:
/// [`CameraModel::pixel_weight`], with a quarter voxel as the smallest
/// distance so a voxel around the eye does not get an infinite weight.
#[derive(Clone, Debug)]
pub struct Weight<'a> {
    camera: &'a CameraModel,
    d2_min: f64,
    /// The perspective camera's `cos theta` at the frame's corner, computed
    /// once here rather than per voxel (None for the other projections).
    cos_corner: Option<f64>,
}

impl Weight<'_> {
    pub fn new(camera: &CameraModel, voxel_km: f64) -> Weight<'_> {
        let cos_corner = (camera.projection == Projection::Perspective).then(|| {
            let (t, a) = (camera.tan_half_fov, camera.aspect());
            1.0 / (1.0 + t * t * (1.0 + a * a)).sqrt()
        });
        Weight { camera, d2_min: 0.25 * voxel_km * voxel_km, cos_corner }
    }

    /// `w` at world position `p`: [`CameraModel::pixel_weight`], the
    /// perspective case written out with the corner's cosine hoisted (the
    /// same operations in the same order, so the same value; a test checks).
    #[inline]
    pub fn at(&self, p: DVec3) -> f64 {
        match self.cos_corner {
            Some(cos_corner) => {
                let v = p - self.camera.position;
                let d2 = v.length_squared().max(self.d2_min);
                let cos = (v.dot(self.camera.forward) / d2.sqrt()).max(cos_corner);
                1.0 / (d2 * cos * cos * cos)
            }
            None => self.camera.pixel_weight(p, self.d2_min),
        }
    }

    /// [`Weight::at`] at every voxel of the leaf at `origin` (offset order),
    /// positions from [`Transform::index_to_world`]: the same values, in a
    /// loop without branches that vectorises.
    ///
    /// In perspective, the camera-relative coordinates per axis once per
    /// leaf and the x and y terms of the squared distance and of the
    /// forward projection once per z-row (glam sums x, y then z, so the same
    /// sums), the z-rows in loops without branches.
    fn leaf(&self, tr: Transform, origin: IVec3) -> Box<[f64; LEAF_NUM_VALUES]> {
        let mut out = Box::new([0.0f64; LEAF_NUM_VALUES]);
        let Some(cos_corner) = self.cos_corner else {
            for (n, o) in out.iter_mut().enumerate() {
                *o = self.at(tr.index_to_world((origin + offset_to_local(n)).as_dvec3()));
            }
            return out;
        };
        let (c, f) = (self.camera.position, self.camera.forward);
        // `index_to_world` then `- position`, one axis at a time.
        let rel = |axis: usize, l: usize| (origin[axis] + l as i32) as f64 * tr.voxel_size + tr.translation[axis] - c[axis];
        let vz: [f64; LEAF_DIM as usize] = std::array::from_fn(|z| rel(2, z));
        let (vz2, fz): ([f64; 8], [f64; 8]) = (vz.map(|v| v * v), vz.map(|v| v * f.z));
        for (x, slab) in out.chunks_exact_mut(64).enumerate() {
            let vx = rel(0, x);
            for (y, row) in slab.chunks_exact_mut(8).enumerate() {
                let vy = rel(1, y);
                let (sxy, dxy) = (vx * vx + vy * vy, vx * f.x + vy * f.y);
                for (z, o) in row.iter_mut().enumerate() {
                    let d2 = (sxy + vz2[z]).max(self.d2_min);
                    let cos = ((dxy + fz[z]) / d2.sqrt()).max(cos_corner);
                    *o = 1.0 / (d2 * cos * cos * cos);
                }
            }
        }
        out
    }
}

/// Each leaf's contribution to the light at the camera, in leaf order:
/// `sum over active voxels of Y(epsilon) V w(d)` (see the module
/// documentation). Each leaf's sum runs in voxel order, so the result does
/// not depend on the thread count.
pub fn leaf_contributions(emission: &Grid<[f32; 3]>, camera: &CameraModel) -> Vec<f64> {
    let tr = emission.transform;
    let v = fmath::powi(tr.voxel_size, 3);
    let w = Weight::new(camera, tr.voxel_size);
    emission
        .leaves()
        .par_iter()
        .map(|l| {
            let weights = w.leaf(tr, l.origin);
            // Voxels off or unlit add +0, which leaves the sum (never -0:
            // it starts at +0 and adds positive terms) as it is: the sum
            // over the lit active voxels, without branches.
            let mut c = 0.0f64;
            for n in 0..LEAF_NUM_VALUES {
                let e = l.values[n];
                let y = luminance([e[0] as f64, e[1] as f64, e[2] as f64]).max(0.0);
                c += if l.is_active(n) && y > 0.0 { y * v * weights[n] } else { 0.0 };
            }
            c
        })
        .collect()
}

/// The leaves to drop: in increasing order of contribution (ties broken by
/// leaf origin, so the choice is deterministic), as many as fit within
/// `budget` of the total. Returns a keep flag per leaf (leaf order) and the
/// fraction removed.
pub fn select(contributions: &[f64], origins: &[[i32; 3]], budget: f64) -> (Vec<bool>, f64) {
    let total: f64 = contributions.iter().sum();
    let mut keep = vec![true; contributions.len()];
    if budget <= 0.0 || total <= 0.0 {
        return (keep, 0.0);
    }
    let mut order: Vec<usize> = (0..contributions.len()).collect();
    order.sort_unstable_by(|&a, &b| contributions[a].total_cmp(&contributions[b]).then(origins[a].cmp(&origins[b])));
    let allowed = budget * total;
    let mut removed = 0.0f64;
    for i in order {
        if removed + contributions[i] > allowed {
            break;
        }
        removed += contributions[i];
        keep[i] = false;
    }
    (keep, removed / total)
}

/// Drops the emission's faintest leaves within `budget` (see the module
/// documentation) for `camera` (the scene's camera at the render size).
pub fn prune(emission: &mut Grid<[f32; 3]>, camera: &CameraModel, budget: f64) -> PruneStats {
    prune_keeping(emission, camera, budget).0
}

/// [`prune`], also returning the dropped leaves in leaf order (the
/// preview keeps them to restore the unpruned grid after a camera edit,
/// [`Grid::restore_leaves`], rather than a copy of the whole grid).
pub fn prune_keeping(emission: &mut Grid<[f32; 3]>, camera: &CameraModel, budget: f64) -> (PruneStats, Vec<Leaf<[f32; 3]>>) {
    let leaves_before = emission.leaf_count();
    let voxels_before = emission.active_voxel_count();
    let c = leaf_contributions(emission, camera);
    let origins: Vec<[i32; 3]> = emission.leaves().iter().map(|l| l.origin.to_array()).collect();
    let (keep, removed_fraction) = select(&c, &origins, budget);
    let mut it = keep.iter();
    // split_off_leaves visits the leaves in order, once each.
    let dropped = emission.split_off_leaves(|_| *it.next().unwrap_or(&true));
    let stats = PruneStats {
        budget,
        leaves_before,
        leaves_removed: leaves_before - emission.leaf_count(),
        voxels_before,
        voxels_removed: voxels_before - emission.active_voxel_count(),
        removed_fraction,
    };
    (stats, dropped)
}

/// Drops the leaves of `grid` whose origin `kept` does not hold (the
/// per-line grids after the emission was pruned: module doc); returns how
/// many were dropped.
pub fn prune_like<T: crate::grid::VoxelValue, U: crate::grid::VoxelValue>(grid: &mut Grid<T>, kept: &Grid<U>) -> usize {
    let before = grid.leaf_count();
    grid.retain_leaves(|l| kept.leaf(l.origin).is_some());
    before - grid.leaf_count()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::Transform;
    use crate::scene::{Camera, Projection};
    use glam::IVec3;

    fn model(cam: Camera) -> CameraModel {
        CameraModel::new(&cam, 100, 100).unwrap()
    }

    fn camera_at(p: [f64; 3]) -> Camera {
        Camera { position: p, look_at: [p[0] + 1.0, p[1], p[2]], ..Camera::default() }
    }

    /// Leaves along x at distances 10, 20, ... km from the camera, one
    /// active voxel each of emission (0, 1, 0).
    fn row(n: i32) -> Grid<[f32; 3]> {
        let mut g = Grid::new("emission", [0.0f32; 3], Transform::new(1.0, DVec3::ZERO));
        for i in 1..=n {
            g.set(IVec3::new(10 * i, 0, 0), [0.0, 1.0, 0.0]);
        }
        g
    }

    #[test]
    fn contribution_falls_as_inverse_square_of_distance_on_axis() {
        let g = row(4);
        let c = leaf_contributions(&g, &model(camera_at([0.0; 3])));
        let y = luminance([0.0, 1.0, 0.0]);
        // On the optical axis (cos theta = 1): y V / d^2.
        for (l, ci) in g.leaves().iter().zip(&c) {
            let want: f64 = l.iter_active().map(|(ijk, _)| y / (ijk.as_dvec3().length_squared())).sum();
            assert!((ci / want - 1.0).abs() < 1e-12, "{ci} vs {want}");
        }
        let ortho = Camera { projection: Projection::Orthographic, ..camera_at([0.0; 3]) };
        for ci in leaf_contributions(&g, &model(ortho)) {
            assert!((ci / y - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn hoisted_weight_equals_the_cameras_pixel_weight() {
        let mut rng = crate::util::rng::rng(&[5]);
        use rand::Rng;
        for projection in [Projection::Perspective, Projection::Orthographic, Projection::Fisheye, Projection::Equirectangular] {
            let m = CameraModel::new(&Camera { projection, fov_deg: 70.0, ..camera_at([1.0, -2.0, 3.0]) }, 160, 90).unwrap();
            let w = Weight::new(&m, 0.5);
            for _ in 0..1000 {
                let p = DVec3::new(rng.random_range(-50.0..50.0), rng.random_range(-50.0..50.0), rng.random_range(-5.0..50.0));
                assert_eq!(w.at(p), m.pixel_weight(p, 0.25 * 0.5 * 0.5), "{projection:?} {p}");
            }
            assert_eq!(w.at(m.position), m.pixel_weight(m.position, 0.0625));
        }
    }

    #[test]
    fn leaf_weights_are_the_weight_at_each_voxel_bit_for_bit() {
        let mut rng = crate::util::rng::rng(&[6]);
        use rand::Rng;
        let tr = Transform::new(0.37, DVec3::new(0.1, -0.25, 0.05));
        for projection in [Projection::Perspective, Projection::Orthographic] {
            let m = CameraModel::new(&Camera { projection, fov_deg: 70.0, ..camera_at([1.0, -2.0, 3.0]) }, 160, 90).unwrap();
            let w = Weight::new(&m, tr.voxel_size);
            for _ in 0..50 {
                let origin = IVec3::new(rng.random_range(-40..40), rng.random_range(-40..40), rng.random_range(-5..40)) * 8;
                let leaf = w.leaf(tr, origin);
                for (n, &got) in leaf.iter().enumerate() {
                    let want = w.at(tr.index_to_world((origin + offset_to_local(n)).as_dvec3()));
                    assert_eq!(got.to_bits(), want.to_bits(), "{projection:?} {origin} {n}");
                }
            }
        }
    }

    #[test]
    fn weight_is_the_pixel_count_a_voxel_covers() {
        // A pinhole image plane at focal distance 1: a small patch of area a
        // facing the eye at distance d, angle theta off axis, covers solid
        // angle a / d^2 and, since a pixel at theta subtends
        // Omega_0 cos^3 theta, a / (d^2 cos^3 theta) / Omega_0 pixels.
        // Check w against that pixel-count ratio between an on-axis and an
        // off-axis point, measured by projecting a tiny square's corners.
        let cam = Camera { fov_deg: 90.0, ..camera_at([0.0; 3]) };
        let m = model(cam);
        let w = Weight::new(&m, 1e-6);
        let project = |p: DVec3| (p.y / p.x, p.z / p.x); // image plane x = 1
        let pixels = |c: DVec3| {
            // A square of side h facing the eye (normal along c).
            let n = c.normalize();
            let u = n.cross(DVec3::Z).normalize();
            let v = n.cross(u);
            let h = 1e-4;
            let (a, b, d) = (project(c), project(c + u * h), project(c + v * h));
            ((b.0 - a.0) * (d.1 - a.1) - (b.1 - a.1) * (d.0 - a.0)).abs()
        };
        let on = DVec3::new(30.0, 0.0, 0.0);
        for off in [DVec3::new(20.0, 15.0, 0.0), DVec3::new(10.0, 6.0, 7.0)] {
            let want = pixels(off) / pixels(on);
            let got = w.at(off) / w.at(on);
            assert!((got / want - 1.0).abs() < 1e-3, "{got} vs {want}");
        }
        // Off screen (behind the camera): the corner's weight at that distance.
        let behind = DVec3::new(-10.0, 0.0, 0.0);
        let corner = 1.0 / (1.0f64 + 1.0 * 2.0).sqrt();
        assert!((w.at(behind) * 100.0 * fmath::powi(corner, 3) - 1.0).abs() < 1e-12);
    }

    #[test]
    fn removed_light_never_exceeds_the_budget_and_faintest_go_first() {
        // Brute-force oracle: for 200 random contribution sets and budgets,
        // the removed share is <= budget, every dropped leaf is no brighter
        // than every kept one, and one more leaf (the faintest kept) would
        // exceed the budget.
        let mut rng = crate::util::rng::rng(&[7]);
        use rand::Rng;
        for case in 0..200 {
            let n = 1 + case % 37;
            let c: Vec<f64> = (0..n).map(|_| fmath::powi(rng.random::<f64>(), 3)).collect();
            let origins: Vec<[i32; 3]> = (0..n).map(|i| [8 * i, 0, 0]).collect();
            let budget = rng.random::<f64>() * 0.3;
            let (keep, frac) = select(&c, &origins, budget);
            let total: f64 = c.iter().sum();
            let removed: f64 = c.iter().zip(&keep).filter(|(_, &k)| !k).map(|(x, _)| x).sum();
            assert!((removed / total - frac).abs() < 1e-12);
            assert!(frac <= budget + 1e-15, "{frac} > {budget}");
            let max_dropped = c.iter().zip(&keep).filter(|(_, &k)| !k).map(|(x, _)| *x).fold(0.0, f64::max);
            let min_kept = c.iter().zip(&keep).filter(|(_, &k)| k).map(|(x, _)| *x).fold(f64::INFINITY, f64::min);
            assert!(max_dropped <= min_kept);
            if min_kept.is_finite() {
                assert!(removed + min_kept > budget * total, "case {case}: could drop one more");
            }
        }
    }

    #[test]
    fn pruning_drops_the_far_leaves_first_and_keeps_the_grid_consistent() {
        // Distances 10 i km, i = 1..8: contributions y / (100 i^2). The
        // expected drop is recomputed here the plain way (farthest first,
        // while the running sum stays within the budget).
        let mut g = row(8);
        let cam = model(camera_at([0.0; 3]));
        let c: Vec<f64> = (1..=8).map(|i| 1.0 / (100.0 * (i * i) as f64)).collect();
        let total: f64 = c.iter().sum();
        let budget = 0.05;
        let mut removed = 0.0;
        let mut want_removed = 0;
        for x in c.iter().rev() {
            if removed + x > budget * total {
                break;
            }
            removed += x;
            want_removed += 1;
        }
        assert!(want_removed >= 2, "the test should drop several leaves");
        let s = prune(&mut g, &cam, budget);
        assert_eq!(s.leaves_removed, want_removed);
        assert_eq!(s.voxels_removed, want_removed as u64);
        assert!((s.removed_fraction - removed / total).abs() < 1e-12);
        // The kept leaves are the nearest ones, and lookups still work.
        for i in 1..=8 {
            let kept = i <= 8 - want_removed as i32;
            assert_eq!(g.is_active(IVec3::new(10 * i, 0, 0)), kept, "leaf {i}");
        }
        // Budget 0 keeps everything.
        let mut h = row(8);
        assert_eq!(prune(&mut h, &cam, 0.0).leaves_removed, 0);
        assert_eq!(h, row(8));
    }
}
