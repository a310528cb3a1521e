//! Curtains along paths: the footprint follows the curve, a straight path is
//! the straight curtain, bad paths are refused naming the key, a long path
//! stays within the memory budget, and the `oval` preset's arc is drawn in
//! one piece through its middle point overhead.

use crate::common::small::coarse;
use crate::common::{aurora, refused, scratch, write};
use aurora::pipeline::bake::bake;
use aurora::pipeline::footprint::curtain_path::{lift_km, vertices, PATH_ALTITUDE_KM};
use aurora::scene::{Curtain, Scene, VoxelSize};
use aurora::util::fmath;
use aurora::util::progress::NoProgress;

/// One curtain, a coarse footprint and few beams on 1 km voxels.
fn scene_with(c: Curtain) -> Scene {
    coarse(Scene { curtains: vec![c], ..Scene::default() }, [128, 48], 1500)
}

/// Distance from (x, y) to a polyline.
fn distance(v: &[[f64; 2]], x: f64, y: f64) -> f64 {
    v.windows(2)
        .map(|w| {
            let (dx, dy) = (w[1][0] - w[0][0], w[1][1] - w[0][1]);
            let t = (((x - w[0][0]) * dx + (y - w[0][1]) * dy) / (dx * dx + dy * dy)).clamp(0.0, 1.0);
            (fmath::powi(x - w[0][0] - t * dx, 2) + fmath::powi(y - w[0][1] - t * dy, 2)).sqrt()
        })
        .fold(f64::INFINITY, f64::min)
}

#[test]
fn emission_of_the_lower_border_follows_a_curved_path() {
    // 300 km with one bend; the path is where the 95-125 km emission lies,
    // not the starts (which are lift_km = 31.9 km south of it).
    let path = vec![[-150.0, 0.0], [-40.0, 40.0], [60.0, 60.0], [150.0, 20.0]];
    let c = Curtain { path: Some(path.clone()), width: 24.0, bend_km: 4.0, ..Curtain::default() };
    let s = scene_with(c.clone());
    s.validate("t", None).unwrap();
    let b = bake(&s, &NoProgress).unwrap();
    let curve = vertices(&path);
    let (mut near, mut all) = (0.0, 0.0);
    for (ijk, e) in b.emission.iter_active() {
        let p = b.emission.transform.index_to_world(ijk.as_dvec3());
        if !(95.0..125.0).contains(&p.z) {
            continue;
        }
        let w = (e[0] + e[1] + e[2]) as f64;
        all += w;
        if distance(&curve, p.x, p.y) <= 0.5 * c.width + c.bend_km {
            near += w;
        }
    }
    // The 95-125 km layer sits within +-15 km of the path's altitude, so
    // within 15 cot(78 deg) = 3.2 km of it horizontally; the rest of the
    // spread is the band's folds and bend, inside width / 2 + bend_km.
    // Unlifted, the emission would lie 32 km off, beyond that 16 km.
    assert!(all > 0.0);
    assert!(near / all >= 0.9, "{:.3} of the 95-125 km emission within {} km of the path", near / all, 0.5 * c.width + c.bend_km);
    // It covers the whole length: emission near both ends.
    let near_end = |q: [f64; 2]| {
        b.emission.iter_active().any(|(ijk, _)| {
            let p = b.emission.transform.index_to_world(ijk.as_dvec3());
            (95.0..125.0).contains(&p.z) && (fmath::powi(p.x - q[0], 2) + fmath::powi(p.y - q[1], 2)).sqrt() < 20.0
        })
    };
    assert!(near_end(path[0]) && near_end(path[3]));
}

