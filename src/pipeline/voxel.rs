//! The voxel size: the scene's, or for `voxel_size = "auto"` the camera's
//! choice ([`auto_voxel_size`]: one pixel at the nearest aurora, within
//! [half the kernel radius, twice the smallest kernel radius]); the grid
//! transform it sets; warnings for a grid that under-resolves the kernel or
//! the curtains.

use crate::geometry::camera::CameraModel;
use crate::grid::Transform;
use crate::pipeline::deposit::Photon;
use crate::pipeline::footprint::Footprint;
use crate::scene::{KernelRadius, Scene, VoxelSize};
use crate::util::fmath;
use glam::DVec3;

/// The voxel size in km and where it came from. `"auto"` asks the camera:
/// see [`auto_voxel_size`].
pub fn voxel_size(scene: &Scene, photons: &[Photon]) -> (f64, String) {
    let camera = CameraModel::new(&scene.camera, scene.render.width, scene.render.height);
    voxel_size_for(scene.grid.voxel_size, KernelRadius::of(&scene.photons), camera.as_ref().ok(), photons)
}

/// [`voxel_size`] from plain data: `grid.voxel_size`, the kernel radius and
/// the camera (None: not valid).
pub fn voxel_size_for(size: VoxelSize, kernel: KernelRadius, camera: Option<&CameraModel>, photons: &[Photon]) -> (f64, String) {
    match size {
        VoxelSize::Km(v) => (v, "scene".into()),
        VoxelSize::Auto(_) => {
            let (v, why) = auto_voxel_size_for(kernel, camera, photons);
            (v, format!("auto: {why}"))
        }
    }
}

/// No more model than the picture needs: the voxel size at which one voxel
/// projects to about one pixel at the nearest aurora.
///
/// A pixel at the image centre subtends an angle `a` (perspective:
/// 2 tan(fov/2) / height; fisheye: fov / max(width, height); equirectangular:
/// min(360 / width, 180 / height) degrees: `CameraModel::pixel_angle`), so at
/// distance d it covers d a km; d is the 1st percentile
/// of the photons' distances from the camera (robust to a few stray photons,
/// which would otherwise shrink every voxel). Orthographic: ortho_height /
/// height. Never below half the kernel radius: the kernel already blurs the
/// field at that scale, so finer voxels add memory and no detail; never above
/// twice the smallest kernel radius, where the voxels would alias it.
/// Rounded to three significant digits (down, at that ceiling) so the size
/// reads well in bake.json.
pub fn auto_voxel_size(scene: &Scene, photons: &[Photon]) -> (f64, String) {
    let camera = CameraModel::new(&scene.camera, scene.render.width, scene.render.height);
    auto_voxel_size_for(KernelRadius::of(&scene.photons), camera.as_ref().ok(), photons)
}

/// [`auto_voxel_size`] from plain data.
pub fn auto_voxel_size_for(kernel: KernelRadius, camera: Option<&CameraModel>, photons: &[Photon]) -> (f64, String) {
    let d = match camera {
        Some(cam) if needs_distances(VoxelSize::Auto(crate::scene::AutoTag::Auto), Some(cam)) => camera_distances(cam.position, photons),
        _ => Vec::new(),
    };
    auto_voxel_size_of(kernel, camera, d)
}

/// Whether the voxel size of `size` seen by `camera` reads the photons'
/// distances ([`camera_distances`]): `"auto"` with a perspective, fisheye
/// or equirectangular camera.
pub fn needs_distances(size: VoxelSize, camera: Option<&CameraModel>) -> bool {
    matches!(size, VoxelSize::Auto(_)) && camera.is_some_and(|c| c.pixel_angle().is_some())
}

/// Each photon's distance from `eye`, km (in any order: the voxel size
/// takes a percentile of them).
pub fn camera_distances(eye: DVec3, photons: &[Photon]) -> Vec<f64> {
    photons.iter().map(|p| (DVec3::new(p.position[0] as f64, p.position[1] as f64, p.position[2] as f64) - eye).length()).collect()
}

