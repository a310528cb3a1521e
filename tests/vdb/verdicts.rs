//! One definition of a valid VDB: the renderer's two ways of opening a
//! file give every damaged file of `common::damaged` the same verdict.
//!
//! - the grid path: `read_vdb_for_render`, then `render_grids` and
//!   `Medium::new` (what `aurora render --vdb` does where the records path
//!   hands over, and what every other reader of grids starts from);
//! - the records path: `read_render_medium` (the file's leaf records
//!   located, the chosen grids decoded straight into the medium, the other
//!   grids' records checked and dropped).
//!
//! Both refuse a file, or both read it into the same medium, field for
//! field (equal to `Medium::new` of the grids `read_vdb` reads). The grid
//! reader's verdict with and without its zero-leaf shortcut agrees too.

use crate::common::damaged::{damaged_files, four_grids, grids_of, with_root_tiles, Damaged, Expect};
use crate::common::{aurora, ok, scratch, stderr};
use aurora::app::vdb_for_render::{read_render_medium, read_render_medium_bytes, render_grids, RenderMedium, RenderReadError};
use aurora::io::vdb::read::{read_vdb, read_vdb_bytes, read_vdb_bytes_for_render, read_vdb_for_render, VdbFile, VdbReadError};
use aurora::render::medium::Medium;
use std::path::Path;

/// The grid path's medium, or its error's text.
fn grid_path(file: Result<VdbFile, VdbReadError>) -> Result<Medium, String> {
    let file = file.map_err(|e| e.to_string())?;
    let (d, e) = render_grids(file).map_err(|e| e.to_string())?;
    Medium::new(d.as_ref(), e.as_ref(), 1.0, 1.0).map_err(|e| e.to_string())
}

/// The records path's medium, `None` where it hands the file to the grid
/// path, or its error's text.
fn records_path(r: Result<Option<RenderMedium>, RenderReadError>) -> Result<Option<Medium>, String> {
    r.map(|m| m.map(|m| m.medium)).map_err(|e| e.to_string())
}

/// How a file went.
#[derive(Debug, PartialEq, Eq)]
enum Outcome {
    /// Both refused.
    Refused,
    /// Both read it, the records path itself.
    Read,
    /// The records path handed it to the grid path (which read or refused it).
    HandedOver,
}

/// The verdicts of one file compared: `Err` describes a disagreement.
fn compare(
    d: &Damaged,
    grid: &Result<Medium, String>,
    all_leaves: &Result<Medium, String>,
    records: &Result<Option<Medium>, String>,
) -> Result<Outcome, String> {
    let name = &d.name;
    if grid.is_ok() != all_leaves.is_ok() {
        return Err(format!("{name}: the grid reader with and without dropping zero leaves: {grid:?} vs {all_leaves:?}"));
    }
    let outcome = match (records, grid) {
        (Ok(None), _) => Outcome::HandedOver,
        (Ok(Some(m)), Ok(_)) => {
            if Ok(m) != all_leaves.as_ref() {
                return Err(format!("{name}: both read it, into different media"));
            }
            Outcome::Read
        }
        (Err(_), Err(_)) => Outcome::Refused,
        (Ok(Some(_)), Err(e)) => return Err(format!("{name}: the records path read it, the grid path refused it: {e}")),
        (Err(e), Ok(_)) => return Err(format!("{name}: the grid path read it, the records path refused it: {e}")),
    };
    let refused = grid.is_err();
    match d.expect {
        Expect::Refused if !refused => return Err(format!("{name}: read, expected a refusal")),
        Expect::Read if refused => return Err(format!("{name}: refused, expected a read: {grid:?}")),
        _ => {}
    }
    if refused && !d.message.is_empty() {
        for (path, r) in [("grid", grid.as_ref().err()), ("records", records.as_ref().err())] {
            if let Some(e) = r {
                if !e.contains(d.message) {
                    return Err(format!("{name}: the {path} path's error lacks `{}`: {e}", d.message));
                }
            }
        }
    }
    Ok(outcome)
}

