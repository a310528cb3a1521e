//! The reference implementation: Debian's OpenVDB 10.0.1 (pyopenvdb under
//! `/usr/bin/python3`, and `vdb_print`) must open every file we write, in
//! every compression mode with and without half floats, and see exactly our
//! grids; and our reader must load what OpenVDB writes with the same values.
//! Needs `tools/setup`; a missing tool fails the test.

use crate::common::{
    every_mode, mode_name, modes, openvdb_write_tool, rounded, run_json, scratch, system_python, test_grids, vdb_print_ok, vdbrs,
};
use crate::small_bake_toml;
use aurora::grid::{Grid, VoxelValue};
use aurora::io::vdb::read::{read_vdb, Decoder};
use aurora::io::vdb::write::{write_vdb, GridRef, MetaValue, WriteOptions};
use glam::{DVec3, IVec3};
use serde_json::{json, Value};
use std::collections::HashMap;

fn ivec(v: &Value) -> IVec3 {
    let a: Vec<i32> = v.as_array().expect("coordinate").iter().map(|x| x.as_i64().expect("int") as i32).collect();
    IVec3::new(a[0], a[1], a[2])
}

/// A JSON number or list of numbers as f32 components. JSON carries the
/// double repr of each f32, so the conversion back is exact.
fn comps(v: &Value) -> Vec<f32> {
    match v {
        Value::Array(a) => a.iter().map(|x| x.as_f64().expect("number") as f32).collect(),
        x => vec![x.as_f64().expect("number") as f32],
    }
}

fn bits<T: VoxelValue>(v: T) -> Vec<u32> {
    v.components()[..T::COMPONENTS].iter().map(|x| x.to_bits()).collect()
}

/// Checks what OpenVDB reports for one grid against our grid `g` (values
/// already rounded to half if stored as half).
fn check_grid<T: VoxelValue>(j: &Value, g: &Grid<T>, value_type: &str, half: bool, what: &str) {
    check_metadata(j, g, value_type, what);
    check_tree(j, g, value_type, half, what);
}

/// The metadata the writer tests give every grid (units km, seed 7).
fn check_metadata<T: VoxelValue>(j: &Value, g: &Grid<T>, value_type: &str, what: &str) {
    let m = &j["metadata"];
    assert_eq!(m["name"], json!(g.name), "{what}");
    assert_eq!(m["file_voxel_count"].as_u64(), Some(g.active_voxel_count()), "{what}");
    assert_eq!(m["units"], json!("km"), "{what}");
    assert_eq!(m["seed"], json!(7), "{what}");
    assert_eq!(m["value_type"], json!(value_type), "{what}");
}

/// The grid's class, transform and every voxel, as OpenVDB reads them.
fn check_tree<T: VoxelValue>(j: &Value, g: &Grid<T>, value_type: &str, half: bool, what: &str) {
    assert_eq!(j["name"], json!(g.name), "{what}");
    assert_eq!(j["value_type"], json!(value_type), "{what}");
    assert_eq!(j["class"], json!("fog volume"), "{what}");
    assert_eq!(j["half"], json!(half), "{what}");
    assert_eq!(j["active_voxels"].as_u64(), Some(g.active_voxel_count()), "{what}");
    assert_eq!(j["leaf_count"].as_u64(), Some(g.leaf_count() as u64), "{what}");
    let (lo, hi) = g.index_bbox().expect("non-empty");
    assert_eq!(ivec(&j["bbox"][0]), lo, "{what}: bbox min");
    assert_eq!(ivec(&j["bbox"][1]), hi, "{what}: bbox max");
    let t = &j["transform"];
    assert_eq!(t["type"], json!("UniformScaleTranslateMap"), "{what}");
    let s = g.transform.voxel_size;
    assert_eq!(t["voxel_size"], json!([s, s, s]), "{what}");
    // OpenVDB computes s * ijk + t in double, as we do: exact equality.
    for (key, p) in [("0,0,0", [0, 0, 0]), ("1,2,3", [1, 2, 3]), ("-7,100,-1000", [-7, 100, -1000])] {
        let w = g.transform.index_to_world(DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64));
        assert_eq!(t["index_to_world"][key], json!(w.to_array()), "{what}: index_to_world({key})");
    }
    // Every active voxel OpenVDB reads equals ours, bit for bit, and there are no tiles.
    assert_eq!(j["tiles"], json!([]), "{what}");
    let voxels = j["voxels"].as_array().expect("voxels");
    assert_eq!(voxels.len() as u64, g.active_voxel_count(), "{what}");
    for v in voxels {
        let p = ivec(&v[0]);
        assert!(g.is_active(p), "{what}: OpenVDB sees {p} active");
        let ours = g.get(p);
        let theirs = T::from_components(&comps(&v[1]));
        assert_eq!(bits(theirs), bits(ours), "{what}: voxel {p}: OpenVDB {theirs:?}, ours {ours:?}");
    }
    // Sampled coordinates through OpenVDB's accessor: active voxels and their
    // inactive neighbours (background 0, inactive).
    for s in j["samples"].as_array().expect("samples") {
        let p = ivec(&s[0]);
        let theirs = T::from_components(&comps(&s[1]));
        assert_eq!(bits(theirs), bits(g.get(p)), "{what}: sample {p}");
        assert_eq!(s[2].as_bool(), Some(g.is_active(p)), "{what}: active state at {p}");
    }
}

