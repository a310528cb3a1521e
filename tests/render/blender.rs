//! The camera as Blender builds it: the settings documented in
//! `src/geometry/camera.rs` (sensor_fit 'VERTICAL', angle_y = fov, ortho_scale =
//! ortho_height, basis columns right, up', -forward) must project world
//! points to the same film positions in Blender 5.0 as our camera.

use crate::common::{python, venv_python};
use aurora::render::CameraModel;
use aurora::scene::{Camera, Projection};
use glam::DVec3;
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;

/// Film position of a world point as fractions of the frame, (x right, y up
/// from the bottom), the way `world_to_camera_view` reports it.
fn project(m: &CameraModel, p: DVec3) -> (f64, f64) {
    let (w, h) = (m.width as f64, m.height as f64);
    let d = p - m.position;
    let (x, y) = match m.projection {
        Projection::Perspective => {
            let z = d.dot(m.forward);
            (d.dot(m.right) / z / (m.tan_half_fov * w / h), d.dot(m.up) / z / m.tan_half_fov)
        }
        Projection::Orthographic => (d.dot(m.right) / (m.half_height * w / h), d.dot(m.up) / m.half_height),
        p => panic!("{p:?}: panoramic cameras are checked against Cycles in tests/python"),
    };
    // Round trip through our own rays: the film point maps back onto p.
    let r = m.ray((x + 1.0) / 2.0 * w, (1.0 - y) / 2.0 * h);
    let t = (p - r.origin).dot(r.dir);
    assert!((r.origin + r.dir * t - p).length() < 1e-9 * (1.0 + d.length()));
    ((x + 1.0) / 2.0, (y + 1.0) / 2.0)
}

#[test]
fn blender_camera_projects_like_ours() {
    let mut rng = Pcg64::seed_from_u64(8);
    let mut cases = vec![];
    let mut script = String::from("import bpy\nfrom mathutils import Matrix, Vector\nfrom bpy_extras.object_utils import world_to_camera_view\nscene = bpy.context.scene\n");
    for (k, (projection, w, h)) in [
        (Projection::Perspective, 64, 36),
        (Projection::Perspective, 36, 64),
        (Projection::Orthographic, 64, 36),
        (Projection::Orthographic, 30, 50),
    ]
    .into_iter()
    .enumerate()
    {
        let cam = Camera {
            position: [rng.random_range(-5.0..5.0), rng.random_range(-30.0..-20.0), rng.random_range(0.0..3.0)],
            look_at: [rng.random_range(-5.0..5.0), rng.random_range(-5.0..5.0), rng.random_range(5.0..15.0)],
            up: [0.0, 0.0, 1.0],
            projection,
            fov_deg: rng.random_range(20.0..80.0),
            ortho_height: rng.random_range(5.0..20.0),
        };
        let m = CameraModel::new(&cam, w, h).unwrap();
        let (r, u, f, p) = (m.right, m.up, m.forward, m.position);
        script += &format!(
            "cd = bpy.data.cameras.new('c{k}')\ncd.type = '{}'\ncd.sensor_fit = 'VERTICAL'\ncd.angle_y = {:.17e}\ncd.ortho_scale = {:.17e}\ncd.shift_x = cd.shift_y = 0.0\n\
             ob = bpy.data.objects.new('c{k}', cd)\nscene.collection.objects.link(ob)\n\
             ob.matrix_world = Matrix((({:.17e}, {:.17e}, {:.17e}, {:.17e}), ({:.17e}, {:.17e}, {:.17e}, {:.17e}), ({:.17e}, {:.17e}, {:.17e}, {:.17e}), (0, 0, 0, 1)))\n\
             scene.render.resolution_x = {w}\nscene.render.resolution_y = {h}\nscene.render.resolution_percentage = 100\nscene.render.pixel_aspect_x = scene.render.pixel_aspect_y = 1\n\
             bpy.context.view_layer.update()\n",
            if projection == Projection::Perspective { "PERSP" } else { "ORTHO" },
            cam.fov_deg.to_radians(),
            cam.ortho_height,
            r.x, u.x, -f.x, p.x, r.y, u.y, -f.y, p.y, r.z, u.z, -f.z, p.z,
        );
        for i in 0..20 {
            let target = DVec3::from_array(cam.look_at)
                + DVec3::new(rng.random_range(-6.0..6.0), rng.random_range(-3.0..3.0), rng.random_range(-4.0..4.0));
            let want = project(&m, target);
            script += &format!(
                "v = world_to_camera_view(scene, ob, Vector(({:.17e}, {:.17e}, {:.17e})))\nprint('P {k} {i}', repr(v.x), repr(v.y))\n",
                target.x, target.y, target.z
            );
            cases.push((k, i, want));
        }
    }
    let text = python(&venv_python(), &["-c", &script]);
    for (k, i, want) in cases {
        let line = text.lines().find(|l| l.starts_with(&format!("P {k} {i} "))).unwrap_or_else(|| panic!("no output for {k} {i}: {text}"));
        let f: Vec<f64> = line.split(' ').skip(3).map(|v| v.parse().unwrap()).collect();
        // Blender computes in f32 (matrices, vectors): 1e-5 of the frame.
        assert!((f[0] - want.0).abs() < 1e-5 && (f[1] - want.1).abs() < 1e-5, "camera {k} point {i}: Blender {f:?} vs ours {want:?}");
    }
}