/// Every damaged file, in memory: the same verdict on both paths (all
/// disagreements listed at once). The structured damages again from a
/// file on disk (the records path maps it; the grid path reads it), with
/// the verdicts they had in memory.
#[test]
fn both_readers_give_every_damaged_file_the_same_verdict() {
    let files = damaged_files();
    let mut bad = Vec::new();
    let (mut read, mut refused, mut handed) = (0, 0, 0);
    let dir = scratch("vdb", "verdicts");
    let path = dir.join("case.vdb");
    let mut on_disk = 0;
    for d in &files {
        let grid = grid_path(read_vdb_bytes_for_render(&d.bytes));
        let all_leaves = grid_path(read_vdb_bytes(&d.bytes));
        let records = records_path(read_render_medium_bytes(&d.bytes, 1.0, 1.0));
        match compare(d, &grid, &all_leaves, &records) {
            Ok(Outcome::Read) => read += 1,
            Ok(Outcome::Refused) => refused += 1,
            Ok(Outcome::HandedOver) => handed += 1,
            Err(m) => {
                std::fs::write(dir.join(format!("disagree_{}.vdb", bad.len())), &d.bytes).unwrap();
                bad.push(m);
                continue;
            }
        }
        let structured = !["truncated", "cut at", "random"].iter().any(|k| d.name.contains(k));
        if structured {
            on_disk += 1;
            std::fs::write(&path, &d.bytes).unwrap();
            let g = grid_path(read_vdb_for_render(&path));
            let a = grid_path(read_vdb(&path));
            let r = records_path(read_render_medium(&path, 1.0, 1.0));
            if g.is_ok() != grid.is_ok() || r.as_ref().ok() != records.as_ref().ok() {
                bad.push(format!("{}: from a file, not as in memory: {g:?} / {r:?}", d.name));
            } else if let Err(m) = compare(d, &g, &a, &r) {
                bad.push(format!("from a file: {m}"));
            }
        }
    }
    eprintln!(
        "{} files ({on_disk} also from disk): {read} read by the records path, {refused} refused by both, \
         {handed} handed to the grid path",
        files.len()
    );
    assert!(bad.is_empty(), "{} disagreements (files in {}):\n{}", bad.len(), dir.display(), bad.join("\n"));
    // The list exercises both outcomes on the records path itself.
    assert!(read >= 50 && refused >= 500, "read {read}, refused {refused}");
    let count = |e: Expect| files.iter().filter(|d| d.expect == e).count();
    assert!(count(Expect::Read) >= 30 && count(Expect::Refused) >= 500, "the list lost its cases");
}

/// A damaged stream (its LZ4 or deflate payload zeroed) in any of the
/// four grids, used by the renderer or not, is refused by the grid reader
/// alone (`read_vdb`, no render checks) and by the records path, both
/// naming the file and the codec; duplicate leaf origins (an active root
/// tile on a root child) are refused by both naming the grid and the
/// origin.
#[test]
fn file_damage_is_refused_whichever_grid_it_is_in() {
    for (comp, what) in [(aurora::scene::Compression::ZipActiveMask, "zip"), (aurora::scene::Compression::BloscActiveMask, "Blosc")] {
        let base = four_grids(comp, false);
        for g in grids_of(&base) {
            // The records path decodes density and emission; it must check
            // temperature and velocity as the grid reader does.
            let (at, len) = g
                .spans
                .iter()
                .map(|s| {
                    let at = s.start + 1;
                    (at, i64::from_le_bytes(base[at..at + 8].try_into().unwrap()))
                })
                .max_by_key(|c| c.1)
                .unwrap();
            let mut b = base.clone();
            b[at + 8 + 24..at + 8 + len as usize].fill(0);
            let grid = read_vdb_bytes(&b).err().map(|e| e.to_string()).expect("the grid reader refuses it");
            let records = read_render_medium_bytes(&b, 1.0, 1.0).err().map(|e| e.to_string());
            let records = records.unwrap_or_else(|| panic!("{comp:?} {}: the records path read it ({grid})", g.name));
            for m in [&grid, &records] {
                assert!(m.contains(what) && m.contains("<memory>"), "{comp:?} {}: {m}", g.name);
            }
            // Duplicate leaf origins: named with the grid and the origin.
            let child = g.spans[0].origin & glam::IVec3::splat(!4095);
            let b = with_root_tiles(&base, &g.name, &[(child, true)]);
            let grid = read_vdb_bytes(&b).err().map(|e| e.to_string()).expect("refused");
            let records = read_render_medium_bytes(&b, 1.0, 1.0).err().map(|e| e.to_string()).expect("refused");
            for m in [&grid, &records] {
                let want = format!("grid `{}`: a root tile and a root child both at {child}: duplicate leaf origins", g.name);
                assert!(m.contains(&want), "{m}");
            }
        }
    }
}

