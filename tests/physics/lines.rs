//! The lines one at a time: per-line grids (`grid.lines`) in rayleigh per
//! km that add up to `aurora profile`'s photons, and each line following a
//! pulsating patch through its upper state's lifetime (`aurora::physics::emission::line_table`,
//! `aurora::physics::emission::lifetime`).

use crate::common::oracle;
use crate::common::small::coarse;
use crate::common::{aurora, ok, refused, scratch, stderr, with_threads, write};
use aurora::grid::Grid;
use aurora::physics::emission::line_table::{line_lifetimes, LINE_KEYS};
use aurora::pipeline::bake::{self, Bake};
use aurora::scene::{AnimationParams, Curtain, Scene, TerrainKind};
use aurora::util::fmath;
use aurora::util::progress::NoProgress;

/// One 40 x 16 km curtain in the middle of a 200 km pulsation patch (its
/// window there is 1 within 2 %), 400 beams, 1 km voxels, nothing pruned.
pub fn patch_scene() -> Scene {
    let s = Scene {
        curtains: vec![Curtain { center: [100.0, 100.0], length: 40.0, width: 16.0, bend_km: 3.0, ..Curtain::default() }],
        // The footprint table's own keys, not the default preset's art.
        footprint: aurora::scene::FootprintParams::default(),
        ..Scene::default()
    };
    let mut s = coarse(s, [128, 48], 400);
    // The thin sheet and the 2014 walk these tests' figures were measured
    // on: the lifetime law ignores the chemistry's dependence on the local
    // ionization rate, which an 8 km body's broad bright core strengthens
    // (630.0 nm kept 0.0662 of the modulation against the law's 0.0741).
    (s.footprint.sheet_thickness_km, s.footprint.glow) = (0.5, 0.2);
    (s.beams.alpha_d_deg, s.beams.delta_alpha_deg) = (5.0, 3.0);
    s.grid.prune = 0.0;
    s.camera.position = [100.0, 0.0, 1.0];
    s.camera.look_at = [100.0, 100.0, 150.0];
    s
}

/// No folds, bend, drift or rays: the curtain stands still (a pulsation
/// still changes in time).
pub fn hold_still(a: &mut AnimationParams) {
    (a.fold_speed_kms, a.fold_breathing, a.bend_speed_kms, a.bend_change_hz, a.drift_km, a.ray_speed_kms) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
}

/// `s` baked with one thread and with `threads`: the line grids must be
/// the same; both bakes.
pub fn bake_with_one_and(threads: usize, s: &Scene) -> (Bake, Bake) {
    let [a, b] = [1, threads].map(|n| with_threads(n, || bake::bake(s, &NoProgress).unwrap()));
    assert_eq!(a.lines.len(), b.lines.len());
    for (x, y) in a.lines.iter().zip(&b.lines) {
        assert!(x == y, "{} differs between 1 and {threads} threads", x.name);
    }
    (a, b)
}

/// The bake's grid of line `key` (`line_KEY`).
pub fn line_grid<'a>(b: &'a Bake, key: &str) -> &'a Grid<f32> {
    b.lines.iter().find(|g| g.name == format!("line_{key}")).unwrap_or_else(|| panic!("no grid line_{key}"))
}

/// A grid's sum per voxel layer (index k), f64.
fn layers(g: &Grid<f32>) -> std::collections::BTreeMap<i32, f64> {
    let mut m = std::collections::BTreeMap::new();
    for (ijk, v) in g.iter_active() {
        *m.entry(ijk.z).or_insert(0.0) += v as f64;
    }
    m
}