/// Coordinates to sample: every 7th active voxel and the voxel next to it
/// (often inactive), plus far-away empty space.
fn samples<T: VoxelValue>(g: &Grid<T>) -> Vec<[i32; 3]> {
    let mut s: Vec<[i32; 3]> = g.iter_active().step_by(7).flat_map(|(p, _)| [p.to_array(), (p + IVec3::new(0, 0, 1)).to_array()]).collect();
    s.push([123456, -98765, 4321]);
    s
}

#[test]
fn openvdb_reads_every_file_we_write() {
    let dir = scratch("vdb", "openvdb_reads");
    let (d, e) = test_grids();
    let samples_path = dir.join("samples.json");
    std::fs::write(&samples_path, json!({"density": samples(&d), "emission": samples(&e)}).to_string()).unwrap();
    let mut files = Vec::new();
    let metadata = [("units".into(), MetaValue::String("km".into())), ("seed".into(), MetaValue::Int64(7))];
    for (comp, half, opts) in every_mode(&metadata) {
        let path = dir.join(format!("{comp:?}_half{half}.vdb"));
        write_vdb(&path, &[GridRef::Float(&d), GridRef::Vec3(&e)], &opts).unwrap();
        files.push((comp, half, path));
    }
    let mut args: Vec<String> = vec!["--dump".into(), "--samples".into(), samples_path.display().to_string()];
    args.extend(files.iter().map(|(_, _, p)| p.display().to_string()));
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    let report = run_json(&system_python(), "vdb_probe.py", &args);
    let report = report.as_array().expect("one entry per file");
    assert_eq!(report.len(), files.len());
    for ((comp, half, path), r) in files.iter().zip(report) {
        let what = format!("{comp:?} half={half}");
        assert!(r.get("error").is_none(), "{what}: OpenVDB failed: {}", r["error"]);
        let grids = r["grids"].as_array().unwrap();
        let by_name: HashMap<&str, &Value> = grids.iter().map(|g| (g["name"].as_str().unwrap(), g)).collect();
        assert_eq!(grids.len(), 2, "{what}");
        let (dd, ee) = if *half { (rounded(&d), rounded(&e)) } else { (d.clone(), e.clone()) };
        check_grid(by_name["density"], &dd, "float", *half, &format!("{what} density"));
        check_grid(by_name["emission"], &ee, "vec3s", *half, &format!("{what} emission"));
        let printed = vdb_print_ok(path);
        for needle in ["density", "emission", "Tree_float_5_4_3", "Tree_vec3s_5_4_3", "VDB version: 10.0/224"] {
            assert!(printed.contains(needle), "{what}: vdb_print output lacks `{needle}`:\n{printed}");
        }
    }
}

/// An empty grid (and a file of only empty grids) opens in OpenVDB as empty.
#[test]
fn openvdb_reads_empty_grids() {
    let dir = scratch("vdb", "openvdb_empty");
    let d = Grid::new("density", 0.0f32, aurora::grid::Transform::new(1.0, DVec3::ZERO));
    let e = Grid::new("emission", [0.0f32; 3], aurora::grid::Transform::new(1.0, DVec3::ZERO));
    let path = dir.join("empty.vdb");
    write_vdb(&path, &[GridRef::Float(&d), GridRef::Vec3(&e)], &WriteOptions { half: vec!["emission".into()], ..Default::default() })
        .unwrap();
    let r = run_json(&system_python(), "vdb_probe.py", &[path.to_str().unwrap()]);
    let grids = r[0]["grids"].as_array().unwrap_or_else(|| panic!("OpenVDB failed: {r}"));
    assert_eq!(grids.len(), 2);
    for g in grids {
        assert_eq!(g["active_voxels"], json!(0));
        assert_eq!(g["empty"], json!(true));
    }
    vdb_print_ok(&path);
}

