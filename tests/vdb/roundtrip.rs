//! Writer -> reader round trips (through vdb-rs where it reads the grid, our
//! parser elsewhere) in every compression mode, the native-decoder oracle
//! against vdb-rs, atomic writes, empty grids, and corrupt input: every
//! truncation and a few hundred seeded random byte changes must give an error
//! or a successful read, never a panic or a hang.

use crate::common::damaged::{body_cuts, cut_body, random_changes, small_file, truncation_lengths};
use crate::common::{every_mode, modes, rounded, scratch, test_grids, vdbrs, with_threads};
use aurora::grid::{Grid, Transform, VoxelValue};
use aurora::io::vdb::read::{read_native_float_grids, read_vdb, read_vdb_bytes, Decoder, RawMeta};
use aurora::io::vdb::write::{write_vdb, write_vdb_bytes, GridRef, MetaValue, WriteOptions};
use aurora::scene::Compression;
use glam::{DVec3, IVec3};
use std::time::{Duration, Instant};

/// Every voxel of `b` is active exactly where it is in `a`, with bit-identical
/// values (so -0.0 and +0.0 differ, NaN payloads would too); transform, name
/// and background equal.
fn assert_same<T: VoxelValue>(a: &Grid<T>, b: &Grid<T>, what: &str) {
    assert_eq!(a.name, b.name, "{what}: name");
    assert_eq!(a.transform, b.transform, "{what}: transform");
    assert_eq!(a.background.components().map(f32::to_bits), b.background.components().map(f32::to_bits), "{what}: background");
    assert_eq!(a.leaf_count(), b.leaf_count(), "{what}: leaf count");
    for la in a.leaves() {
        let lb = b.leaf(la.origin).unwrap_or_else(|| panic!("{what}: leaf {} missing", la.origin));
        assert_eq!(la.mask, lb.mask, "{what}: mask of leaf {}", la.origin);
        for n in 0..la.values.len() {
            let (va, vb) = (la.values[n].components(), lb.values[n].components());
            assert_eq!(va.map(f32::to_bits), vb.map(f32::to_bits), "{what}: value {n} of leaf {}: {va:?} vs {vb:?}", la.origin);
        }
    }
}

fn extra_meta() -> Vec<(String, MetaValue)> {
    vec![
        ("units".into(), MetaValue::String("km".into())),
        ("seed".into(), MetaValue::Int64(-42)),
        ("scene_hash".into(), MetaValue::String("0123abcd".into())),
        ("exposure".into(), MetaValue::Float(1.5)),
        ("km_per_unit".into(), MetaValue::Double(1.0)),
        ("baked".into(), MetaValue::Bool(true)),
        ("res".into(), MetaValue::Vec3i([1, -2, 3])),
        ("sun".into(), MetaValue::Vec3d([0.1, 0.2, -0.97])),
    ]
}