#[test]
fn per_line_grids_sum_to_the_profiles_photons() {
    // Summed over voxels, a grid in R/km (1e3 photons s^-1 / 1e19 per km^3,
    // `aurora::physics::emission::line_table`) times the voxel volume in km^3 times 1e16 is the
    // line's photons per second: `aurora profile`'s total of that line for
    // the same beams. The gather's kernel integrates to 1 and is sampled at
    // one voxel per kernel radius (the discrete sum of a Gaussian of
    // standard deviation h is its integral to e^(-2 pi^2), 3e-9; the cut at
    // 3 r averages out over thousands of photons), and a step's yield is
    // taken at its midpoint where the profile takes each 0.5 km piece's:
    // second-order, below 0.1 % for steps of a few km. 1 % holds with room.
    let mut s = patch_scene();
    s.grid.lines = LINE_KEYS.iter().map(|k| k.to_string()).collect();
    let b = bake::bake(&s, &NoProgress).unwrap();
    assert_eq!(b.lines.len(), 5);
    let prof = aurora::pipeline::altitude_profile::profile(&s, &NoProgress).unwrap();
    let voxel_km3 = fmath::powi(b.emission.transform.voxel_size, 3);
    // Profile columns: ion pairs, then n2p_4278, oi_5577, oi_6300, oi_6364, n2_1p.
    for (key, col) in [("5577", 2), ("6300", 3), ("6364", 4), ("4278", 1), ("n2_1p", 5)] {
        let g = line_grid(&b, key);
        let grid_photons: f64 = g.iter_active().map(|(_, x)| x as f64).sum::<f64>() * voxel_km3 * 1e16;
        let profile_photons: f64 = prof.curtains.iter().flat_map(|c| c.bins.iter()).map(|r| r[col]).sum();
        assert!(profile_photons > 0.0);
        let rel = grid_photons / profile_photons - 1.0;
        assert!(rel.abs() < 0.01, "{key}: grid {grid_photons:.5e} vs profile {profile_photons:.5e} photons/s ({rel:+.4})");
    }
    // The RGB emission is the one it was: a bake without grid.lines has the
    // same emission grid.
    let mut plain = s.clone();
    plain.grid.lines.clear();
    let p = bake::bake(&plain, &NoProgress).unwrap();
    assert!(p.lines.is_empty());
    assert!(p.emission == b.emission, "grid.lines changed the emission grid");
}

#[test]
fn pulsating_patch_lines_keep_the_modulation_their_lifetimes_allow() {
    // A patch of fixed period P = 8 s, 8 frames a period, depth 0.8. Per
    // line, the whole grid's sum over the frames is mean + first harmonic
    // exactly (the source is a sine: a line of lifetime tau keeps
    // g = 1 / sqrt(1 + (omega tau)^2) of it, lagging atan(omega tau); the
    // 8-point DFT of a sine plus a constant is exact). 427.8 nm (lifetime 0)
    // shows the source's depth D. The law predicts for a line whose layer
    // k holds the mean emission E_k at lifetime tau_k the depth
    // D |sum_k E_k g_k e^(-i lag_k)| / sum_k E_k: every beam's altitude
    // distribution is its curtain's spectrum's, whatever its place in the
    // patch, so each layer sees the same source.
    let period = 8.0;
    let n = 8;
    let mut s = patch_scene();
    // The atmosphere the law was checked on (NRLMSIS 2.1 with GLOW's
    // ionosphere, from the source tree's data/). On the default U.S.
    // Standard Atmosphere the 630.0 nm line keeps 0.063 of the modulation
    // against the law's 0.071, 12 % apart: docs/data.md.
    s.atmosphere.model = aurora::scene::AtmosphereModel::Nrlmsis21;
    s.atmosphere.ionosphere = aurora::scene::Ionosphere::Glow;
    // The layers below are the grid's z rows, which are altitudes on a
    // flat ground only.
    s.earth.radius_km = 0.0;
    s.animation.pulsation = 0.8;
    s.animation.pulsation_patch_km = 200.0;
    s.animation.pulsation_period_s = [period, period];
    s.grid.lines = vec!["6300".into(), "5577".into(), "4278".into()];
    // Only the patch changes in time.
    hold_still(&mut s.animation);
    let atm = aurora::pipeline::plan::atmosphere(&s);
    let omega = std::f64::consts::TAU / period;
    // Frame k + 1 of a sequence at n frames a period: t = k P / n.
    let anim = AnimationParams { fps: n as f64 / period, ..s.animation.clone() };
    let mut frames = Vec::new();
    for k in 0..n {
        let mut f = s.clone();
        f.animation = aurora::pipeline::motion::at_frame(&anim, k as i64 + 1);
        frames.push(bake::bake(&f, &NoProgress).unwrap());
    }
    // Per line: mean, first harmonic (complex), mean layer profile.
    let harmonic = |key: &str| {
        let (mut mean, mut re, mut im) = (0.0, 0.0, 0.0);
        let mut prof = std::collections::BTreeMap::<i32, f64>::new();
        for (k, b) in frames.iter().enumerate() {
            let g = line_grid(b, key);
            let total: f64 = g.iter_active().map(|(_, x)| x as f64).sum();
            let phase = omega * k as f64 * period / n as f64;
            mean += total / n as f64;
            re += 2.0 * total * fmath::cos(phase) / n as f64;
            im += 2.0 * total * fmath::sin(phase) / n as f64;
            for (z, e) in layers(g) {
                *prof.entry(z).or_insert(0.0) += e / n as f64;
            }
        }
        let z0 = frames[0].emission.transform;
        let prof: Vec<(f64, f64)> = prof.into_iter().map(|(k, e)| (z0.index_to_world(glam::DVec3::new(0.0, 0.0, k as f64)).z, e)).collect();
        (mean, fmath::hypot(re, im), prof)
    };
    let (m_blue, a_blue, _) = harmonic("4278");
    let depth_blue = a_blue / m_blue;
    // The source's depth: 0.8 w / 2 over 1 - 0.8 w / 2 with w near 1 here.
    assert!((0.5..0.7).contains(&depth_blue), "427.8 nm depth {depth_blue}");
    for (key, line) in [("6300", 1), ("5577", 0)] {
        let (m, a, prof) = harmonic(key);
        let measured = a / m / depth_blue;
        let (mut re, mut im, mut sum) = (0.0, 0.0, 0.0);
        for (z, e) in &prof {
            let tau = line_lifetimes(&atm, *z)[line];
            let (g, lag) = aurora::physics::emission::lifetime::response(omega, tau);
            re += e * g * fmath::cos(lag);
            im += e * g * fmath::sin(lag);
            sum += e;
        }
        let predicted = fmath::hypot(re, im) / sum;
        eprintln!("{key}: kept {measured:.4} of the modulation, the law predicts {predicted:.4}");
        assert!((measured / predicted - 1.0).abs() < 0.1, "{key}: kept {measured:.4} of the modulation, the law predicts {predicted:.4}");
        match key {
            // O(1D) lives 10-100 s where 630.0 nm shines: it barely follows.
            "6300" => assert!(measured < 0.3, "630.0 nm kept {measured}"),
            // O(1S), 0.9 s: 1 / sqrt(1 + (0.785 x 0.9)^2) = 0.82.
            _ => assert!((0.75..0.9).contains(&measured), "557.7 nm kept {measured}"),
        }
    }
}