/// Files OpenVDB writes (pyopenvdb defaults: Blosc + active mask, with
/// `file_delayed_load` metadata) load through our reader with the same
/// values: tiles densified, vec3s and half grids decoded, unknown types skipped.
#[test]
fn our_reader_reads_files_openvdb_writes() {
    let dir = scratch("vdb", "openvdb_writes");
    let path = dir.join("reference.vdb");
    let r = run_json(&system_python(), "vdb_probe.py", &["--write-reference", path.to_str().unwrap()]);
    let f = read_vdb(&path).unwrap_or_else(|e| panic!("{e}"));
    let grids = r["grids"].as_array().unwrap();
    assert_eq!(f.grids.len(), grids.len());
    for j in grids {
        let name = j["name"].as_str().unwrap();
        let info = f.info(name).unwrap_or_else(|| panic!("grid {name} missing"));
        assert_eq!(json!(info.class), j["class"], "{name}");
        assert_eq!(json!(info.half), j["half"], "{name}");
        match j["value_type"].as_str().unwrap() {
            "float" => check_reference(j, f.float(name).unwrap()),
            "vec3s" => check_reference(j, f.vec3(name).unwrap()),
            other => assert_eq!(info.decoder, Decoder::Skipped, "{name} of type {other}"),
        }
    }
    // Our decoder reads every grid; vdb-rs (the oracle) reads the tile-free
    // float grid the same.
    assert_eq!(f.info("density_plain").unwrap().decoder, Decoder::Native);
    let v = vdbrs::read_vdb_bytes_with_vdbrs(&std::fs::read(&path).unwrap()).unwrap();
    assert_eq!(v.info("density_plain").unwrap().decoder, Decoder::External);
    let (a, b) = (f.float("density_plain").unwrap(), v.float("density_plain").unwrap());
    assert_eq!(a.active_voxel_count(), b.active_voxel_count());
    for (p, x) in a.iter_active() {
        assert_eq!(x.to_bits(), b.get(p).to_bits(), "density_plain at {p}: native vs vdb-rs");
    }
    assert_eq!(f.info("density").unwrap().decoder, Decoder::Native, "tiles");
    assert_eq!(f.info("emission").unwrap().decoder, Decoder::Native, "vec3s");
    assert!(f.info("emission_half").unwrap().half);
    assert_eq!(f.info("emission_half").unwrap().map, "UniformScaleMap");
}

/// Our grid holds exactly OpenVDB's active voxels (tiles expanded) with
/// bit-identical values, and the same transform.
fn check_reference<T: VoxelValue>(j: &Value, g: &Grid<T>) {
    let name = j["name"].as_str().unwrap();
    let mut expect: HashMap<IVec3, T> = HashMap::new();
    for v in j["voxels"].as_array().unwrap() {
        expect.insert(ivec(&v[0]), T::from_components(&comps(&v[1])));
    }
    for t in j["tiles"].as_array().unwrap() {
        let (lo, hi, val) = (ivec(&t[0]), ivec(&t[1]), T::from_components(&comps(&t[2])));
        for x in lo.x..=hi.x {
            for y in lo.y..=hi.y {
                for z in lo.z..=hi.z {
                    expect.insert(IVec3::new(x, y, z), val);
                }
            }
        }
    }
    assert_eq!(expect.len() as u64, j["active_voxels"].as_u64().unwrap(), "{name}: dump covers every active voxel");
    assert_eq!(g.active_voxel_count(), expect.len() as u64, "{name}: active count");
    for (p, v) in &expect {
        assert!(g.is_active(*p), "{name}: {p} inactive in our grid");
        assert_eq!(bits(g.get(*p)), bits(*v), "{name}: value at {p}");
    }
    let bg = T::from_components(&comps(&j["background"]));
    assert_eq!(bits(g.background), bits(bg), "{name}: background");
    for (key, p) in [("0,0,0", [0, 0, 0]), ("1,2,3", [1, 2, 3]), ("-7,100,-1000", [-7, 100, -1000])] {
        let w = g.transform.index_to_world(DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64));
        assert_eq!(j["transform"]["index_to_world"][key], json!(w.to_array()), "{name}: index_to_world({key})");
    }
}

