//! Blender (bpy 5.0.1) loads our VDB (every compression mode, with and
//! without half floats) as a Volume with both grids, and imports
//! our USD stage as a Volume with the same grids; usd-core (pxr) opens the
//! stage and resolves its fields. Needs `tools/setup`; a missing tool fails.

use crate::common::{every_mode, run_json, scratch, test_grids, venv_python};
use aurora::grid::{Grid, VoxelValue};
use aurora::io::usd::write_usda;
use aurora::io::vdb::write::{write_vdb, GridRef, WriteOptions};
use glam::{DVec3, IVec3};
use serde_json::{json, Value};
use std::path::Path;

/// Blender keeps matrices and bounds in f32: a relative tolerance of 1e-6
/// (8 ulps at 2^-23) of the largest magnitude involved.
fn close(a: f64, b: f64, scale: f64) -> bool {
    (a - b).abs() <= 1e-6 * scale.max(1.0)
}

fn num(v: &Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("not a number: {v}"))
}

/// Union of the grids' leaf boxes (OpenVDB `evalLeafBoundingBox`), in index space.
fn leaf_bounds<T: VoxelValue>(g: &Grid<T>, lo: &mut IVec3, hi: &mut IVec3) {
    for l in g.leaves() {
        *lo = lo.min(l.origin);
        *hi = hi.max(l.origin + IVec3::splat(7));
    }
}

/// Checks one Volume object as Blender reports it: both grids with their
/// types, channels and index-to-object matrix, loadable; `object_scale` is
/// the object's own scale (1 for a loaded VDB, metersPerUnit for USD).
fn check_volume(v: &Value, d: &Grid<f32>, e: &Grid<[f32; 3]>, vdb_path: &Path, object_scale: f64) {
    assert_eq!(v["error"], json!(""), "{v}");
    assert_eq!(v["grids_loaded"], json!(true));
    let want = std::fs::canonicalize(vdb_path).unwrap();
    let got = std::fs::canonicalize(v["abs_filepath"].as_str().unwrap()).unwrap();
    assert_eq!(got, want, "volume file path");
    let grids = v["grids"].as_array().unwrap();
    let names: Vec<&str> = grids.iter().map(|g| g["name"].as_str().unwrap()).collect();
    assert_eq!(names, vec!["density", "emission"]);
    let s = d.transform.voxel_size;
    let t = d.transform.translation;
    for (g, (ty, ch)) in grids.iter().zip([("FLOAT", 1), ("VECTOR_FLOAT", 3)]) {
        assert_eq!(g["data_type"], json!(ty), "{g}");
        assert_eq!(g["channels"], json!(ch), "{g}");
        assert_eq!(g["load_ok"], json!(true), "{g}");
        let m = &g["matrix_object"];
        let expect = [[s, 0.0, 0.0, t.x], [0.0, s, 0.0, t.y], [0.0, 0.0, s, t.z], [0.0, 0.0, 0.0, 1.0]];
        for r in 0..4 {
            for c in 0..4 {
                assert!(
                    close(num(&m[r][c]), expect[r][c], t.abs().max_element()),
                    "matrix_object[{r}][{c}] = {} (expected {})",
                    m[r][c],
                    expect[r][c]
                );
            }
        }
    }
    // Object bounds: union of leaf boxes, half a voxel beyond the outer voxel
    // centres, in object space, times the object's scale.
    let (mut lo, mut hi) = (IVec3::MAX, IVec3::MIN);
    leaf_bounds(d, &mut lo, &mut hi);
    leaf_bounds(e, &mut lo, &mut hi);
    let size = (hi - lo + IVec3::ONE).as_dvec3() * s * object_scale;
    let lo_world = d.transform.index_to_world(lo.as_dvec3() - DVec3::splat(0.5));
    for a in 0..3 {
        assert!(close(num(&v["dimensions"][a]), size[a], size.max_element()), "dimension {a}: {} vs {}", v["dimensions"][a], size[a]);
        assert!(close(num(&v["bound_box"][0][a]), lo_world[a], lo_world.abs().max_element()), "bound_box min {a}");
        assert!(close(num(&v["scale"][a]), object_scale, object_scale), "scale {a}");
        assert_eq!(num(&v["rotation_euler"][a]), 0.0, "Z-up stage: no rotation");
    }
}