/// [`auto_voxel_size_for`] from every photon's distance from the camera
/// (`d`, [`camera_distances`]; read only when [`needs_distances`]), so a
/// bake traced in chunks keeps the distances and not the photons.
pub fn auto_voxel_size_of(kernel: KernelRadius, camera: Option<&CameraModel>, mut d: Vec<f64>) -> (f64, String) {
    let floor = kernel.auto_voxel_floor_km();
    // A validated scene always has a camera; should it not, the kernel
    // radius is a size that neither aliases nor wastes.
    let Some(cam) = camera else {
        return (kernel.base_km, "no valid camera: kernel radius".into());
    };
    let (raw, why) = match cam.pixel_angle() {
        None => (cam.pixel_footprint(0.0), "ortho_height / height".to_string()),
        Some(_) => {
            if d.is_empty() {
                return (kernel.base_km, "no photons: kernel radius".into());
            }
            let k = d.len() / 100;
            let (_, nth, _) = d.select_nth_unstable_by(k, f64::total_cmp);
            let dist = *nth;
            (cam.pixel_footprint(dist), format!("one pixel at {dist:.1} km (1st percentile of photon distances)"))
        }
    };
    // Never above twice the smallest kernel radius either: coarser voxels
    // alias the kernel (see [`resolution_warnings`]), so the bake would
    // warn about its own choice.
    let ceiling = 2.0 * kernel.min_km;
    if raw > ceiling && ceiling >= floor {
        let p = fmath::powi(10f64, 2 - fmath::log10(ceiling.abs()).floor() as i32);
        return ((ceiling * p).floor() / p, format!("{why}, lowered to twice the smallest kernel radius"));
    }
    let v = raw.max(floor);
    let why = if raw < floor { format!("{why}, raised to half the kernel radius") } else { why };
    (round_sig(v, 3), why)
}

fn round_sig(x: f64, digits: i32) -> f64 {
    if x == 0.0 || !x.is_finite() {
        return x;
    }
    let p = fmath::powi(10f64, digits - 1 - fmath::log10(x.abs()).floor() as i32);
    (x * p).round() / p
}

/// Mean thickness, km, of the band the beams of a footprint start from: the
/// area of the cells above `threshold` divided by the curtain's length (the
/// sum of the band's widths across the curtain, averaged along it).
pub fn band_thickness_km(fp: &Footprint, threshold: f64) -> f64 {
    let cells = fp.data.iter().filter(|&&d| d as f64 > threshold).count();
    cells as f64 * fp.cell_area_km2() / fp.length
}

/// Warnings for a bake at voxel size `voxel_km` whose grid under-resolves
/// what it stores:
/// - the smallest kernel radius, `r_min = radius_km (1 - radius_noise)`, is
///   below half a voxel. Voxel centres sample the Gaussian kernel; by Poisson
///   summation the sum of a Gaussian of sd r sampled every h differs from its
///   integral by up to `2 exp(-2 pi^2 r^2 / h^2)` per axis: 1.4 % at
///   r = h / 2, 22 % at r = h / 3, so below h / 2 each photon's contribution
///   depends on where it falls between voxel centres (noise at the voxel
///   scale, power no longer conserved voxel by voxel).
/// - a curtain's beams start in a band thinner than a voxel
///   ([`band_thickness_km`]): across its thickness the sheet is one voxel or
///   less, so its profile is lost (beam deflections widen the sheet a
///   little; the kernel blurs it to at least r).
pub fn resolution_warnings(scene: &Scene, footprints: &[Footprint], voxel_km: f64) -> Vec<String> {
    resolution_warnings_for(KernelRadius::of(&scene.photons), footprints, scene.footprint.threshold, voxel_km)
}