#[test]
fn round_trip_every_mode_bit_exact() {
    let (d, e) = test_grids();
    for (comp, half, opts) in every_mode(&extra_meta()) {
        let what = format!("{comp:?} half={half}");
        let bytes = write_vdb_bytes(&[GridRef::Float(&d), GridRef::Vec3(&e)], &opts).unwrap();
        let f = read_vdb_bytes(&bytes).unwrap_or_else(|err| panic!("{what}: {err}"));
        let (d_expect, e_expect) = if half { (rounded(&d), rounded(&e)) } else { (d.clone(), e.clone()) };
        assert_same(&d_expect, f.float("density").expect("density"), &what);
        assert_same(&e_expect, f.vec3("emission").expect("emission"), &what);
        // Our decoder reads every grid; vdb-rs, the independent oracle,
        // reads the plain float ones and agrees exactly.
        let di = f.info("density").unwrap();
        assert_eq!(di.decoder, Decoder::Native, "{what}");
        assert_eq!(f.info("emission").unwrap().decoder, Decoder::Native);
        let v = vdbrs::read_vdb_bytes_with_vdbrs(&bytes).unwrap();
        let vi = v.info("density").unwrap();
        assert_eq!(vi.decoder, if half { Decoder::Native } else { Decoder::External }, "{what}");
        assert_same(v.float("density").unwrap(), f.float("density").unwrap(), &format!("{what}: native vs vdb-rs"));
        let native = read_native_float_grids(&bytes).unwrap();
        assert_same(f.float("density").unwrap(), &native[0], &format!("{what}: native"));
        for info in &f.grids {
            assert_eq!(info.class, "fog volume");
            assert_eq!(info.half, half);
            assert_eq!(info.map, "UniformScaleTranslateMap");
            let m = |k: &str| info.metadata.iter().find(|(key, _)| key == k).map(|(_, v)| v.clone());
            assert_eq!(m("units"), Some(RawMeta::String("km".into())));
            assert_eq!(m("seed"), Some(RawMeta::Int64(-42)));
            assert_eq!(m("res"), Some(RawMeta::Vec3i([1, -2, 3])));
            assert_eq!(m("sun"), Some(RawMeta::Vec3d([0.1, 0.2, -0.97])));
            assert_eq!(m("exposure"), Some(RawMeta::Float(1.5)));
            assert_eq!(m("baked"), Some(RawMeta::Bool(true)));
            assert_eq!(m("name"), Some(RawMeta::String(info.name.clone())));
        }
        let dm = &di.metadata;
        let bb = d.index_bbox().unwrap();
        assert!(dm.contains(&("file_bbox_min".into(), RawMeta::Vec3i(bb.0.to_array()))));
        assert!(dm.contains(&("file_bbox_max".into(), RawMeta::Vec3i(bb.1.to_array()))));
        assert!(dm.contains(&("file_voxel_count".into(), RawMeta::Int64(d.active_voxel_count() as i64))));
        assert!(dm.contains(&("value_type".into(), RawMeta::String("float".into()))));
    }
}

/// Negative zero, tiny subnormals and a non-zero background survive exactly.
#[test]
fn round_trip_special_values_and_background() {
    let mut g = Grid::new("d", 0.25f32, Transform::new(2.0, DVec3::new(-1e6, 0.5, 3.0)));
    g.set(IVec3::new(-3, 0, 0), -0.0);
    g.set(IVec3::new(-2, 0, 0), f32::from_bits(1)); // smallest subnormal
    g.set(IVec3::new(-1, 0, 0), f32::MAX);
    g.set(IVec3::new(0, 0, 0), -f32::MAX);
    g.set(IVec3::new(5, 5, 5), 0.25); // equal to the background but active
    for comp in modes() {
        let bytes = write_vdb_bytes(&[GridRef::Float(&g)], &WriteOptions { compression: comp, ..Default::default() }).unwrap();
        let f = read_vdb_bytes(&bytes).unwrap();
        assert_same(&g, &f.float_grids[0], &format!("{comp:?}"));
        let v = vdbrs::read_vdb_bytes_with_vdbrs(&bytes).unwrap();
        assert_eq!(v.grids[0].decoder, Decoder::External);
        assert_same(&g, &v.float_grids[0], &format!("{comp:?} vdb-rs"));
        assert_same(&g, &read_native_float_grids(&bytes).unwrap()[0], &format!("{comp:?} native"));
    }
}

#[test]
fn empty_grids_and_empty_files_are_valid() {
    let d = Grid::new("density", 0.0f32, Transform::new(0.5, DVec3::ZERO));
    let e = Grid::new("emission", [0.0f32; 3], Transform::new(0.5, DVec3::ZERO));
    for comp in modes() {
        let opts = WriteOptions { compression: comp, half: vec!["emission".into()], metadata: vec![], ..Default::default() };
        let bytes = write_vdb_bytes(&[GridRef::Float(&d), GridRef::Vec3(&e)], &opts).unwrap();
        let f = read_vdb_bytes(&bytes).unwrap();
        assert_eq!(f.float("density").unwrap().active_voxel_count(), 0);
        assert_eq!(f.vec3("emission").unwrap().leaf_count(), 0);
        let m = &f.info("density").unwrap().metadata;
        assert!(m.contains(&("file_voxel_count".into(), RawMeta::Int64(0))));
        assert!(m.contains(&("file_bbox_min".into(), RawMeta::Vec3i([i32::MAX; 3]))));
    }
    let none = write_vdb_bytes(&[], &WriteOptions::default()).unwrap();
    assert_eq!(none.len(), 57 + 4 + 4);
    let f = read_vdb_bytes(&none).unwrap();
    assert!(f.grids.is_empty());
}

