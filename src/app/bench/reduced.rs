//! The bench's scene: a reduced copy of the user's scene, small enough that
//! converged references (many more beams, finer voxels) fit in the bench's
//! time budget, and the two cameras the render studies look through.
//!
//! [`reduce`] keeps the **first curtain** only (one placed by a `path` as
//! the straight curtain of the path's length through its middle) and
//! shortens it to `length_km` (when longer), keeping everything per unit length and per unit
//! area the same, so photon density, kernel and voxel relate as in the full
//! scene:
//! - `curtain.length` -> `length_km`; factor `f = length_km / length`;
//! - `footprint.resolution[0]` (cells along the curtain) -> `round(f n)`, the
//!   same cell size;
//! - `footprint.velocity_waves` and `density_waves` (periods per curtain
//!   length) times `f`, `footprint.bend_wavelength` (in curtain lengths)
//!   divided by `f`: the same wavelengths in km;
//! - `beams.count` -> `round(count * w_0 / sum(w) * f)` (the first curtain's
//!   share of the beams, times `f`): the same beams per km of curtain, so
//!   each beam carries the same power;
//! - `grid.voxel_size = "auto"` is replaced by the size the full scene's
//!   bake would choose (passed in: it depends on the full scene's photons
//!   and camera).
//!
//! Everything else (seed, atmosphere, kernel, colour, B field, volume
//! scales, terrain) is the scene's own.

use crate::scene::{Camera, Projection, Scene, Terrain, TerrainKind, VoxelSize};
use crate::util::fmath;

/// The reduced scene and a line per change made, for `bench.json`.
#[derive(Clone, Debug)]
pub struct Reduced {
    pub scene: Scene,
    pub changes: Vec<String>,
}

/// A curtain placed by a `path` as the straight curtain of the path's
/// ground length through its middle point, along the chord between the
/// path's middle neighbours: the bench shortens a curtain by its length,
/// which a path does not read.
fn straightened(c: &crate::scene::Curtain, changes: &mut Vec<String>) -> crate::scene::Curtain {
    let Some(path) = c.path.as_ref().filter(|p| p.len() >= 2) else {
        return c.clone();
    };
    let length: f64 = path.windows(2).map(|w| fmath::hypot(w[1][0] - w[0][0], w[1][1] - w[0][1])).sum();
    let m = path.len() / 2;
    let (a, b) = (path[m.saturating_sub(1)], path[(m + 1).min(path.len() - 1)]);
    let mid = if path.len() % 2 == 1 { path[m] } else { [(path[m - 1][0] + path[m][0]) / 2.0, (path[m - 1][1] + path[m][1]) / 2.0] };
    let rotation_deg = fmath::atan2(b[1] - a[1], b[0] - a[0]).to_degrees();
    changes.push(format!(
        "curtain[0].path: a straight curtain of its length {length:.1} km through [{:.1}, {:.1}] at {rotation_deg:.1} degrees",
        mid[0], mid[1]
    ));
    crate::scene::Curtain { path: None, center: mid, length, rotation_deg, ..c.clone() }
}

/// See the module documentation. The scene must have been validated (at
/// least one curtain). `auto_voxel` is the full scene's resolved voxel size
/// and how it was chosen, used when `grid.voxel_size = "auto"`.
pub fn reduce(scene: &Scene, length_km: f64, auto_voxel: Option<(f64, String)>) -> Reduced {
    let mut s = scene.clone();
    let mut changes = Vec::new();
    let c0 = straightened(&scene.curtains[0], &mut changes);
    let total_weight: f64 = scene.curtains.iter().map(|c| c.beam_weight.max(0.0)).sum();
    let share = if total_weight > 0.0 { c0.beam_weight.max(0.0) / total_weight } else { 1.0 };
    if scene.curtains.len() > 1 {
        changes.push(format!("curtains: first of {} kept (beam share {:.4})", scene.curtains.len(), share));
    }
    let f = (length_km / c0.length).min(1.0);
    let mut c = c0.clone();
    c.length = c0.length * f;
    c.beam_weight = 1.0;
    s.curtains = vec![c];
    if f < 1.0 {
        changes.push(format!("curtain.length: {} -> {} km (f = {f:.4})", c0.length, c0.length * f));
        let fp = &mut s.footprint;
        let n0 = fp.resolution[0];
        fp.resolution[0] = ((n0 as f64 * f).round() as usize).max(8);
        fp.velocity_waves *= f;
        fp.density_waves *= f;
        fp.bend_wavelength /= f;
        changes.push(format!(
            "footprint: resolution[0] {n0} -> {}, velocity_waves x f = {}, density_waves x f = {}, bend_wavelength / f = {} (same cell size and wavelengths in km)",
            fp.resolution[0], fp.velocity_waves, fp.density_waves, fp.bend_wavelength
        ));
    }
    let n = ((scene.beams.count as f64 * share * f).round() as usize).max(16);
    if n != scene.beams.count {
        changes.push(format!("beams.count: {} -> {n} (same beams per km of curtain)", scene.beams.count));
    }
    s.beams.count = n;
    if let (VoxelSize::Auto(_), Some((v, src))) = (scene.grid.voxel_size, auto_voxel) {
        s.grid.voxel_size = VoxelSize::Km(v);
        changes.push(format!("grid.voxel_size: auto -> {v} km (the full scene's {src})"));
    }
    Reduced { scene: s, changes }
}

/// Unit vectors along the curtain's axis and across it (+v), in the ground plane.
fn curtain_frame(scene: &Scene) -> ([f64; 2], [f64; 2]) {
    let (sn, cs) = fmath::sin_cos(scene.curtains[0].rotation_deg.to_radians());
    ([cs, sn], [-sn, cs])
}