#[test]
fn a_straight_two_point_path_is_the_straight_curtain() {
    // The path at 110 km, from (-40, 10) to (40, 10 + 80 tan 20 deg): the
    // straight curtain of length 80 km rotated 20 degrees, centred on the
    // path's middle lifted to the start altitude.
    let rot = 20f64.to_radians();
    let (a, b) = ([-40.0 * fmath::cos(rot), 10.0 - 40.0 * fmath::sin(rot)], [40.0 * fmath::cos(rot), 10.0 + 40.0 * fmath::sin(rot)]);
    let lift = lift_km(&Scene::default().beams);
    let straight =
        Curtain { center: [lift[0], 10.0 + lift[1]], length: 80.0, width: 20.0, rotation_deg: 20.0, bend_km: 3.0, ..Curtain::default() };
    let along = Curtain { path: Some(vec![a, b]), ..straight.clone() };
    let (s1, s2) = (scene_with(straight), scene_with(along));
    let (f1, f2) = (aurora::pipeline::plan::footprints(&s1), aurora::pipeline::plan::footprints(&s2));
    assert_eq!((f1[0].nx, f1[0].ny), (f2[0].nx, f2[0].ny));
    assert!((f1[0].length - f2[0].length).abs() < 1e-9);
    let worst = f1[0].data.iter().zip(&f2[0].data).map(|(x, y)| (x - y).abs()).fold(0.0f32, f32::max);
    // Only the last bits of the length differ (f32 footprint values).
    assert!(worst < 1e-5, "footprints differ by {worst}");
    for (u, v) in [(-30.0, 4.0), (0.0, 0.0), (35.0, -8.0)] {
        let (p, q) = (f1[0].to_world(u, v), f2[0].to_world(u, v));
        assert!((p.0 - q.0).abs() < 1e-6 && (p.1 - q.1).abs() < 1e-6, "{p:?} {q:?}");
    }
    let (b1, b2) = (bake(&s1, &NoProgress).unwrap(), bake(&s2, &NoProgress).unwrap());
    let total = |b: &aurora::pipeline::bake::Bake| b.emission.iter_active().map(|(_, e)| (e[0] + e[1] + e[2]) as f64).sum::<f64>();
    let (t1, t2) = (total(&b1), total(&b2));
    assert!((t1 - t2).abs() <= 1e-4 * t1, "{t1} {t2}");
    assert_eq!(b1.emission.active_voxel_count(), b2.emission.active_voxel_count());
    let _ = PATH_ALTITUDE_KM;
}

#[test]
fn bad_paths_are_refused_naming_the_key() {
    for (text, want) in [
        ("[[curtain]]\npath = [[0.0, 0.0]]\n", "at least 2 points"),
        ("[[curtain]]\npath = [[0.0, 0.0], [0.0, 0.0], [50.0, 0.0]]\n", "repeated point"),
        ("[[curtain]]\ncenter = [1.0, 2.0]\npath = [[0.0, 0.0], [50.0, 0.0]]\n", "not both"),
        ("[[curtain]]\nrotation_deg = 5.0\nlength = 20.0\npath = [[0.0, 0.0], [50.0, 0.0]]\n", "length, rotation_deg"),
        ("[[curtain]]\npath = [[0.0, 0.0, 3.0], [50.0, 0.0]]\n", "[x, y]"),
    ] {
        let m = Scene::from_toml_str(text, "p.toml").unwrap_err().to_string();
        assert!(m.contains("curtain[0].path") && m.contains(want), "{text}: {m}");
    }
    // The command line: exit status 2, the key in the message, no output.
    let d = scratch("path", "bad");
    let f = write(&d, "bad.toml", "[[curtain]]\ncenter = [1.0, 2.0]\npath = [[0.0, 0.0], [50.0, 0.0]]\n");
    let out = d.join("out");
    let e = refused(&aurora(&["bake", f.to_str().unwrap(), "--out", out.to_str().unwrap()]));
    assert!(e.contains("curtain[0].path"), "{e}");
    assert!(!out.join("aurora.vdb").exists());
    // A path curtain round-trips through TOML without the straight keys.
    let s = scene_with(Curtain { path: Some(vec![[0.0, 0.0], [50.0, 10.0], [90.0, 0.0]]), ..Curtain::default() });
    let text = s.to_toml();
    assert!(!text.contains("rotation_deg"), "{text}");
    assert_eq!(Scene::from_toml_str(&text, "rt").unwrap(), s);
}