#[test]
fn write_vdb_is_atomic_and_reports_stats() {
    let dir = scratch("vdb", "atomic");
    let path = dir.join("aurora.vdb");
    std::fs::write(&path, b"old contents").unwrap();
    let (d, e) = test_grids();
    let stats = write_vdb(&path, &[GridRef::Float(&d), GridRef::Vec3(&e)], &WriteOptions::default()).unwrap();
    let on_disk = std::fs::read(&path).unwrap();
    assert_eq!(stats.bytes, on_disk.len() as u64);
    assert_eq!(stats.grids[0].active_voxels, d.active_voxel_count());
    assert_eq!(stats.grids[1].leaves, e.leaf_count());
    assert_eq!(stats.grids.iter().map(|g| g.bytes).sum::<u64>() + 65, stats.bytes);
    let names: Vec<_> = std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert_eq!(names.len(), 1, "no temporary file left behind: {names:?}");
    let f = read_vdb(&path).unwrap();
    assert_same(&d, f.float("density").unwrap(), "from disk");
    // A refused write leaves the old file untouched.
    let mut bad = d.clone();
    bad.set(IVec3::new(1, 1, 1), f32::NAN);
    assert!(write_vdb(&path, &[GridRef::Float(&bad)], &WriteOptions::default()).is_err());
    assert_eq!(std::fs::read(&path).unwrap(), on_disk);
    // Errors name the file.
    let err = read_vdb(&dir.join("missing.vdb")).unwrap_err().to_string();
    assert!(err.contains("missing.vdb"), "{err}");
    std::fs::write(dir.join("junk.vdb"), b"this is not a vdb file at all").unwrap();
    let err = read_vdb(&dir.join("junk.vdb")).unwrap_err().to_string();
    assert!(err.contains("junk.vdb") && err.contains("magic"), "{err}");
}

/// Reads, and fails the test on a hang. A read of these few-KB files takes
/// milliseconds; a corrupted file may legitimately declare active tiles that
/// densify into up to `MAX_TILE_VOXELS` voxels (~0.2 s alone), and the machine
/// is shared, so only a read over 10 s counts as a hang.
fn read_timed(bytes: &[u8]) -> Result<aurora::io::vdb::read::VdbFile, String> {
    let t0 = Instant::now();
    let r = read_vdb_bytes(bytes).map_err(|e| e.to_string());
    assert!(t0.elapsed() < Duration::from_secs(10), "read of {} bytes took {:?}", bytes.len(), t0.elapsed());
    r
}

#[test]
fn every_truncation_is_an_error() {
    for (comp, half) in [(Compression::ZipActiveMask, false), (Compression::None, true), (Compression::ActiveMask, false)] {
        let full = small_file(comp, half);
        assert!(read_timed(&full).is_ok());
        eprintln!("{comp:?} half={half}: {} bytes", full.len());
        // Every length for files up to 64 KiB; for the larger uncompressed
        // file, the lengths `truncation_lengths` keeps.
        for len in truncation_lengths(full.len()) {
            let r = read_timed(&full[..len]);
            assert!(r.is_err(), "{comp:?}: truncation to {len} of {} bytes read successfully", full.len());
        }
    }
}

