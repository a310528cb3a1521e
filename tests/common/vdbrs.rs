//! The vdb-rs crate as an independent oracle for our VDB decoder, plugged
//! into `aurora::io::vdb::read::read_vdb_bytes_with` (vdb-rs is a dev-dependency:
//! the product never builds it).
//!
//! vdb-rs reads the plain `float` grids: no half floats, no active tiles
//! (it drops root tiles), one of its three transform maps. It gets vec3s
//! trees (every root background and tile value read as 4 bytes) and half
//! grids wrong and panics on `ScaleMap`, `TranslationMap` and `AffineMap`,
//! so those go to our decoder. It still has `unwrap`s, `assert`s and
//! indexing on input: it runs inside `std::panic::catch_unwind` with the
//! panic message silenced, and only on files our validation accepted, so it
//! never sees a length that could make it allocate without bound. Its
//! magic-number check is inverted in effect (it rejects only the
//! byte-swapped magic): our parser checks the magic first.

use aurora::grid::{Leaf, Transform, LEAF_MASK_WORDS, LEAF_NUM_VALUES};
use aurora::io::vdb::layout::{internal16_child_origin, internal32_child_origin};
use aurora::io::vdb::parse::{GridHeader, ValueKind};
use aurora::io::vdb::read::{read_vdb_bytes_with, ExternalDecode, ExternalFloatDecoder, FloatLeaves, GridNames, VdbFile, VdbReadError};
use glam::{DVec3, IVec3};
use std::cell::Cell;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::sync::Once;

/// A file read with its plain float grids decoded by vdb-rs.
pub fn read_vdb_bytes_with_vdbrs(bytes: &[u8]) -> Result<VdbFile, VdbReadError> {
    read_vdb_bytes_with(bytes, &ExternalFloatDecoder { reads: &vdbrs_reads, decode: &decode })
}

/// Whether vdb-rs reads this grid correctly (the module docs).
pub fn vdbrs_reads(gh: &GridHeader) -> bool {
    gh.kind == Some(ValueKind::Float)
        && !gh.half
        && matches!(gh.map_name.as_str(), "UniformScaleMap" | "UniformScaleTranslateMap" | "ScaleTranslateMap")
}

fn decode(bytes: &[u8], names: &GridNames) -> ExternalDecode {
    let result = catch_silently(|| -> Result<Vec<_>, (String, String)> {
        let mut reader = vdb_rs::VdbReader::new(std::io::Cursor::new(bytes)).map_err(|e| (String::new(), e.to_string()))?;
        let mut out = Vec::with_capacity(names.len());
        for (name, raw) in names {
            let g = reader.read_grid::<f32>(&vdbrs_key(raw)).map_err(|e| (name.clone(), e.to_string()))?;
            out.push(convert(&g).map_err(|m| (name.clone(), m))?);
        }
        Ok(out)
    });
    match result {
        Ok(r) => r,
        Err(panic) => {
            let all: Vec<&str> = names.iter().map(|(n, _)| n.as_str()).collect();
            Err((all.join(", "), format!("vdb-rs panicked: {panic}")))
        }
    }
}

/// vdb-rs keys grids by descriptor name read byte by byte as `char`s.
pub fn vdbrs_key(name: &[u8]) -> String {
    name.iter().map(|&b| char::from(b)).collect()
}

/// Leaves and transform of a vdb-rs grid. Leaf origins are derived from the
/// slot indices with our offset functions.
fn convert(g: &vdb_rs::Grid<f32>) -> Result<FloatLeaves, String> {
    let transform = match &g.transform {
        vdb_rs::Map::ScaleTranslateMap { translation: t, scale_values: s, .. } => Transform::new(s.x, DVec3::new(t.x, t.y, t.z)),
        vdb_rs::Map::UniformScaleMap { scale_values: s, .. } => Transform::new(s.x, DVec3::ZERO),
    };
    let mut leaves = Vec::new();
    for n5 in &g.tree.root_nodes {
        let o5 = IVec3::new(n5.origin.x, n5.origin.y, n5.origin.z);
        for i5 in n5.child_mask.iter_ones() {
            let n4 = n5.nodes.get(&(i5 as u32)).ok_or("missing Internal16 node")?;
            let o4 = internal32_child_origin(o5, i5);
            for i4 in n4.child_mask.iter_ones() {
                let n3 = n4.nodes.get(&(i4 as u32)).ok_or("missing leaf node")?;
                if n3.buffer.len() != LEAF_NUM_VALUES || n3.value_mask.as_raw_slice().len() != LEAF_MASK_WORDS {
                    return Err(format!("leaf buffer of {} values", n3.buffer.len()));
                }
                let mut leaf = Leaf::new(internal16_child_origin(o4, i4), 0.0f32);
                leaf.mask.copy_from_slice(n3.value_mask.as_raw_slice());
                leaf.values.copy_from_slice(&n3.buffer);
                leaves.push(leaf);
            }
        }
    }
    Ok((leaves, transform))
}

thread_local! {
    /// Set while this thread runs vdb-rs: its panics are expected and caught.
    static SILENCE_PANICS: Cell<bool> = const { Cell::new(false) };
}
static INSTALL_HOOK: Once = Once::new();

/// Runs `f`, catching a panic. While it runs, panic messages from this thread
/// are not printed; other threads' panics still are (the hook is installed
/// once and consults a thread-local flag, so concurrent readers are safe).
pub fn catch_silently<R>(f: impl FnOnce() -> R) -> Result<R, String> {
    INSTALL_HOOK.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if !SILENCE_PANICS.with(|s| s.get()) {
                previous(info);
            }
        }));
    });
    SILENCE_PANICS.with(|s| s.set(true));
    let r = catch_unwind(AssertUnwindSafe(f));
    SILENCE_PANICS.with(|s| s.set(false));
    r.map_err(|p| {
        p.downcast_ref::<String>().cloned().or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string())).unwrap_or_else(|| "panic".into())
    })
}

/// Whether this thread's panics are being silenced now.
pub fn silenced() -> bool {
    SILENCE_PANICS.with(|s| s.get())
}
