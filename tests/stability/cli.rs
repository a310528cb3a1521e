//! Where the bake's inputs break it, through the command line and the
//! writer: a deflection angle of 90 degrees (refused by validation), values
//! beyond half-float range in half storage (refused, never written as inf),
//! grids too coarse for the kernel or the curtain (warned), and a foreign
//! VDB whose scaled values would overflow (refused). A VDB too large for
//! the memory is refused under an address-space cap (`tests/capped.rs`).
//!
//! The fluid step far past its CFL limit is pinned in `src/pipeline/footprint/fluid.rs`
//! (`advection_is_bounded_and_finite_far_above_the_cfl_limit`: dt = 100
//! cells, density stays within its initial bounds); `extremes` bakes with
//! the largest `footprint.dt` the scene accepts.

use crate::common::{aurora, file_names as files_in, ok, refused, render_foreign_vdb, scratch, stderr};
use aurora::grid::{Grid, Transform};
use aurora::io::vdb::write::{write_vdb, GridRef, VdbWriteError, WriteOptions};
use glam::{DVec3, IVec3};
use std::path::PathBuf;
use std::process::Output;

fn dir(name: &str) -> PathBuf {
    scratch("stability", name)
}

/// A small scene (one 8 km curtain, a few beams) to which `extra` lines are
/// appended inside the given tables.
fn scene_text(beams: &str, photons: &str, grid: &str, footprint: &str, curtain: &str) -> String {
    format!(
        "seed = 3\n[[curtain]]\nlength = 8.0\nwidth = 4.0\nbend_km = 1.0\n{curtain}\n\
         [footprint]\nresolution = [32, 16]\npressure_iterations = 10\n{footprint}\n\
         [beams]\n{beams}\n[photons]\n{photons}\n[grid]\n{grid}\n"
    )
}

