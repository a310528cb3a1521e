//! The round Earth: an arc's lower border seen from the ground lies at the
//! elevation its altitude has on the sphere (and on a flat ground with
//! `earth.radius_km = 0`), and a long curtain's beams stay along the local
//! field from one end to the other.

use crate::common::small::coarse;
use aurora::geometry::camera::CameraModel;
use aurora::geometry::earth::Earth;
use aurora::physics::geomagnetic_field::{dipole_angles_deg, MagneticField};
use aurora::pipeline::bake::bake;
use aurora::pipeline::beams::trace_all;
use aurora::render::{render, RenderSettings, Volume};
use aurora::scene::{Camera, Curtain, Projection, Scene, TerrainKind};
use aurora::util::colour::luminance;
use aurora::util::fmath;
use aurora::util::progress::NoProgress;
use glam::DVec3;

/// Ground distance of the curtain's start line north of the observer, km.
const NORTH_KM: f64 = 900.0;
/// The fisheye's side, px: 180 degrees over 1200 px is 0.15 degree a pixel.
const SIDE: usize = 1200;
/// The observer's altitude, km.
const EYE_KM: f64 = 0.01;

/// A straight arc along x, 900 km north, uniform along its length (no
/// fluid, no ray or colour noise, no air extinction), seen by a 180-degree
/// fisheye looking at the zenith with north up.
fn arc_scene(radius_km: f64) -> Scene {
    let s = Scene {
        curtains: vec![Curtain { center: [0.0, NORTH_KM], length: 120.0, width: 16.0, bend_km: 0.0, ..Curtain::default() }],
        ..Scene::default()
    };
    let mut s = coarse(s, [64, 16], 6000);
    s.earth.radius_km = radius_km;
    s.footprint.uniform = true;
    s.beams.top_noise_km = 0.0;
    s.colour.noise_km = 0.0;
    s.grid.density_a = 0.0;
    s.camera = Camera {
        position: [0.0, 0.0, EYE_KM],
        look_at: [0.0, 0.0, 1.0],
        up: [0.0, 1.0, 0.0],
        projection: Projection::Fisheye,
        fov_deg: 180.0,
        ..Camera::default()
    };
    s.render.width = SIDE;
    s.render.height = SIDE;
    s.render.spp = 1;
    s.terrain.kind = TerrainKind::None;
    s.background.radiance = [0.0; 3];
    s.background.stars = false;
    s.airglow.on = false;
    s
}

/// The lowest elevation, degrees, along the image column toward north
/// where the luminance exceeds 20 % of the column's peak (linear between
/// the rows that straddle it), and the baked grids.
fn lower_border_elevation(s: &Scene) -> (f64, aurora::pipeline::bake::Bake) {
    let b = bake(s, &NoProgress).unwrap();
    let img =
        render(&RenderSettings::from_scene(s), &Volume { density: Some(&b.density), emission: Some(&b.emission) }, &NoProgress).unwrap();
    let cam = CameraModel::new(&s.camera, SIDE, SIDE).unwrap();
    let col = SIDE / 2;
    // Rows 0 .. SIDE/2 run from the north horizon up to the zenith.
    let rows: Vec<(f64, f64)> = (0..SIDE / 2)
        .map(|r| {
            let p = img.pixel(col, r);
            let el = fmath::asin(cam.ray(col as f64 + 0.5, r as f64 + 0.5).dir.z).to_degrees();
            (el, luminance([p[0] as f64, p[1] as f64, p[2] as f64]))
        })
        .collect();
    let peak = rows.iter().map(|r| r.1).fold(0.0, f64::max);
    assert!(peak > 0.0, "the arc is not in the column");
    let k = rows.iter().position(|r| r.1 > 0.2 * peak).unwrap();
    assert!(k > 0, "the border is at the image's edge");
    let (a, c) = (rows[k - 1], rows[k]);
    let f = (0.2 * peak - a.1) / (c.1 - a.1);
    (a.0 + f * (c.0 - a.0), b)
}

/// From a flat bake's emission: the lowest altitude where the luminance
/// summed over the voxels of |x| < 3 km (across the curtain) exceeds 20 % of
/// its peak over altitude, and the luminance-weighted ground distance of
/// those voxels within 10 km of that altitude.
fn grid_lower_border(b: &aurora::pipeline::bake::Bake) -> (f64, f64) {
    let tr = b.emission.transform;
    let mut prof = std::collections::BTreeMap::<i32, f64>::new();
    let mut pts = Vec::new();
    for (ijk, v) in b.emission.iter_active() {
        let p = tr.index_to_world(ijk.as_dvec3());
        if p.x.abs() < 3.0 {
            let y = luminance([v[0] as f64, v[1] as f64, v[2] as f64]);
            *prof.entry(ijk.z).or_default() += y;
            pts.push((p, y));
        }
    }
    let peak = prof.values().cloned().fold(0.0, f64::max);
    let (&k1, &l1) = prof.iter().find(|(_, &l)| l > 0.2 * peak).unwrap();
    let l0 = prof.get(&(k1 - 1)).copied().unwrap_or(0.0);
    let vs = b.stats.voxel_size_km;
    let h = vs * ((k1 - 1) as f64 + (0.2 * peak - l0) / (l1 - l0));
    let (mut sy, mut sw) = (0.0, 0.0);
    for (p, y) in pts.iter().filter(|(p, _)| (p.z - h).abs() < 10.0) {
        sy += p.y * y;
        sw += y;
    }
    (h, sy / sw)
}