/// A grid whose leaves hold inactive values other than the background, so
/// that every metadata case of OpenVDB's mask compression (0 to 6) occurs.
fn mask_cases_grid() -> Grid<f32> {
    use aurora::grid::{offset_to_local, Leaf, Transform};
    let bg = 0.5f32;
    let mut g = Grid::new("mask_cases", bg, Transform::new(1.0, DVec3::new(0.5, 0.25, -4.0)));
    let cases: [&dyn Fn(usize) -> f32; 7] = [
        &|_| 0.5,
        &|_| -0.5,
        &|_| 3.0,
        &|n| if n % 2 == 0 { -0.5 } else { 0.5 },
        &|n| if n % 2 == 0 { 0.5 } else { 7.0 },
        &|n| if n % 2 == 0 { 7.0 } else { 8.0 },
        &|n| n as f32 * 0.125,
    ];
    for (c, f) in cases.iter().enumerate() {
        let mut leaf = Leaf::new(IVec3::new(8 * c as i32 - 24, -8, 16), bg);
        for n in 0..512 {
            leaf.values[n] = f(n);
            if n % 5 == 0 {
                leaf.set_active(n, true);
                leaf.values[n] = 1.0 + (offset_to_local(n).x as f32) * 0.01;
            }
        }
        g.insert_leaf(leaf);
    }
    g
}

/// Offset where a grid's transform starts (after compression flags and metadata).
fn transform_start(bytes: &[u8], grid_pos: u64) -> usize {
    let mut cur = aurora::io::vdb::parse::Cursor::new(bytes);
    cur.seek(grid_pos + 4).unwrap();
    aurora::io::vdb::parse::read_meta_map(&mut cur).unwrap();
    cur.pos()
}

/// The transform, topology and buffers we write are byte-identical to what
/// OpenVDB's C++ writer (libopenvdb 10.0.1, same compression, same half
/// setting) writes for the same grids, in all twelve modes, including every
/// mask-compression case, ZIP streams (same zlib, level 6) and Blosc frames
/// (our bundled c-blosc 1.21.6 against Debian's 1.21.3 with liblz4 1.9.4:
/// the same LZ4 bytes). Only the header UUID and grid metadata differ.
#[test]
fn tree_bytes_are_identical_to_openvdb_writer() {
    let tool = openvdb_write_tool();
    let dir = scratch("vdb", "openvdb_bytes");
    let (d, e) = test_grids();
    let m = mask_cases_grid();
    for comp in modes() {
        for half in [false, true] {
            let what = format!("{comp:?} half={half}");
            let half_names: Vec<String> = if half { vec!["density".into(), "emission".into(), "mask_cases".into()] } else { vec![] };
            let ours = dir.join(format!("ours_{comp:?}_{half}.vdb"));
            let theirs = dir.join(format!("theirs_{comp:?}_{half}.vdb"));
            let opts = WriteOptions { compression: comp, half: half_names.clone(), metadata: vec![], ..Default::default() };
            write_vdb(&ours, &[GridRef::Float(&d), GridRef::Vec3(&e), GridRef::Float(&m)], &opts).unwrap();
            let mut cmd = std::process::Command::new(&tool);
            cmd.arg(&ours).arg(&theirs).arg(mode_name(comp));
            for h in &half_names {
                cmd.args(["--half", h]);
            }
            let out = cmd.output().expect("run openvdb_write_bench");
            assert!(out.status.success(), "{what}: {}", String::from_utf8_lossy(&out.stderr));
            let (a, b) = (std::fs::read(&ours).unwrap(), std::fs::read(&theirs).unwrap());
            let pa = aurora::io::vdb::parse::parse_file(&a, &|_| false).unwrap();
            let pb = aurora::io::vdb::parse::parse_file(&b, &|_| false).unwrap_or_else(|e| panic!("{what}: OpenVDB's file: {e}"));
            assert_eq!(pa.grids.len(), pb.grids.len());
            for ga in &pa.grids {
                let gb = pb.grids.iter().find(|g| g.header.unique_name == ga.header.unique_name).expect("same grids");
                let (ha, hb) = (&ga.header, &gb.header);
                assert_eq!(ha.type_name, hb.type_name, "{what}");
                assert_eq!(ha.compression, hb.compression, "{what}");
                let (sa, sb) = (transform_start(&a, ha.grid_pos), transform_start(&b, hb.grid_pos));
                let tree_a = &a[sa..ha.end_pos as usize];
                let tree_b = &b[sb..hb.end_pos as usize];
                assert_eq!(ha.block_pos as usize - sa, hb.block_pos as usize - sb, "{what} {}: topology length", ha.unique_name);
                if tree_a != tree_b {
                    let i = tree_a.iter().zip(tree_b).position(|(x, y)| x != y).unwrap_or(tree_a.len().min(tree_b.len()));
                    panic!(
                        "{what} {}: bytes differ at offset {i} after the metadata (lengths {} vs {})",
                        ha.unique_name,
                        tree_a.len(),
                        tree_b.len()
                    );
                }
            }
        }
    }
}