#[test]
fn render_grid_is_the_line_grid_integrated_along_each_ray() {
    // `aurora render --grid line_6300` of a baked VDB, spp 1 (each pixel's
    // ray through its centre), against the brute-force integral of the
    // file's line grid (taken as grey) through its density along the same
    // rays (`common::oracle::oracle`: Gauss quadrature between every
    // index-plane crossing, independent of the renderer). The renderer's
    // exact integration is accurate to about 1e-11 (its own tests); the
    // f32 image and the grid's f32 values leave some 1e-7: 1e-3 relative,
    // against a floor of 1e-3 of the brightest pixel, is a generous bound
    // that a wrong scale, a missed density or a lost leaf all break.
    let dir = scratch("lines", "render_grid");
    let mut s = patch_scene();
    s.grid.lines = vec!["6300".into()];
    s.grid.density_a = 0.5; // thick enough that the density matters
    s.terrain.kind = TerrainKind::None;
    s.render.width = 48;
    s.render.height = 27;
    s.render.spp = 1;
    s.camera.position = [100.0, 20.0, 60.0];
    s.camera.look_at = [100.0, 100.0, 180.0];
    s.camera.fov_deg = 70.0;
    let scene = write(&dir, "scene.toml", s.to_toml());
    let sc = scene.to_str().unwrap();
    let out = dir.join("bake");
    ok(&aurora(&["bake", "-q", "--out", out.to_str().unwrap(), sc]));
    let vdb = out.join("aurora.vdb");
    let exr = dir.join("line.exr");
    ok(&aurora(&["render", "-q", "--vdb", vdb.to_str().unwrap(), "--grid", "line_6300", "--out", exr.to_str().unwrap(), sc]));
    let (w, h, px) = aurora::render::image_file::read_exr_grey(&exr).unwrap();
    assert_eq!((w, h), (48, 27));
    let file = aurora::io::vdb::read::read_vdb(&vdb).unwrap();
    let density = file.float("density").unwrap();
    let line = aurora::render::grids::grey(file.float("line_6300").unwrap());
    let peak = px.iter().cloned().fold(0.0f32, f32::max) as f64;
    assert!(peak > 0.0);
    let (mut lit, mut attenuated) = (0, 0);
    for y in 0..h {
        for x in 0..w {
            let (o, d) = oracle::camera_ray(&s.camera, w, h, x as f64 + 0.5, y as f64 + 0.5);
            let (tau, l) = oracle::oracle(Some(density), Some(&line), 1.0, 1.0, oracle::RaySpan { o, d, t_max: f64::INFINITY }, 4);
            let got = px[y * w + x] as f64;
            assert!(oracle::rel(got, l[0], 1e-3 * peak) < 1e-3, "pixel ({x}, {y}): {got} R vs brute force {} R", l[0]);
            if l[0] > 0.02 * peak {
                lit += 1;
                attenuated += (tau > 0.05) as usize;
            }
        }
    }
    assert!(lit > 50 && attenuated > 10, "{lit} lit pixels, {attenuated} through density: the test does not test");
    // A name the file does not hold is the user's error, naming what is there.
    let e = refused(&aurora(&["render", "-q", "--vdb", vdb.to_str().unwrap(), "--grid", "line_5577", "--out", exr.to_str().unwrap(), sc]));
    assert!(e.contains("line_6300"), "{e}");
    // PNG: greyscale at the stated scale.
    let png = dir.join("line.png");
    ok(&aurora(&[
        "render",
        "-q",
        "--vdb",
        vdb.to_str().unwrap(),
        "--grid",
        "line_6300",
        "--grid-max",
        "1e9",
        "--out",
        png.to_str().unwrap(),
        sc,
    ]));
    let dec = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&png).unwrap()));
    let reader = dec.read_info().unwrap();
    assert_eq!(reader.info().color_type, png::ColorType::Grayscale);
}