/// `aurora render --vdb` refuses a file with a damaged stream in a grid it
/// does not render, and one with duplicate leaf origins: exit 2, the
/// grid named, no image.
#[test]
fn the_render_command_refuses_damage_in_any_grid() {
    let dir = scratch("vdb", "verdicts-cli");
    let scene = dir.join("s.toml");
    std::fs::write(
        &scene,
        "[camera]\nposition = [0, -40, 100]\nlook_at = [0, 0, 100]\n[render]\nwidth = 8\nheight = 8\nspp = 1\n[terrain]\nkind = \"none\"\n",
    )
    .unwrap();
    let base = four_grids(aurora::scene::Compression::ZipActiveMask, false);
    let temperature = grids_of(&base).into_iter().find(|g| g.name == "temperature").unwrap();
    let at =
        temperature.spans.iter().map(|s| s.start + 1).max_by_key(|&at| i64::from_le_bytes(base[at..at + 8].try_into().unwrap())).unwrap();
    let len = i64::from_le_bytes(base[at..at + 8].try_into().unwrap()) as usize;
    let mut checksum = base.clone();
    checksum[at + 8 + len - 1] ^= 1;
    let density = grids_of(&base).into_iter().find(|g| g.name == "density").unwrap();
    let child = density.spans[0].origin & glam::IVec3::splat(!4095);
    let duplicate = with_root_tiles(&base, "density", &[(child, false)]);
    for (name, bytes, want) in [
        ("checksum.vdb", checksum, vec!["temperature".to_string(), "zip chunk".into()]),
        ("duplicate.vdb", duplicate, vec!["density".into(), "duplicate leaf origins".into(), child.to_string()]),
    ] {
        let vdb = dir.join(name);
        std::fs::write(&vdb, &bytes).unwrap();
        let img = dir.join("out.exr");
        let _ = std::fs::remove_file(&img);
        let args = ["render", scene.to_str().unwrap(), "--vdb", vdb.to_str().unwrap(), "--out", img.to_str().unwrap(), "-q"];
        let o = aurora(&args);
        let m = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{name}: {m}");
        for w in want {
            assert!(m.contains(&w), "{name}: `{w}` missing: {m}");
        }
        assert!(!img.exists(), "{name}: no image");
        assert_eq!(std::fs::read(&vdb).unwrap(), bytes, "{name}: the input is left untouched");
    }
    // The undamaged file renders.
    let vdb = dir.join("intact.vdb");
    std::fs::write(&vdb, &base).unwrap();
    let img = dir.join("out.exr");
    ok(&aurora(&["render", scene.to_str().unwrap(), "--vdb", vdb.to_str().unwrap(), "--out", img.to_str().unwrap(), "-q"]));
    assert!(Path::new(&img).exists());
}