#[test]
fn blender_loads_our_vdb_and_imports_our_usd_stage() {
    let dir = scratch("vdb", "blender");
    let (d, e) = test_grids();
    let vdb = dir.join("aurora.vdb");
    let opts = WriteOptions { half: vec!["emission".into()], ..Default::default() };
    write_vdb(&vdb, &[GridRef::Float(&d), GridRef::Vec3(&e)], &opts).unwrap();
    let usda = dir.join("aurora.usda");
    write_usda(&usda, "aurora.vdb", &[("density", "float"), ("emission", "float3")], 1000.0).unwrap();
    let py = venv_python();

    // Every compression mode, with and without half floats, then the stage,
    // all in one Blender session (a fresh empty scene per file).
    let mut files = Vec::new();
    for (comp, half, o) in every_mode(&[]) {
        let p = dir.join(format!("{comp:?}_{half}.vdb"));
        write_vdb(&p, &[GridRef::Float(&d), GridRef::Vec3(&e)], &o).unwrap();
        files.push(p);
    }
    let mut args: Vec<&str> = files.iter().map(|p| p.to_str().unwrap()).collect();
    args.push(vdb.to_str().unwrap());
    args.push(usda.to_str().unwrap());
    let r = run_json(&py, "blender_probe.py", &args);
    let r = r.as_array().unwrap_or_else(|| panic!("{r}"));
    assert_eq!(r.len(), files.len() + 2);
    for (p, entry) in files.iter().chain([&vdb]).zip(r) {
        let vols = entry["volumes"].as_array().unwrap_or_else(|| panic!("{entry}"));
        assert_eq!(vols.len(), 1, "{}", p.display());
        check_volume(&vols[0], &d, &e, p, 1.0);
    }

    // The USD stage: one Volume object (plus an Empty per field prim),
    // metersPerUnit 1000 -> object scale 1000, Z up -> no rotation.
    let u = &r[files.len() + 1];
    assert_eq!(u["import_status"], json!(["FINISHED"]), "{u}");
    let vols = u["volumes"].as_array().unwrap();
    assert_eq!(vols.len(), 1, "one Volume object: {u}");
    assert_eq!(u["object_types"], json!(["EMPTY", "EMPTY", "VOLUME"]));
    check_volume(&vols[0], &d, &e, &vdb, 1000.0);

    // usd-core: the stage, its metadata and resolved fields.
    let u = run_json(&py, "usd_probe.py", &[usda.to_str().unwrap()]);
    assert_eq!(u["default_prim"], json!("/aurora"));
    assert_eq!(u["meters_per_unit"], json!(1000.0));
    assert_eq!(u["up_axis"], json!("Z"));
    assert_eq!(u["prims"], json!([["/aurora", "Volume"], ["/aurora/density", "OpenVDBAsset"], ["/aurora/emission", "OpenVDBAsset"]]));
    let v = &u["volumes"][0];
    let identity = json!([[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]]);
    assert_eq!(v["local_transform"], identity);
    for (name, ty) in [("density", "float"), ("emission", "float3")] {
        let f = &v["fields"][name];
        assert_eq!(f["is_openvdb_asset"], json!(true), "{name}");
        assert_eq!(f["file_path"], json!("aurora.vdb"), "{name}");
        let resolved = std::fs::canonicalize(f["resolved_path"].as_str().unwrap_or("")).unwrap();
        assert_eq!(resolved, std::fs::canonicalize(&vdb).unwrap(), "{name}");
        assert_eq!(f["field_name"], json!(name));
        assert_eq!(f["field_class"], json!("fogVolume"));
        assert!(f["field_class_allowed"].as_array().unwrap().contains(&json!("fogVolume")), "fogVolume is a schema token");
        assert_eq!(f["field_data_type"], json!(ty));
    }
}