#[test]
fn line_grids_are_the_same_for_any_thread_count_and_a_frame_is_the_plain_bake_at_its_time() {
    // Pulsation on (each line follows its lifetime), two per-line grids:
    // 1 and 3 threads give the same grids, and frame 3 of a 2-fps
    // sequence (`aurora bake --frames`) holds what a plain bake at
    // t = 1 s does, line grids included, listed in the sequence's stage.
    let mut s = patch_scene();
    s.beams.count = 150;
    s.animation = AnimationParams { pulsation: 0.6, fps: 2.0, ..s.animation };
    s.grid.lines = vec!["6300".into(), "5577".into()];
    let at_1s = Scene { animation: AnimationParams { time_s: 1.0, ..s.animation.clone() }, ..s.clone() };
    let (a, _) = bake_with_one_and(3, &at_1s);
    assert_eq!(a.lines.len(), 2);
    let dir = scratch("lines", "sequence");
    let scene = write(&dir, "scene.toml", s.to_toml());
    let out = dir.join("seq");
    ok(&aurora(&["bake", "-q", "--out", out.to_str().unwrap(), "--frames", "3-3", scene.to_str().unwrap()]));
    let file = aurora::io::vdb::read::read_vdb(&out.join("aurora.0003.vdb")).unwrap();
    for g in &a.lines {
        let read = file.float(&g.name).unwrap_or_else(|| panic!("frame 3 has no {}", g.name));
        assert!(read == g, "frame 3's {} is not the plain bake's at t = 1 s", g.name);
    }
    let stage = std::fs::read_to_string(out.join("aurora.usda")).unwrap();
    assert!(stage.contains("def OpenVDBAsset \"line_6300\"") && stage.contains("def OpenVDBAsset \"line_5577\""), "{stage}");
}

#[test]
fn bad_line_names_are_refused_naming_the_key_the_value_and_the_names() {
    let dir = scratch("lines", "bad_names");
    for (lines, colour, want) in [
        (r#"["630"]"#, "physical", r#"grid.lines = "630" is out of range: must be one of "5577", "6300""#),
        (r#"["6300", "6300"]"#, "physical", r#"grid.lines = "6300" is out of range: is listed twice"#),
        (r#"["6300"]"#, "colormap", "needs colour.mode = \"physical\""),
    ] {
        let scene = write(&dir, "scene.toml", format!("[grid]\nlines = {lines}\n\n[colour]\nmode = \"{colour}\"\n"));
        let out = dir.join("out");
        let o = aurora(&["bake", "-q", "--out", out.to_str().unwrap(), scene.to_str().unwrap()]);
        assert_eq!(o.status.code(), Some(2), "{lines}: {}", stderr(&o));
        assert!(stderr(&o).contains(want), "{lines}: {}", stderr(&o));
        assert!(!out.join("aurora.vdb").exists(), "{lines}: a refused scene wrote output");
    }
}