#[test]
fn deflection_of_90_degrees_is_refused_naming_key_and_range_and_nothing_is_written() {
    let d = dir("alpha90");
    for value in ["90", "90.0", "135.5"] {
        let scene = d.join(format!("alpha-{value}.toml"));
        let text = scene_text(&format!("count = 10\nalpha_d_deg = {value}"), "", "", "steps = 2", "");
        std::fs::write(&scene, text).unwrap();
        let out = d.join(format!("out-{value}"));
        let o = aurora(&["bake", scene.to_str().unwrap(), "--out", out.to_str().unwrap()]);
        assert_eq!(o.status.code(), Some(2), "alpha_d_deg = {value}: {}", stderr(&o));
        let e = stderr(&o);
        // File, line (alpha_d_deg is line 13 of the text scene_text builds), key, value, range.
        assert!(e.contains(&format!("{}:13: beams.alpha_d_deg = ", scene.display())), "{e}");
        assert!(e.contains("[0, 90)"), "{e}");
        assert!(!out.exists(), "nothing may be written: {:?}", files_in(&out));
    }
    // Just below 90 is accepted by the scene's checks, and refused by the
    // bake: a cone of 89.9 degrees about a field dipping 78 reaches past the
    // horizontal (exit 2, naming the dip and the limit, nothing written).
    let scene = d.join("alpha-89.toml");
    std::fs::write(&scene, scene_text("count = 10\nalpha_d_deg = 89.9\ndelta_alpha_deg = 10.0", "", "", "steps = 2", "")).unwrap();
    let out = d.join("out-89");
    let o = aurora(&["bake", scene.to_str().unwrap(), "--out", out.to_str().unwrap(), "-q"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    let e = stderr(&o);
    assert!(e.contains("dips only 78.00 degrees") && e.contains("beams.alpha_d_deg = 89.9"), "{e}");
    assert!(files_in(&out).is_empty(), "nothing may be written: {:?}", files_in(&out));
}

#[test]
fn values_beyond_half_range_are_refused_by_the_writer_and_no_file_is_left() {
    let d = dir("half-writer");
    let path = d.join("aurora.vdb");
    let mut e = Grid::new("emission", [0.0f32; 3], Transform::new(0.5, DVec3::ZERO));
    e.set(IVec3::new(1, 2, 3), [1.0, 2.0, 3.0]);
    e.set(IVec3::new(-7, 0, 40), [0.5, 70_000.0, 0.0]);
    let opts = WriteOptions { half: vec!["emission".into()], ..Default::default() };
    let err = write_vdb(&path, &[GridRef::Vec3(&e)], &opts).unwrap_err();
    assert!(matches!(err, VdbWriteError::HalfOverflow { ijk: [-7, 0, 40], .. }), "{err}");
    let m = err.to_string();
    assert!(m.contains("`emission`") && m.contains("(-7, 0, 40)") && m.contains("65504"), "{m}");
    assert!(files_in(&d).is_empty(), "no file, no temporary: {:?}", files_in(&d));
    // Negative values beyond the range too; the largest half itself passes.
    e.set(IVec3::new(-7, 0, 40), [-65_505.0, 0.0, 0.0]);
    assert!(matches!(write_vdb(&path, &[GridRef::Vec3(&e)], &opts), Err(VdbWriteError::HalfOverflow { .. })));
    assert!(files_in(&d).is_empty());
    e.set(IVec3::new(-7, 0, 40), [65_504.0, -65_504.0, 0.0]);
    write_vdb(&path, &[GridRef::Vec3(&e)], &opts).unwrap();
    let back = aurora::io::vdb::read::read_vdb(&path).unwrap();
    let g = back.vec3("emission").unwrap();
    assert_eq!(g.get(IVec3::new(-7, 0, 40)), [65_504.0, -65_504.0, 0.0], "stored exactly, never inf");
}

#[test]
fn a_bake_beyond_half_range_is_written_as_full_floats_with_a_warning() {
    // A tiny point kernel (0.01 km) on 0.2 km voxels with 40 beams at the
    // largest energy flux: the few voxel centres that fall near a photon get
    // its whole kernel peak, about 1.5e5 kR/km, beyond half range. (The
    // default segment kernel spreads each step's power along the step, so
    // the point kernel is asked for.)
    let d = dir("half-bake");
    let body = |half: bool| {
        scene_text(
            "count = 40",
            "radius_km = 0.01\nradius_noise = 0.0\nkernel = \"point\"",
            &format!("voxel_size = 0.2\nhalf_emission = {half}"),
            "steps = 4",
            "energy_flux = 10000.0",
        )
    };
    let scene = d.join("half.toml");
    std::fs::write(&scene, body(true)).unwrap();
    let out = d.join("out-half");
    let o = aurora(&["bake", scene.to_str().unwrap(), "--out", out.to_str().unwrap(), "-q"]);
    // Half floats are the default: where the values do not fit, the grid is
    // stored as full floats, the bake warns naming the key and the limit, and
    // bake.json says which grids fell back.
    assert!(o.status.success(), "{}", stderr(&o));
    let e = stderr(&o);
    assert!(e.contains("grid.half_emission") && e.contains("65504") && e.contains("full floats"), "{e}");
    let report: serde_json::Value = serde_json::from_slice(&std::fs::read(out.join("bake.json")).unwrap()).unwrap();
    assert_eq!(report["files"]["half_emission"], false, "{}", report["files"]);
    assert!(report["files"]["full_float_beyond_half_range"].as_array().unwrap().iter().any(|n| n == "emission"));
    let f = aurora::io::vdb::read::read_vdb(&out.join("aurora.vdb")).unwrap();
    let g = f.vec3("emission").unwrap();
    let peak = g.iter_active().flat_map(|(_, v)| v).fold(0.0f32, f32::max);
    assert!(peak > 65_504.0 && peak.is_finite(), "the values are there, finite: {peak}");
    assert!(g.first_non_finite().is_none());
}

#[test]
fn under_resolved_kernels_and_curtains_are_warned_on_stderr() {
    let d = dir("warnings");
    let run = |name: &str, text: String| -> (Output, PathBuf) {
        let scene = d.join(format!("{name}.toml"));
        std::fs::write(&scene, text).unwrap();
        let out = d.join(format!("out-{name}"));
        // --quiet hides progress and the summary, never warnings.
        (aurora(&["bake", scene.to_str().unwrap(), "--out", out.to_str().unwrap(), "-q"]), out)
    };
    // Resolved: r = 1 km (0.75 with the default radius noise) on 1 km voxels,
    // the fluid spreads the band over more than a km.
    let (o, out) = run("resolved", scene_text("count = 20", "radius_km = 1.0", "voxel_size = 1.0", "steps = 4", ""));
    assert!(o.status.success() && !stderr(&o).contains("warning"), "{}", stderr(&o));
    assert!(out.join("aurora.vdb").exists());

    // Kernel: r_min = 0.2 * 0.75 = 0.15 km < half of 0.5 km.
    let (o, out) = run("kernel", scene_text("count = 20", "radius_km = 0.2", "voxel_size = 0.5", "steps = 4", ""));
    let e = stderr(&o);
    assert!(o.status.success(), "a warning is not an error: {e}");
    assert!(e.contains("aurora: warning: under-resolved kernel") && e.contains("photons.radius_km = 0.2"), "{e}");
    assert!(e.contains("grid.voxel_size <= 0.3"), "the remedy: {e}");
    assert!(out.join("aurora.vdb").exists());
    let json = std::fs::read_to_string(out.join("bake.json")).unwrap();
    assert!(json.contains("under-resolved kernel"), "warnings are kept in bake.json");

    // Curtain: no fluid motion, so the band stays a couple of 0.25 km cells
    // (0.7 km), on 1 km voxels.
    let (o, _) = run(
        "curtain",
        scene_text(
            "count = 20",
            "radius_km = 1.0",
            "voxel_size = 1.0",
            "model = \"fluid2014\"\nsteps = 0\nvelocity_amplitude = 0.0\nband_fraction = 0.02",
            "",
        ),
    );
    let e = stderr(&o);
    assert!(o.status.success(), "{e}");
    assert!(e.contains("aurora: warning: under-resolved curtain: curtain[0]") && e.contains("thinner than a voxel (1 km)"), "{e}");
    assert!(!e.contains("under-resolved kernel"), "{e}");
}

#[test]
fn band_thickness_is_the_band_area_over_the_length() {
    // The library measure behind the curtain warning, against a footprint
    // built by hand: 3 of 16 rows above threshold, rows 0.25 km apart.
    let mut fp = aurora::pipeline::footprint::Footprint {
        nx: 32,
        ny: 16,
        data: vec![0.0; 32 * 16],
        center: [0.0, 0.0],
        rotation_rad: 0.0,
        length: 8.0,
        width: 4.0,
        path: None,
        flux_scale: 1.0,
        filament_share: None,
    };
    for j in 7..10 {
        for i in 0..32 {
            fp.data[j * 32 + i] = 0.5;
        }
    }
    // Cells at 0.5 in three rows: 3 * 0.25 km. The threshold is strict.
    assert!((aurora::pipeline::voxel::band_thickness_km(&fp, 0.03) - 0.75).abs() < 1e-12);
    assert_eq!(aurora::pipeline::voxel::band_thickness_km(&fp, 0.5), 0.0);
    let mut s = aurora::scene::Scene::default();
    s.photons.radius_noise = 0.0;
    s.photons.radius_km = 0.5;
    let w = aurora::pipeline::voxel::resolution_warnings(&s, &[fp.clone()], 0.7);
    assert!(w.is_empty(), "{w:?}");
    let w = aurora::pipeline::voxel::resolution_warnings(&s, &[fp.clone(), fp], 0.8);
    assert_eq!(w.len(), 2, "one per thin curtain: {w:?}");
    let w = aurora::pipeline::voxel::resolution_warnings(&s, &[], 1.01);
    assert_eq!(w.len(), 1, "r = 0.5 < 1.01 / 2: {w:?}");
}

#[test]
fn a_foreign_vdb_whose_scaled_values_would_overflow_is_refused_naming_the_scale() {
    // A valid file (finite values) that only overflows once multiplied by
    // the scene's emission_scale (1e9, the largest the scene accepts):
    // 1e25 x 1e9 = 1e34 per km, and a ray crossing the voxel would reach inf
    // in f32 film. Refused before rendering: exit 2, the key named, no image.
    let d = dir("scaled-overflow");
    let tr = Transform::new(1.0, DVec3::ZERO);
    let mut e: Grid<[f32; 3]> = Grid::new("emission", [0.0; 3], tr);
    e.set(IVec3::new(0, 0, 100), [1e25, 1e25, 1e25]);
    let (render, img) = render_foreign_vdb(&d, &e, "[volume]\nemission_scale = 1e9\n");
    let m = refused(&render.output());
    assert!(m.contains("emission") && m.contains("volume.emission_scale") && m.contains("overflow"), "{m}");
    assert!(!img.exists());
    // The same file at scale 1 renders, every pixel finite.
    let (render, img) = render_foreign_vdb(&d, &e, "");
    ok(&render.output());
    assert!(img.exists());
}