#[test]
fn random_byte_changes_never_panic_or_hang() {
    let (mut ok, mut err) = (0, 0);
    for (seed, (comp, half)) in
        [(Compression::ZipActiveMask, false), (Compression::None, false), (Compression::ActiveMask, true), (Compression::Zip, true)]
            .into_iter()
            .enumerate()
    {
        let full = small_file(comp, half);
        // One to three bytes replaced by random values (a "flip" of a whole byte).
        for b in random_changes(&full, 0x5eed_2024 + seed as u64, 100) {
            match read_timed(&b) {
                Ok(_) => ok += 1,
                Err(msg) => {
                    assert!(msg.contains("<memory>"), "error names the source: {msg}");
                    err += 1
                }
            }
        }
        // The magic and the offsets flag are always checked.
        for at in (0..8).chain([20]) {
            let mut b = full.clone();
            b[at] ^= 0x41;
            assert!(read_timed(&b).is_err(), "change at byte {at} not detected");
        }
    }
    // Both outcomes occur: changes in value data read, structural ones fail.
    assert!(ok > 0 && err > 0, "ok {ok}, err {err}");
}

/// Truncations inside a grid body with the descriptor's offsets patched to the
/// cut (`cut_body`), so the parser gets past the offset check and must catch
/// the missing bytes in the metadata, transform, topology or buffers
/// themselves.
#[test]
fn truncated_grid_bodies_with_consistent_offsets_are_errors() {
    for comp in [Compression::ZipActiveMask, Compression::ActiveMask, Compression::Zip] {
        let mut g = Grid::new("density", 0.0f32, Transform::new(0.5, DVec3::ZERO));
        for (i, p) in [IVec3::new(-1, 2, 3), IVec3::new(9, 9, 9), IVec3::new(10, 9, 200)].into_iter().enumerate() {
            g.set(p, 0.5 + i as f32);
        }
        let full = write_vdb_bytes(&[GridRef::Float(&g)], &WriteOptions { compression: comp, ..Default::default() }).unwrap();
        for cut in body_cuts(&full) {
            let b = cut_body(&full, cut);
            assert!(read_timed(&b).is_err(), "{comp:?}: cut at {cut} of {} read successfully", full.len());
        }
    }
}

/// Leaves are decoded in parallel: the grids read back identically (leaf
/// order included) with one thread and with several, in every mode.
#[test]
fn parallel_decoding_is_thread_count_independent() {
    let (d, e) = test_grids();
    for comp in modes() {
        let bytes =
            write_vdb_bytes(&[GridRef::Float(&d), GridRef::Vec3(&e)], &WriteOptions { compression: comp, ..Default::default() }).unwrap();
        let read = |threads: usize| with_threads(threads, || read_vdb_bytes(&bytes).unwrap());
        let (one, many) = (read(1), read(3));
        let what = format!("{comp:?}");
        assert_same(one.float("density").unwrap(), many.float("density").unwrap(), &what);
        assert_same(one.vec3("emission").unwrap(), many.vec3("emission").unwrap(), &what);
        let origins =
            |f: &aurora::io::vdb::read::VdbFile| -> Vec<IVec3> { f.vec3("emission").unwrap().leaves().iter().map(|l| l.origin).collect() };
        assert_eq!(origins(&one), origins(&many), "{what}: leaf order");
        assert_same(&d, one.float("density").unwrap(), &what);
    }
}

/// A panic inside the oracle's contained region comes back as an error with
/// its message, on this thread and on concurrent ones, and the silencing
/// flag is reset afterwards.
#[test]
fn vdbrs_panics_are_contained() {
    use crate::common::vdbrs::{catch_silently, silenced};
    assert_eq!(catch_silently(|| 7), Ok(7));
    assert_eq!(catch_silently(|| -> i32 { panic!("boom {}", 1) }), Err("boom 1".to_string()));
    let handles: Vec<_> = (0..4).map(|i| std::thread::spawn(move || catch_silently(move || -> u8 { panic!("thread {i}") }))).collect();
    for (i, h) in handles.into_iter().enumerate() {
        assert_eq!(h.join().unwrap(), Err(format!("thread {i}")));
    }
    assert!(!silenced());
}

/// vdb-rs's descriptor keys are the name's bytes as chars.
#[test]
fn vdbrs_keys_are_latin1() {
    use crate::common::vdbrs::vdbrs_key;
    assert_eq!(vdbrs_key(b"density"), "density");
    assert_eq!(vdbrs_key("dé".as_bytes()), "d\u{c3}\u{a9}");
}