/// The file a default bake writes with the high column apart (both grids
/// as half floats, the column above `grid.high_above_km` in grids of its
/// own at twice the voxel size, no Cycles shell) opens in OpenVDB with all four grids, each on its
/// own transform, bit for bit as our reader sees them; `vdb_print` lists them.
#[test]
fn openvdb_reads_the_default_bake_with_its_high_column() {
    let dir = scratch("vdb", "openvdb_default_bake");
    let mut scene = aurora::scene::Scene::from_toml_str(small_bake_toml!(), "small.toml").unwrap();
    assert!(scene.grid.half_emission && scene.grid.half_density && !scene.grid.cycles_shell);
    scene.grid.high_voxel_factor = 2;
    // The default air is optically thin: its density grids are empty, and
    // OpenVDB reads them as grids with no voxel.
    let thin = aurora::pipeline::bake::bake(&scene, &aurora::util::progress::NoProgress).unwrap();
    aurora::io::bake_folder::write_outputs(&scene, &thin, &dir.join("thin")).unwrap();
    let report = run_json(&system_python(), "vdb_probe.py", &[dir.join("thin").join("aurora.vdb").to_str().unwrap()]);
    let r = &report.as_array().expect("one entry per file")[0];
    assert!(r.get("error").is_none(), "OpenVDB failed: {}", r["error"]);
    for g in r["grids"].as_array().unwrap() {
        let empty = g["name"].as_str().unwrap().starts_with("density");
        assert_eq!(g["active_voxels"].as_u64() == Some(0), empty, "{g}");
    }
    // The artistic air: every grid holds values OpenVDB must read.
    scene.grid.density_a = 0.02;
    let baked = aurora::pipeline::bake::bake(&scene, &aurora::util::progress::NoProgress).unwrap();
    let out = dir.join("out");
    aurora::io::bake_folder::write_outputs(&scene, &baked, &out).unwrap();
    let path = out.join("aurora.vdb");
    let ours = read_vdb(&path).unwrap();
    let (d, e) = (ours.float("density").unwrap(), ours.vec3("emission").unwrap());
    let (dh, eh) = (ours.float("density_high").unwrap(), ours.vec3("emission_high").unwrap());
    assert_eq!(eh.transform.voxel_size, 2.0 * e.transform.voxel_size);
    assert!(eh.active_voxel_count() > 0, "the small scene reaches above the split");
    let samples_path = dir.join("samples.json");
    let s = json!({"density": samples(d), "emission": samples(e), "density_high": samples(dh), "emission_high": samples(eh)});
    std::fs::write(&samples_path, s.to_string()).unwrap();
    let args = ["--dump", "--samples", samples_path.to_str().unwrap(), path.to_str().unwrap()];
    let report = run_json(&system_python(), "vdb_probe.py", &args);
    let r = &report.as_array().expect("one entry per file")[0];
    assert!(r.get("error").is_none(), "OpenVDB failed: {}", r["error"]);
    let grids = r["grids"].as_array().unwrap();
    let by_name: HashMap<&str, &Value> = grids.iter().map(|g| (g["name"].as_str().unwrap(), g)).collect();
    assert_eq!(grids.len(), 4, "{:?}", by_name.keys());
    check_tree(by_name["density"], d, "float", true, "density");
    check_tree(by_name["emission"], e, "vec3s", true, "emission");
    check_tree(by_name["density_high"], dh, "float", true, "density_high");
    check_tree(by_name["emission_high"], eh, "vec3s", true, "emission_high");
    // The default bake's ZIP (libdeflate) and rounded mantissas, as OpenVDB sees them.
    for g in ["density", "emission", "density_high", "emission_high"] {
        let m = &by_name[g]["metadata"];
        assert_eq!(m["file_compression"], json!("zip + active values"), "{g}");
        assert_eq!(m["aurora_mantissa_bits"], json!(scene.grid.mantissa_bits), "{g}");
    }
    let printed = vdb_print_ok(&path);
    for needle in ["density_high", "emission_high", "VDB version: 10.0/224"] {
        assert!(printed.contains(needle), "vdb_print output lacks `{needle}`:\n{printed}");
    }
}