/// The camera of the volume studies: from the ground (1.5 km up), 120 km
/// from the curtain's centre across its axis (on the -v side), looking at
/// the curtain broadside, the vertical field of view spanning 85 km to 10 km
/// above `beams.top_km` at the curtain (plus 10 %). No terrain is in view.
pub fn volume_camera(scene: &Scene) -> Camera {
    let c = scene.curtains[0].center;
    let (_, across) = curtain_frame(scene);
    let (d, h) = (120.0, 1.5);
    let pos = [c[0] - across[0] * d, c[1] - across[1] * d, h];
    let lo = fmath::atan((85.0 - h) / d);
    let hi = fmath::atan((scene.beams.top_km + 10.0 - h) / d);
    let el = 0.5 * (lo + hi);
    let look_at = [c[0], c[1], h + d * fmath::tan(el)];
    Camera {
        position: pos,
        look_at,
        up: [0.0, 0.0, 1.0],
        projection: Projection::Perspective,
        fov_deg: (hi - lo).to_degrees() * 1.1,
        ortho_height: 1.0,
    }
}

/// The camera of the shadow-ray study: 12 km above the terrain base, 25 km
/// from the curtain's centre across its axis, looking down at the ground
/// below the curtain (40 degree field of view, every pixel on the ground).
pub fn ground_camera(scene: &Scene, terrain: &Terrain) -> Camera {
    let c = scene.curtains[0].center;
    let (_, across) = curtain_frame(scene);
    let base = terrain.height;
    Camera {
        position: [c[0] - across[0] * 25.0, c[1] - across[1] * 25.0, base + 12.0],
        look_at: [c[0], c[1], base],
        up: [0.0, 0.0, 1.0],
        projection: Projection::Perspective,
        fov_deg: 40.0,
        ortho_height: 1.0,
    }
}

/// The terrain of the shadow-ray study: the scene's, or a plane at height 0
/// when the scene has none (the study needs ground to light).
pub fn ground_terrain(scene: &Scene) -> Terrain {
    match scene.terrain.kind {
        TerrainKind::None => Terrain { kind: TerrainKind::Plane, height: 0.0, ..scene.terrain.clone() },
        _ => scene.terrain.clone(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reduction_keeps_beams_per_km_and_wavelengths() {
        // The default's first arc follows a path: the invariants hold for
        // the straight curtain of its length that the bench puts there.
        let mut s = Scene::default();
        s.curtains[0] = straightened(&s.curtains[0], &mut Vec::new());
        assert!(s.curtains[0].path.is_none() && s.curtains[0].length > 300.0, "{}", s.curtains[0].length);
        let r = reduce(&s, 40.0, None);
        let (full, red) = (&s.curtains[0], &r.scene.curtains[0]);
        assert_eq!(r.scene.curtains.len(), 1);
        assert_eq!(red.length, 40.0);
        // Beams per km: count * share / length, equal to rounding (one beam).
        let per_km_full = s.beams.count as f64 / s.curtains.len() as f64 / full.length;
        let per_km_red = r.scene.beams.count as f64 / red.length;
        assert!((per_km_full - per_km_red).abs() * red.length <= 0.5 + 1e-9, "{per_km_full} {per_km_red}");
        // Wavelengths in km: length / waves.
        let wl = |sc: &Scene| sc.curtains[0].length / sc.footprint.density_waves;
        assert!((wl(&s) - wl(&r.scene)).abs() < 1e-9);
        let bend = |sc: &Scene| sc.curtains[0].length * sc.footprint.bend_wavelength;
        assert!((bend(&s) - bend(&r.scene)).abs() < 1e-9);
        // Cell size along the curtain (the cells the footprint model lays).
        let cell = |sc: &Scene| {
            let c = &sc.curtains[0];
            c.length / crate::pipeline::footprint::cells_along(c, c.length, &sc.footprint) as f64
        };
        // The same to the rounding of the reduced cell count (an integer):
        // within half a cell in the reduced curtain's length.
        let n_red = crate::pipeline::footprint::cells_along(red, red.length, &r.scene.footprint) as f64;
        assert!((cell(&s) / cell(&r.scene) - 1.0).abs() <= 0.5 / n_red + 1e-12, "{} {}", cell(&s), cell(&r.scene));
        r.scene.validate("reduced", None).unwrap();
        // A curtain already shorter is kept whole.
        let r2 = reduce(&r.scene, 100.0, None);
        assert_eq!(r2.scene.curtains[0].length, 40.0);
        assert_eq!(r2.scene.beams.count, r.scene.beams.count);
    }

    #[test]
    fn auto_voxel_size_is_replaced_by_the_full_scenes() {
        let mut s = Scene::default();
        s.grid.voxel_size = VoxelSize::Auto(crate::scene::AutoTag::Auto);
        let r = reduce(&s, 40.0, Some((0.37, "auto: test".into())));
        assert_eq!(r.scene.grid.voxel_size, VoxelSize::Km(0.37));
        assert!(r.changes.iter().any(|c| c.contains("auto -> 0.37 km")));
    }

    #[test]
    fn cameras_validate() {
        let r = reduce(&Scene::default(), 40.0, None);
        let mut s = r.scene.clone();
        s.camera = volume_camera(&s);
        s.validate("volume camera", None).unwrap();
        s.camera = ground_camera(&s, &ground_terrain(&s));
        s.validate("ground camera", None).unwrap();
    }
}