#[test]
fn a_3000_km_path_fits_the_memory_budget() {
    // An arc of 3000 km (a quarter of a circle of radius 1910 km) through 7 points.
    let r = 3000.0 / std::f64::consts::FRAC_PI_2;
    let path: Vec<[f64; 2]> =
        (0..7).map(|i| std::f64::consts::FRAC_PI_2 * i as f64 / 6.0).map(|a| [r * fmath::cos(a), r * fmath::sin(a) - r]).collect();
    let mut s = Scene { curtains: vec![Curtain { path: Some(path), ..Curtain::default() }], ..Scene::default() };
    s.beams.count = 20_000;
    s.grid.voxel_size = VoxelSize::Km(1.0);
    s.validate("t", None).unwrap();
    let plan = aurora::pipeline::plan::BakePlan::new(&s, &aurora::util::progress::NoProgress);
    let e = aurora::pipeline::memory::budget::estimate(&plan, aurora::pipeline::memory::budget::LeafCount::Bands);
    // Default width 40 km, 128 cells across: 0.3125 km, and the sheet's
    // cells as long as wide, so about 9600 cells along, an f32 each kept.
    let fp = e.terms.iter().find(|t| t.what == "footprints").unwrap();
    assert!(fp.bytes > 9000.0 * 128.0 * 4.0 && fp.bytes < 10_000.0 * 128.0 * 4.0, "{}", fp.bytes);
    // The band bound at 1 km voxels, far below the 2000 x 2000 km box's leaves.
    assert!(e.total() < 8.0 * (1u64 << 30) as f64, "{}: {:?}", aurora::util::memory::gib(e.total()), e.terms);
    let f = &aurora::pipeline::plan::footprints(&s)[0];
    assert!((f.length - 3000.0).abs() < 5.0 && f.nx >= 9000, "{} km, {} cells", f.length, f.nx);
    assert!(f.data.iter().any(|&d| d > 0.5));
}

#[test]
fn the_oval_arc_is_one_piece_overhead() {
    // The `oval` preset's arc overhead: its middle point, at the camera's
    // zenith, is a knot of the spline, the dipole's lift is due south there
    // and turns either side, and the two halves' beams start on either side
    // of u = 0. With a uniform footprint the lower border's emission along
    // the arc is flat, so any dip at the middle is a seam drawn by a stage
    // between the path and the grid (frame, lift, starts, gather), not the
    // footprint's rays and gaps. The arc kept to its 5 middle points
    // (+-156 km, the frame and lift as in the preset), 20,000 beams: about
    // 64 a km along it, stratified.
    let mut s = aurora::scene::presets::oval();
    let path = s.curtains[0].path.clone().unwrap();
    let mid = path.len() / 2;
    assert!(path[mid][0].abs() < 1e-3 && path[mid][1].abs() < 1e-3, "the middle point is overhead: {:?}", path[mid]);
    s.curtains[0].path = Some(path[mid - 2..=mid + 2].to_vec());
    s.footprint.uniform = true;
    s.beams.count = 20_000;
    s.validate("t", None).unwrap();
    let b = bake(&s, &NoProgress).unwrap();
    // The 95-140 km emission (the green lower border) in 4 km bins along x:
    // bin k holds the voxels centred in [4k - 2, 4k + 2) km, four each.
    let mut bins = [0.0f64; 31];
    for (ijk, e) in b.emission.iter_active() {
        let p = b.emission.transform.index_to_world(ijk.as_dvec3());
        let k = ((p.x + 2.0) / 4.0).floor() as i64 + 15;
        if (95.0..140.0).contains(&p.z) && (0..31).contains(&k) {
            bins[k as usize] += (e[0] + e[1] + e[2]) as f64;
        }
    }
    // Reference: the arc 20-60 km either side of the middle, whose bins
    // scatter by 1.4 % rms (stratified starts). A seam like a gap of the
    // sheet's rays (4 km wide, 30-70 % deep) is far outside 6 %: starts
    // kept out of |u| < 1 km put the middle bin at 0.79.
    let at = |k: i64| bins[(k + 15) as usize];
    let far: Vec<f64> = (-15..=15).filter(|k: &i64| k.abs() >= 5).map(at).collect();
    let mean = far.iter().sum::<f64>() / far.len() as f64;
    let scatter = (far.iter().map(|v| fmath::powi(v / mean - 1.0, 2)).sum::<f64>() / far.len() as f64).sqrt();
    let near: Vec<f64> = (-4..=4).map(|k| at(k) / mean).collect();
    assert!(mean > 0.0 && scatter < 0.03, "the arc 20-60 km from the middle scatters by {scatter:.3}");
    assert!(
        near.iter().all(|&r| (r - 1.0).abs() < 0.06),
        "the arc's 4 km bins within 18 km of the middle, of the mean 20-60 km away: {near:.3?}"
    );
}