#[test]
fn an_arcs_lower_border_sits_where_its_altitude_puts_it_on_the_sphere_and_on_the_plane() {
    let (e_flat, flat) = lower_border_elevation(&arc_scene(0.0));
    let (h, d) = grid_lower_border(&flat);
    // The curtain's emission stays near its start line; the lower border is
    // a green one.
    assert!((95.0..125.0).contains(&h) && (NORTH_KM - 10.0..NORTH_KM + 60.0).contains(&d), "{h} km at {d} km");
    let want_flat = Earth::FLAT.elevation_deg(EYE_KM, h, d);
    assert!((e_flat - want_flat).abs() < 0.3, "flat: {e_flat} deg, {h} km at {d} km is at {want_flat} deg");
    // The altitude from the flat render, on the sphere.
    let h_flat = EYE_KM + d * fmath::tan(e_flat.to_radians());
    let earth = Earth::new(aurora::geometry::earth::MEAN_RADIUS_KM);
    let want_round = earth.elevation_deg(EYE_KM, h_flat, d);
    let (e_round, _) = lower_border_elevation(&arc_scene(earth.radius_km));
    eprintln!("lower border {h:.2} km at {d:.1} km: flat {e_flat:.3} deg (closed form {want_flat:.3}), round {e_round:.3} deg (closed form {want_round:.3} for {h_flat:.2} km)");
    assert!((e_round - want_round).abs() < 0.3, "round: {e_round} deg, {h_flat} km at {d} km is at {want_round} deg");
    // The two differ by the curvature (about 4.5 degrees here), far beyond
    // the tolerance: the test tells them apart.
    assert!(e_flat - e_round > 3.0, "{e_flat} vs {e_round}");
}

/// The unit field direction at scene point `p` for the field of angles
/// (inclination, declination) relative to the local frame there.
fn local_b(earth: &Earth, p: DVec3, inc: f64, dec: f64) -> DVec3 {
    let q = earth.to_curved(p);
    let [e, n, u] = earth.local_frame(q.x, q.y);
    let b = MagneticField::new(inc, dec).b;
    e * b.x + n * b.y + u * b.z
}

#[test]
fn a_long_curtains_beams_stay_along_the_local_field_at_both_ends() {
    // 2000 km along x through the origin; no deflection (alpha = 0): every
    // step goes along the field, so each photon's segment is the field
    // direction where it lies, up to the curved frame's metric (module doc
    // of `aurora::geometry::earth`: about 0.2 degree at I = 78 deg).
    let earth = Earth::new(aurora::geometry::earth::MEAN_RADIUS_KM);
    for pole in [None, Some([0.0, 2200.0])] {
        let mut s =
            Scene { curtains: vec![Curtain { length: 2000.0, width: 16.0, bend_km: 0.0, ..Curtain::default() }], ..Scene::default() };
        s.footprint.uniform = true;
        s.footprint.resolution = [256, 16];
        s.beams.count = 3000;
        s.beams.alpha_d_deg = 0.0;
        s.beams.delta_alpha_deg = 0.0;
        s.earth.magnetic_pole = pole;
        s.validate("t", None).unwrap();
        let fps = aurora::pipeline::plan::footprints(&s);
        let atm = aurora::pipeline::plan::atmosphere(&s);
        let colour = aurora::pipeline::plan::colour_table(&s, &atm);
        let (photons, _) = trace_all(&s, &fps, &atm, &colour, &NoProgress).unwrap();
        let (mut worst, mut n, mut global) = (0.0f64, 0, 0.0f64);
        let b0 = MagneticField::new(s.beams.b_inclination_deg, s.beams.b_declination_deg).b;
        for ph in &photons {
            let (a, b) = (DVec3::from(ph.position.map(|v| v as f64)), DVec3::from(ph.end.map(|v| v as f64)));
            let seg = b - a;
            // Steps of at least 0.5 km (the f32 positions' 0.1 m rounding
            // is then under 0.02 degree), at the ends of the curtain.
            if seg.length() < 0.5 || a.x.abs() < 900.0 {
                continue;
            }
            let mid = 0.5 * (a + b);
            let (inc, dec) = match pole {
                Some(p) => {
                    let q = earth.to_curved(mid);
                    dipole_angles_deg(&earth, p, [q.x, q.y])
                }
                None => (s.beams.b_inclination_deg, s.beams.b_declination_deg),
            };
            let angle = fmath::acos(seg.normalize().dot(local_b(&earth, mid, inc, dec)).clamp(-1.0, 1.0)).to_degrees();
            worst = worst.max(angle);
            global = global.max(fmath::acos(seg.normalize().dot(b0).clamp(-1.0, 1.0)).to_degrees());
            n += 1;
        }
        eprintln!("{pole:?}: {n} steps at the ends, at most {worst:.3} deg off the local field, {global:.2} deg off the origin's");
        assert!(n > 500, "{pole:?}: {n} steps at the ends");
        assert!(worst < 1.0, "{pole:?}: a step {worst} degrees off the local field");
        // One field for the whole curtain would be 9 degrees off at its ends
        // (1000 km / R): the check can tell.
        assert!(global > 5.0, "{pole:?}: {global}");
    }
}