/// [`resolution_warnings`] from plain data: the kernel radius, the
/// footprints and `footprint.threshold`.
pub fn resolution_warnings_for(kernel: KernelRadius, footprints: &[Footprint], threshold: f64, voxel_km: f64) -> Vec<String> {
    let mut w = Vec::new();
    let r_min = kernel.min_km;
    if r_min < 0.5 * voxel_km {
        w.push(format!(
            "under-resolved kernel: photons.radius_km = {} (smallest radius with radius_noise = {}: {:.4} km) is below half the voxel size ({} km); the emission is aliased at the voxel scale: use grid.voxel_size <= {:.4} or a larger radius",
            kernel.base_km, kernel.noise, r_min, voxel_km, 2.0 * r_min
        ));
    }
    for (i, fp) in footprints.iter().enumerate() {
        let t = band_thickness_km(fp, threshold);
        if t < voxel_km {
            w.push(format!(
                "under-resolved curtain: curtain[{i}]'s beams start in a band {t:.3} km thick on average (footprint above threshold), thinner than a voxel ({voxel_km} km); the sheet's profile across is lost: use grid.voxel_size <= {:.3}",
                t
            ));
        }
    }
    w
}

/// The grid transform of voxel size `voxel_km`: translation 0, so voxel
/// (i, j, k) is centred at `voxel_km * (i, j, k)` km.
pub fn grid_transform(voxel_km: f64) -> Transform {
    Transform::new(voxel_km, DVec3::ZERO)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pipeline::deposit::Photon;
    use crate::scene::{AutoTag, Projection, VoxelSize};

    fn photon_at(p: [f32; 3]) -> Photon {
        Photon::point(p, [1.0; 3])
    }

    /// A pixel at distance d covers d * 2 tan(fov/2) / height.
    #[test]
    fn auto_voxel_projects_to_one_pixel_at_the_nearest_aurora() {
        let mut s = Scene::default();
        s.grid.voxel_size = VoxelSize::Auto(AutoTag::Auto);
        s.camera.position = [0.0, 0.0, 0.0];
        s.camera.fov_deg = 90.0;
        s.render.height = 100;
        s.photons.radius_km = 2.0;
        s.photons.radius_noise = 0.0;
        // 1000 photons at 150, 151, ... km: the 1st percentile (index 10) is 160 km.
        let photons: Vec<Photon> = (0..1000).map(|i| photon_at([0.0, 0.0, 150.0 + i as f32])).collect();
        let (v, why) = voxel_size(&s, &photons);
        assert!((v - 160.0 * 2.0 / 100.0).abs() < 1e-9, "{v} {why}");
        assert!(why.starts_with("auto"));
        // One stray photon near the camera moves the percentile by one photon
        // (159 km instead of 160), not to 1 km.
        let mut with_stray = photons.clone();
        with_stray.push(photon_at([0.0, 0.0, 1.0]));
        assert!((voxel_size(&s, &with_stray).0 - 1.59 * 2.0).abs() < 1e-9);
        // Never below half the kernel radius.
        s.photons.radius_km = 10.0;
        assert_eq!(voxel_size(&s, &photons).0, 5.0);
        // Never above twice the smallest radius (1.0 x (1 - 0.3) x 2 = 1.4 km).
        s.photons.radius_km = 1.0;
        s.photons.radius_noise = 0.3;
        let (v, why) = voxel_size(&s, &photons);
        assert!((v - 1.4).abs() < 1e-12 && why.contains("lowered"), "{v} {why}");
        assert!(resolution_warnings(&s, &[], v).is_empty(), "the bake does not warn about its own choice");
        // Orthographic: ortho_height / height.
        s.photons.radius_km = 0.1;
        s.photons.radius_noise = 0.0;
        s.camera.projection = Projection::Orthographic;
        s.camera.ortho_height = 20.0;
        assert!((voxel_size(&s, &photons).0 - 0.2).abs() < 1e-12);
    }
}
