//! VDB reader: any OpenVDB file (versions 222 to 225) with `float` or
//! `vec3s` grids, ours or another tool's, into [`Grid<f32>`] /
//! [`Grid<[f32; 3]>`].
//!
//! Two steps:
//! 1. **Validation** by our bounds-checked parser ([`super::parse`]): header,
//!    magic, version, metadata and string lengths, descriptor offsets within
//!    the file, grid types, transform, every node mask, count and chunk
//!    length, Blosc headers.
//! 2. **Decoding** by the same parser: the leaf records are located in one
//!    serial pass, then decoded in parallel, each straight into its leaf
//!    (decompressed into a per-thread scratch buffer, or read from the file's
//!    bytes when stored raw): no intermediate copies. Active tiles are
//!    densified into leaves; vec3s, half floats and every transform map of
//!    `parse` are read.
//!
//! One definition of a valid file: this reader and the renderer's records
//! path ([`read_render_medium`]) accept and refuse the same files. Both
//! rest on the same parse (which also refuses repeated root origins, the
//! only way two leaves could share an origin), apply [`MAX_TILE_VOXELS`]
//! to every grid, and decompress every record of every grid once: here
//! while decoding; on the records path, the chosen grids' records while
//! the medium is built and the other grids' by `parse::check_located`
//! (decompressed into a per-thread scratch buffer and dropped: a ZIP
//! checksum or an LZ4 payload is checked only by running the decompressor;
//! a header and size check would pass damaged payloads the grid reader
//! refuses). That costs the records path nothing on aurora's bakes (both
//! grids are used) and, on a file with other grids, one parallel
//! decompression of their records in its open time, less than the grid
//! reader spends decoding them (no values are scattered or kept).
//!
//! [`read_vdb_bytes_with_vdbrs`] reads the plain `float` grids (no half
//! floats, no active tiles, one of its three transform maps) with the vdb-rs
//! crate instead: it is kept as the tests' independent oracle for our decoder. vdb-rs runs inside
//! `std::panic::catch_unwind` with the panic message silenced (it still has
//! `unwrap`s, `assert`s and indexing on input), and only on files our
//! validation accepted, so it never sees a length that could make it
//! allocate without bound. It gets vec3s trees (every root background and
//! tile value read as 4 bytes), half grids and root tiles wrong, and panics on
//! `ScaleMap`, `TranslationMap` and `AffineMap`.
//!
//! Every grid comes back with its inactive voxels at the background value
//! (the [`Grid`] invariant). Note vdb-rs's magic-number check is inverted in
//! effect (it rejects only the byte-swapped magic and accepts anything else),
//! so the magic is checked here.

use super::parse::{self, AnyTree, GridHeader, ParseError, ParsedFile, Tree, ValueKind};
use crate::grid::{Grid, Leaf, Transform, VoxelValue, LEAF_DIM};
use crate::{
    leaf_source::{LeafError, LeafSource, LeafValues, Scratch},
    render::medium::Medium,
};
use glam::{DVec3, IVec3};
use std::cell::Cell;
use std::collections::HashSet;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::sync::Once;

pub use super::parse::RawMeta;

/// Why a file could not be read. Every variant names the file.
#[derive(Debug, thiserror::Error)]
pub enum VdbReadError {
    #[error("reading `{path}`: {source}")]
    Io { path: PathBuf, source: std::io::Error },
    /// The bytes are not a valid VDB file we can read.
    #[error("`{file}` {source}")]
    Invalid {
        file: String,
        #[source]
        source: ParseError,
    },
    /// vdb-rs failed or panicked on a file our validation accepted.
    #[error("`{file}`: grid `{grid}`: vdb-rs could not read it: {message}")]
    VdbRs { file: String, grid: String, message: String },
    /// Tiles would densify into too many voxels.
    #[error("`{file}`: grid `{grid}`: active tiles cover {voxels} voxels, more than the {limit} this reader densifies into leaves")]
    TooManyTileVoxels { file: String, grid: String, voxels: u128, limit: u128 },
}

impl VdbReadError {
    /// Always the user's input: the file given to read (exit status 2).
    pub fn is_input(&self) -> bool {
        true
    }
}

/// Which decoder produced a grid.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Decoder {
    /// The vdb-rs crate.
    VdbRs,
    /// Our parser ([`super::parse`]).
    Native,
    /// Not read: a grid type other than `float` / `vec3s`.
    Skipped,
}

/// What the file says about one grid.
#[derive(Clone, Debug)]
pub struct GridInfo {
    /// Grid name (metadata `name`).
    pub name: String,
    /// Grid type as stored, e.g. `Tree_vec3s_5_4_3_HalfFloat`.
    pub type_name: String,
    /// `None` for skipped types.
    pub kind: Option<ValueKind>,
    /// Metadata `class`, e.g. `fog volume` (`unknown` if absent).
    pub class: String,
    /// Stored as half floats.
    pub half: bool,
    /// Compression flags (0x1 ZIP, 0x2 active mask, 0x4 Blosc).
    pub compression: u32,
    /// Transform map type, e.g. `UniformScaleTranslateMap` (empty if skipped).
    pub map: String,
    /// All grid metadata as stored.
    pub metadata: Vec<(String, RawMeta)>,
    pub decoder: Decoder,
}

/// A whole file read into grids.
#[derive(Clone, Debug)]
pub struct VdbFile {
    /// `float` grids in file order.
    pub float_grids: Vec<Grid<f32>>,
    /// `vec3s` grids in file order.
    pub vec3_grids: Vec<Grid<[f32; 3]>>,
    /// Every grid of the file in file order, including skipped ones.
    pub grids: Vec<GridInfo>,
    pub file_version: u32,
    pub library_version: (u32, u32),
    pub uuid: String,
    /// File-level metadata.
    pub metadata: Vec<(String, RawMeta)>,
}

impl VdbFile {
    pub fn float(&self, name: &str) -> Option<&Grid<f32>> {
        self.float_grids.iter().find(|g| g.name == name)
    }
    pub fn vec3(&self, name: &str) -> Option<&Grid<[f32; 3]>> {
        self.vec3_grids.iter().find(|g| g.name == name)
    }
    pub fn info(&self, name: &str) -> Option<&GridInfo> {
        self.grids.iter().find(|g| g.name == name)
    }
    /// The grid class (`fog volume`, `level set`, ...).
    pub fn class(&self, name: &str) -> Option<&str> {
        self.info(name).map(|g| g.class.as_str())
    }
}

/// Most voxels the reader creates from active tiles (2^25 = 32 Mi voxels,
/// 128 MiB as float leaves).
pub const MAX_TILE_VOXELS: u128 = 1 << 25;

/// Reads a VDB file.
pub fn read_vdb(path: &Path) -> Result<VdbFile, VdbReadError> {
    let bytes = crate::input_file::read(path).map_err(|e| VdbReadError::Io { path: path.to_path_buf(), source: e.into() })?;
    read_vdb_named(&bytes, &path.display().to_string(), false, false)
}

/// [`read_vdb`] for the renderer: leaves whose active voxels are all 0 are
/// dropped while decoding (every record is still decoded and validated).
/// On a grid with background 0 (the only kind the renderer accepts) an
/// active 0 samples exactly as an inactive voxel, so the rendered field is
/// the same; the default bake's shell of zero voxels for Cycles (a third of
/// its leaves) then costs no memory.
pub fn read_vdb_for_render(path: &Path) -> Result<VdbFile, VdbReadError> {
    let bytes = crate::input_file::read(path).map_err(|e| VdbReadError::Io { path: path.to_path_buf(), source: e.into() })?;
    read_vdb_named(&bytes, &path.display().to_string(), false, true)
}

/// Reads a VDB file held in memory.
pub fn read_vdb_bytes(bytes: &[u8]) -> Result<VdbFile, VdbReadError> {
    read_vdb_named(bytes, "<memory>", false, false)
}

/// [`read_vdb_for_render`] of a file held in memory.
pub fn read_vdb_bytes_for_render(bytes: &[u8]) -> Result<VdbFile, VdbReadError> {
    read_vdb_named(bytes, "<memory>", false, true)
}

/// [`read_vdb_bytes`] with the plain float grids decoded by vdb-rs (module
/// docs): the tests' oracle for our decoder.
pub fn read_vdb_bytes_with_vdbrs(bytes: &[u8]) -> Result<VdbFile, VdbReadError> {
    read_vdb_named(bytes, "<memory>", true, false)
}

/// Whether vdb-rs reads this grid correctly (see the module docs).
fn vdbrs_reads(gh: &GridHeader) -> bool {
    gh.kind == Some(ValueKind::Float)
        && !gh.half
        && matches!(gh.map_name.as_str(), "UniformScaleMap" | "UniformScaleTranslateMap" | "ScaleTranslateMap")
}

fn read_vdb_named(bytes: &[u8], file: &str, allow_vdbrs: bool, drop_zero: bool) -> Result<VdbFile, VdbReadError> {
    let invalid = |source: ParseError| VdbReadError::Invalid { file: file.to_string(), source };
    let vdbrs_reads = |gh: &GridHeader| allow_vdbrs && vdbrs_reads(gh);
    let native = if drop_zero { parse::Decode::NonZero } else { parse::Decode::All };
    // 1. Validate everything; decode natively what vdb-rs cannot read.
    let mut parsed = parse::parse_file_with(bytes, &|gh| if vdbrs_reads(gh) { parse::Decode::Skip } else { native }).map_err(invalid)?;
    // Grids with active tiles go native too (vdb-rs drops root tiles).
    let retry: HashSet<Vec<u8>> = parsed
        .grids
        .iter()
        .filter(|g| vdbrs_reads(&g.header) && tree_tile_count(g.tree.as_ref()) > 0)
        .map(|g| g.header.unique_name_raw.clone())
        .collect();
    if !retry.is_empty() {
        parsed = parse::parse_file_with(bytes, &|gh| {
            if !vdbrs_reads(gh) || retry.contains(&gh.unique_name_raw) {
                native
            } else {
                parse::Decode::Skip
            }
        })
        .map_err(invalid)?;
    }
    let use_vdbrs = |gh: &GridHeader| vdbrs_reads(gh) && !retry.contains(&gh.unique_name_raw);
    // 2. vdb-rs for the plain float grids.
    let vdbrs_names: Vec<(String, Vec<u8>)> = parsed
        .grids
        .iter()
        .filter(|g| use_vdbrs(&g.header))
        .map(|g| (g.header.unique_name.clone(), g.header.unique_name_raw.clone()))
        .collect();
    let mut from_vdbrs = read_with_vdbrs(bytes, &vdbrs_names, file)?.into_iter();
    // 3. Assemble in file order.
    let ParsedFile { header, grids: parsed_grids } = parsed;
    let mut out = VdbFile {
        float_grids: Vec::new(),
        vec3_grids: Vec::new(),
        grids: Vec::new(),
        file_version: header.file_version,
        library_version: (header.library_major, header.library_minor),
        uuid: header.uuid,
        metadata: header.metadata,
    };
    for pg in parsed_grids {
        let gh = pg.header;
        let name = gh.name();
        let decoder = match (&pg.tree, use_vdbrs(&gh)) {
            (None, _) => Decoder::Skipped,
            (Some(_), true) => Decoder::VdbRs,
            (Some(_), false) => Decoder::Native,
        };
        let transform = gh.transform.unwrap_or(Transform::new(1.0, DVec3::ZERO));
        match (pg.tree, decoder) {
            (Some(AnyTree::Float(tree)), Decoder::VdbRs) => {
                let Some((leaves, vdbrs_transform)) = from_vdbrs.next() else {
                    return Err(VdbReadError::VdbRs {
                        file: file.into(),
                        grid: name,
                        message: "returned fewer grids than asked for".into(),
                    });
                };
                let mut g = Grid::new(name.clone(), tree.background, vdbrs_transform);
                for leaf in leaves {
                    g.insert_leaf(normalise(leaf, tree.background));
                }
                g.sort_leaves();
                out.float_grids.push(g);
            }
            (Some(AnyTree::Float(tree)), _) => out.float_grids.push(assemble(tree, &name, transform, file)?),
            (Some(AnyTree::Vec3(tree)), _) => out.vec3_grids.push(assemble(tree, &name, transform, file)?),
            (None, _) => {}
        }
        out.grids.push(GridInfo {
            name,
            type_name: gh.type_name,
            kind: gh.kind,
            class: class_of(&gh.metadata),
            half: gh.half,
            compression: gh.compression,
            map: gh.map_name,
            metadata: gh.metadata,
            decoder,
        });
    }
    Ok(out)
}

fn class_of(meta: &[(String, RawMeta)]) -> String {
    match meta.iter().find(|(k, _)| k == "class") {
        Some((_, RawMeta::String(s))) => s.clone(),
        _ => "unknown".into(),
    }
}

fn tree_tile_count(t: Option<&AnyTree>) -> usize {
    match t {
        Some(AnyTree::Float(t)) => t.active_tile_count,
        Some(AnyTree::Vec3(t)) => t.active_tile_count,
        None => 0,
    }
}

/// Sets inactive voxels to the background (the [`Grid`] invariant).
fn normalise<T: VoxelValue>(mut leaf: Leaf<T>, background: T) -> Leaf<T> {
    for n in 0..leaf.values.len() {
        if !leaf.is_active(n) {
            leaf.values[n] = background;
        }
    }
    leaf
}

/// Builds a grid from a natively decoded tree, densifying active tiles.
fn assemble<T: VoxelValue>(tree: Tree<T>, name: &str, transform: Transform, file: &str) -> Result<Grid<T>, VdbReadError> {
    check_tile_voxels(tree.tile_voxels, name, file)?;
    let mut g = Grid::new(name, tree.background, transform);
    for leaf in tree.leaves {
        g.insert_leaf(normalise(leaf, tree.background));
    }
    for (origin, log2, value) in tree.tiles {
        let leaves_per_axis = (1i32 << log2) / LEAF_DIM;
        for i in 0..leaves_per_axis {
            for j in 0..leaves_per_axis {
                for k in 0..leaves_per_axis {
                    let mut leaf = Leaf::new(origin + IVec3::new(i, j, k) * LEAF_DIM, value);
                    leaf.mask = [u64::MAX; crate::grid::LEAF_MASK_WORDS];
                    g.insert_leaf(leaf);
                }
            }
        }
    }
    g.sort_leaves();
    Ok(g)
}

/// Refuses a tree whose active tiles would densify into more than
/// [`MAX_TILE_VOXELS`] voxels (both reading paths, whether or not they
/// densify that grid).
fn check_tile_voxels(voxels: u128, name: &str, file: &str) -> Result<(), VdbReadError> {
    if voxels > MAX_TILE_VOXELS {
        return Err(VdbReadError::TooManyTileVoxels { file: file.into(), grid: name.into(), voxels, limit: MAX_TILE_VOXELS });
    }
    Ok(())
}

thread_local! {
    /// Set while this thread runs vdb-rs: its panics are expected and caught.
    static SILENCE_PANICS: Cell<bool> = const { Cell::new(false) };
}
static INSTALL_HOOK: Once = Once::new();

/// Runs `f`, catching a panic. While it runs, panic messages from this thread
/// are not printed; other threads' panics still are (the hook is installed
/// once and consults a thread-local flag, so concurrent readers are safe).
fn catch_silently<R>(f: impl FnOnce() -> R) -> Result<R, String> {
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

/// vdb-rs keys grids by descriptor name read byte by byte as `char`s.
fn vdbrs_key(name: &[u8]) -> String {
    name.iter().map(|&b| char::from(b)).collect()
}

/// Leaves and transform of one grid as vdb-rs read it.
type VdbRsGrid = (Vec<Leaf<f32>>, Transform);

/// Reads the named float grids (display name, descriptor name bytes) with
/// vdb-rs: for each, its leaves (mask and values) and transform.
fn read_with_vdbrs(bytes: &[u8], names: &[(String, Vec<u8>)], file: &str) -> Result<Vec<VdbRsGrid>, VdbReadError> {
    if names.is_empty() {
        return Ok(Vec::new());
    }
    let fail = |grid: &str, message: String| VdbReadError::VdbRs { file: file.into(), grid: grid.into(), message };
    let result = catch_silently(|| -> Result<Vec<_>, (String, String)> {
        let mut reader = vdb_rs::VdbReader::new(std::io::Cursor::new(bytes)).map_err(|e| (String::new(), e.to_string()))?;
        let mut out = Vec::with_capacity(names.len());
        for (name, raw) in names {
            let g = reader.read_grid::<f32>(&vdbrs_key(raw)).map_err(|e| (name.clone(), e.to_string()))?;
            out.push(convert_vdbrs(&g).map_err(|m| (name.clone(), m))?);
        }
        Ok(out)
    });
    match result {
        Ok(Ok(v)) => Ok(v),
        Ok(Err((grid, message))) => Err(fail(&grid, message)),
        Err(panic) => {
            let all: Vec<&str> = names.iter().map(|(n, _)| n.as_str()).collect();
            Err(fail(&all.join(", "), format!("panicked: {panic}")))
        }
    }
}

/// Extracts leaves and transform from a vdb-rs grid. Leaf origins are derived
/// from the slot indices with our offset functions.
fn convert_vdbrs(g: &vdb_rs::Grid<f32>) -> Result<VdbRsGrid, String> {
    use super::layout::{internal16_child_origin, internal32_child_origin};
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
                if n3.buffer.len() != crate::grid::LEAF_NUM_VALUES || n3.value_mask.as_raw_slice().len() != crate::grid::LEAF_MASK_WORDS {
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

/// Decodes every `float` grid of a file with our parser alone (no vdb-rs):
/// the oracle the tests compare vdb-rs against.
pub fn read_native_float_grids(bytes: &[u8]) -> Result<Vec<Grid<f32>>, VdbReadError> {
    let invalid = |source: ParseError| VdbReadError::Invalid { file: "<memory>".into(), source };
    let parsed = parse::parse_file(bytes, &|_| true).map_err(invalid)?;
    let mut out = Vec::new();
    for pg in parsed.grids {
        if let Some(AnyTree::Float(tree)) = pg.tree {
            let tr = pg.header.transform.unwrap_or(Transform::new(1.0, DVec3::ZERO));
            out.push(assemble(tree, &pg.header.name(), tr, "<memory>")?);
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A panic inside the contained region comes back as an error with its
    /// message, on this thread and on concurrent ones.
    #[test]
    fn panics_are_contained() {
        assert_eq!(catch_silently(|| 7), Ok(7));
        assert_eq!(catch_silently(|| -> i32 { panic!("boom {}", 1) }), Err("boom 1".to_string()));
        let handles: Vec<_> = (0..4).map(|i| std::thread::spawn(move || catch_silently(move || -> u8 { panic!("thread {i}") }))).collect();
        for (i, h) in handles.into_iter().enumerate() {
            assert_eq!(h.join().unwrap(), Err(format!("thread {i}")));
        }
        // The flag is reset: a later panic outside is not silenced (not
        // observable here beyond the flag itself).
        assert!(!SILENCE_PANICS.with(|s| s.get()));
    }

    /// The renderer's read drops exactly the leaves whose active voxels are
    /// all 0 (float and vec3, every compression) and keeps the others
    /// bit for bit; a negative value is never dropped (validation sees it).
    #[test]
    fn render_read_drops_only_zero_leaves() {
        use crate::scene::Compression;
        use crate::vdb::write::{write_vdb_bytes, GridRef, WriteOptions};
        let tr = Transform::new(0.5, DVec3::new(1.0, 2.0, 3.0));
        let mut d = Grid::new("density", 0.0f32, tr);
        let mut e = Grid::new("emission", [0.0f32; 3], tr);
        for (ijk, v) in [((0, 0, 0), 1.5f32), ((3, 4, 5), 0.0), ((8, 0, 0), 0.0), ((9, 9, 9), 0.0), ((16, 0, 0), -0.0)] {
            let ijk = IVec3::new(ijk.0, ijk.1, ijk.2);
            d.set(ijk, v);
            e.set(ijk, [0.0, v, 0.0]);
        }
        d.set(IVec3::new(0, 8, 0), -2.0);
        e.set(IVec3::new(0, 8, 0), [0.0, 0.0, 1e-30]);
        for c in [Compression::None, Compression::Zip, Compression::ZipActiveMask, Compression::BloscActiveMask] {
            let opts = WriteOptions { compression: c, ..WriteOptions::default() };
            let bytes = write_vdb_bytes(&[GridRef::Float(&d), GridRef::Vec3(&e)], &opts).unwrap();
            let all = read_vdb_named(&bytes, "t", false, false).unwrap();
            let some = read_vdb_named(&bytes, "t", false, true).unwrap();
            let origins = |g: &Grid<f32>| g.leaves().iter().map(|l| l.origin).collect::<Vec<_>>();
            assert_eq!(origins(&all.float_grids[0]).len(), 5, "{c:?}");
            assert_eq!(origins(&some.float_grids[0]), vec![IVec3::ZERO, IVec3::new(0, 8, 0)], "{c:?}");
            for o in origins(&some.float_grids[0]) {
                assert_eq!(some.float_grids[0].leaf(o).unwrap(), all.float_grids[0].leaf(o).unwrap());
                assert_eq!(some.vec3_grids[0].leaf(o).unwrap(), all.vec3_grids[0].leaf(o).unwrap());
            }
            assert_eq!(some.vec3_grids[0].leaves().len(), 2, "{c:?}");
        }
    }

    /// Density and emission grids with dense, sparse, all-zero (a Cycles
    /// shell) and single-voxel leaves, negative coordinates, inactive
    /// voxels holding garbage-free background, on transform `tr` (emission
    /// on `tr_e`).
    fn medium_grids(tr: Transform, tr_e: Transform) -> (Grid<f32>, Grid<[f32; 3]>) {
        let mut d = Grid::new("density", 0.0f32, tr);
        let mut e = Grid::new("emission", [0.0f32; 3], tr_e);
        let mut h = 17u32;
        let mut next = || {
            h ^= h << 13;
            h ^= h >> 17;
            h ^= h << 5;
            h
        };
        for x in -12..20 {
            for y in -4..9 {
                for z in 0..11 {
                    let r = next();
                    if r % 3 == 0 {
                        continue;
                    }
                    let v = (r % 1000) as f32 * 1e-3;
                    d.set(IVec3::new(x, y, z), if r % 7 == 0 { 0.0 } else { v });
                    if r % 5 != 0 {
                        e.set(IVec3::new(x, y, z), [v, 0.5 * v, if r % 11 == 0 { 0.0 } else { 2.0 * v }]);
                    }
                }
            }
        }
        // A shell leaf of active zeros in both, one only in emission, a
        // lone voxel on a leaf's upper face.
        for ijk in [IVec3::new(40, 0, 0), IVec3::new(41, 3, 7)] {
            d.set(ijk, 0.0);
            e.set(ijk, [0.0; 3]);
        }
        e.set(IVec3::new(-40, 8, 0), [0.0; 3]);
        d.set(IVec3::new(7, 63, -9), 3.5);
        (d, e)
    }

    /// The medium built straight from a file's records equals the one built
    /// from the same file read into grids, field for field (block numbers
    /// included), for every compression, half emission, shared and
    /// separate transforms, any scales and the thread count; the scales set
    /// afterwards equal the scales built in.
    #[test]
    fn medium_from_file_equals_medium_from_grids() {
        use crate::render::medium::Medium;
        use crate::scene::Compression;
        use crate::vdb::write::{write_vdb_bytes, GridRef, WriteOptions};
        let tr = Transform::new(0.5, DVec3::new(1.0, -2.0, 3.0));
        for tr_e in [tr, Transform::new(0.25, DVec3::ZERO)] {
            let (d, e) = medium_grids(tr, tr_e);
            for c in [
                Compression::None,
                Compression::Zip,
                Compression::ActiveMask,
                Compression::ZipActiveMask,
                Compression::Blosc,
                Compression::BloscActiveMask,
            ] {
                for half in [false, true] {
                    let opts = WriteOptions {
                        compression: c,
                        half: if half { vec!["emission".into()] } else { Vec::new() },
                        ..WriteOptions::default()
                    };
                    let bytes = write_vdb_bytes(&[GridRef::Float(&d), GridRef::Vec3(&e)], &opts).unwrap();
                    let file = read_vdb_bytes(&bytes).unwrap();
                    let (gd, ge) = render_grids(file).unwrap();
                    for (ds, es) in [(1.0, 1.0), (2.5, 0.0), (0.0, 3.0)] {
                        let want = Medium::new(gd.as_ref(), ge.as_ref(), ds, es).unwrap();
                        for threads in [1, 2] {
                            let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
                            let got = pool.install(|| read_render_medium_bytes(&bytes, ds, es)).unwrap().unwrap().medium;
                            assert!(got == want, "{c:?} half {half} scales {ds} {es} threads {threads}");
                        }
                        let mut rescaled = Medium::new(gd.as_ref(), ge.as_ref(), 1.0, 1.0).unwrap();
                        rescaled.set_scales(ds, es).unwrap();
                        assert!(rescaled == want, "set_scales({ds}, {es})");
                    }
                    let m = Medium::new(gd.as_ref(), ge.as_ref(), 1.0, 1.0).unwrap();
                    assert_eq!(m.fields.len(), if tr_e == tr { 1 } else { 2 });
                }
            }
        }
    }

    /// A render of the medium read straight from the file is byte-identical
    /// to the render of the grids in memory.
    #[test]
    fn render_from_file_equals_render_in_memory() {
        use crate::render::{render, render_prepared, Prepared, RenderSettings, Volume};
        use crate::vdb::write::{write_vdb_bytes, GridRef, WriteOptions};
        let tr = Transform::new(0.5, DVec3::ZERO);
        let (d, e) = medium_grids(tr, tr);
        let bytes = write_vdb_bytes(&[GridRef::Float(&d), GridRef::Vec3(&e)], &WriteOptions::default()).unwrap();
        let mut scene = crate::scene::Scene::default();
        scene.terrain.kind = crate::scene::TerrainKind::None;
        scene.render.width = 24;
        scene.render.height = 16;
        scene.render.spp = 4;
        scene.camera.position = [4.0, -30.0, 2.0];
        scene.camera.look_at = [4.0, 0.0, 2.0];
        scene.volume.emission_scale = 40.0;
        let settings = RenderSettings::from_scene(&scene);
        let volume = Volume { density: Some(&d), emission: Some(&e) };
        let want = render(&settings, &volume, &crate::progress::NoProgress).unwrap();
        let m = read_render_medium_bytes(&bytes, 1.0, 1.0).unwrap().unwrap().medium;
        let p = Prepared::with_medium(&settings, m.clone(), None).unwrap();
        let got = render_prepared(&p, &crate::progress::NoProgress).unwrap();
        let bits = |img: &crate::render::Image| img.pixels.iter().flat_map(|p| p.map(f32::to_bits)).collect::<Vec<_>>();
        assert!(bits(&want).iter().any(|&b| b != 0), "the camera sees the volume");
        assert_eq!(bits(&got), bits(&want));
        // With a terrain lit by the volume: the emission sampler built from
        // the medium equals the one built from the grid.
        let mut lit = settings.clone();
        lit.terrain.kind = crate::scene::TerrainKind::Plane;
        lit.terrain.height = -1.0;
        let want = render(&lit, &volume, &crate::progress::NoProgress).unwrap();
        let p = Prepared::with_medium(&lit, m, None).unwrap();
        assert!(p.sampler().is_some(), "the terrain's sampler is exercised");
        assert_eq!(bits(&render_prepared(&p, &crate::progress::NoProgress).unwrap()), bits(&want));
        assert!(want.stats.shadow_samples > 0, "shadow rays were traced");
    }

    /// Bad files give typed errors, never a panic: every 7th byte of a
    /// small file's last two thirds damaged in turn, a truncated file,
    /// negative voxels (named with their coordinates; the writer refuses
    /// NaN, `render_read_drops_only_zero_leaves` covers the rest).
    #[test]
    fn bad_files_give_errors_on_the_medium_path() {
        use crate::vdb::write::{write_vdb_bytes, GridRef, WriteOptions};
        let tr = Transform::new(0.5, DVec3::ZERO);
        let mut d = Grid::new("density", 0.0f32, tr);
        let mut e = Grid::new("emission", [0.0f32; 3], tr);
        for i in 0..40 {
            d.set(IVec3::new(i, i % 5, 2 * i), 1.0 + i as f32);
            e.set(IVec3::new(i, 1, 0), [i as f32, 0.0, 1.0]);
        }
        let bytes = write_vdb_bytes(&[GridRef::Float(&d), GridRef::Vec3(&e)], &WriteOptions::default()).unwrap();
        for cut in [0, 8, bytes.len() / 2, bytes.len() - 1] {
            assert!(read_render_medium_bytes(&bytes[..cut], 1.0, 1.0).is_err(), "cut at {cut}");
        }
        let start = bytes.len() / 3;
        for at in (start..bytes.len()).step_by(7) {
            for flip in [0x01u8, 0x80, 0xff] {
                let mut b = bytes.clone();
                b[at] ^= flip;
                // Either an error or a medium (a flipped float bit can be a
                // valid value): never a panic.
                let _ = read_render_medium_bytes(&b, 1.0, 1.0);
            }
        }
        for (v, want) in [(-1.0f32, "-1.0"), (-1e-30, "-1e-30")] {
            let mut bad = d.clone();
            bad.set(IVec3::new(3, 4, 5), v);
            let bytes = write_vdb_bytes(&[GridRef::Float(&bad), GridRef::Vec3(&e)], &WriteOptions::default()).unwrap();
            let err = read_render_medium_bytes(&bytes, 1.0, 1.0).err().expect("refused").to_string();
            assert!(err.contains("[3, 4, 5]") && err.contains(want) && err.contains("density"), "{err}");
        }
    }

    /// vdb-rs's descriptor keys are the name's bytes as chars.
    #[test]
    fn vdbrs_keys_are_latin1() {
        assert_eq!(vdbrs_key(b"density"), "density");
        assert_eq!(vdbrs_key("dé".as_bytes()), "d\u{c3}\u{a9}");
    }
}

/// Why a VDB cannot be rendered (the renderer's grid choice,
/// [`crate::render::grids`]).
pub use crate::render::grids::RenderGridsError;

/// The grids a renderer needs from a file: the file's grids listed for the
/// renderer's grid choice ([`crate::render::grids::choose`]: a float
/// `density` grid, an `emission` grid, vec3 or float counted as grey; either
/// may be absent, not both).
pub fn render_grids(file: VdbFile) -> Result<(Option<Grid<f32>>, Option<Grid<[f32; 3]>>), RenderGridsError> {
    use crate::render::grids::{choose, Listed};
    let listing: Vec<Listed<'_>> =
        file.grids.iter().map(|g| Listed { name: &g.name, type_name: &g.type_name, kind: grid_type(g.kind) }).collect();
    choose(&listing, file.float_grids, file.vec3_grids)
}

/// The renderer's name for a grid's value type, as listed for
/// [`crate::render::grids`] (both the grid and the records path).
fn grid_type(kind: Option<ValueKind>) -> crate::render::grids::GridType {
    use crate::render::grids::GridType;
    match kind {
        Some(ValueKind::Float) => GridType::Float,
        Some(ValueKind::Vec3) => GridType::Vec3,
        None => GridType::Other,
    }
}

/// Why a VDB file's medium could not be built: the grid choice
/// ([`crate::render::grids`]) or the renderer's checks on the values.
#[derive(Debug, thiserror::Error)]
pub enum RenderReadError {
    #[error(transparent)]
    Read(#[from] VdbReadError),
    #[error("{file}: {source}")]
    Grids { file: String, source: RenderGridsError },
    #[error("{file}: {source}")]
    Render { file: String, source: crate::render::RenderError },
}

impl RenderReadError {
    /// True when the file, or a grid the renderer refuses, is at fault (exit status 2).
    pub fn is_input(&self) -> bool {
        match self {
            RenderReadError::Read(e) => e.is_input(),
            RenderReadError::Grids { source, .. } => source.is_input(),
            RenderReadError::Render { source, .. } => source.is_input(),
        }
    }
}

/// The renderer's medium read straight from a VDB file, and the split of
/// the time it took.
pub struct RenderMedium {
    pub medium: crate::render::medium::Medium,
    /// Reading the file and validating every record (its leaves located).
    pub open_seconds: f64,
    /// Decoding the records into the medium (`Medium::from_sources`).
    pub build_seconds: f64,
}

/// One grid of a file as a [`LeafSource`]: its leaves located by a
/// [`parse::Decode::Locate`] parse, each record decoded when the medium's
/// builder asks for it, into the builder's per-thread scratch.
struct FileLeaves<'a, T> {
    name: String,
    transform: Transform,
    tree: &'a Tree<T>,
    data: &'a [u8],
}

macro_rules! file_leaves {
    ($t:ty) => {
        impl LeafSource for FileLeaves<'_, $t> {
            fn name(&self) -> &str {
                &self.name
            }
            fn transform(&self) -> Transform {
                self.transform
            }
            fn channels(&self) -> usize {
                <$t as VoxelValue>::COMPONENTS
            }
            fn background(&self) -> [f32; 3] {
                self.tree.background.components()
            }
            fn leaf_count(&self) -> usize {
                self.tree.spans.len()
            }
            fn origin(&self, i: usize) -> IVec3 {
                self.tree.spans[i].origin
            }
            fn mask(&self, i: usize) -> &[u64; crate::grid::LEAF_MASK_WORDS] {
                &self.tree.spans[i].mask
            }
            fn values<'s>(&'s self, i: usize, scratch: &'s mut Scratch) -> Result<LeafValues<'s>, LeafError> {
                let span = &self.tree.spans[i];
                let mut c = super::cursor::Cursor::new(self.data);
                c.seek(span.start as u64)?;
                let slots = super::codec::read_stored_f32(
                    &mut c,
                    self.tree.format,
                    crate::grid::LEAF_NUM_VALUES,
                    &span.mask,
                    <$t as VoxelValue>::COMPONENTS,
                    &mut scratch.values,
                    &mut scratch.bytes,
                )?;
                Ok(match slots {
                    super::codec::StoredSlots::All => LeafValues::All(&scratch.values),
                    super::codec::StoredSlots::Active => LeafValues::Active(&scratch.values),
                })
            }
        }
    };
}
file_leaves!(f32);
file_leaves!([f32; 3]);

/// Reads a VDB file straight into the renderer's medium (the `render`
/// command's path): the file is parsed once, validating every record and
/// locating each leaf's, then [`Medium::from_sources`] decodes the records
/// in parallel, each into a per-thread buffer, checks them and copies them
/// into the medium's blocks: no [`Grid`] in between. The grids are the ones
/// [`render_grids`] would choose and the medium equals `Medium::new` of
/// those grids (read by [`read_vdb`]), field for field. The other grids'
/// records are checked, not kept (module docs), so this path refuses
/// exactly the files the grid path refuses.
///
/// `Ok(None)` where this path does not apply and the caller should read
/// grids instead ([`read_vdb_for_render`], [`render_grids`]): a float
/// `emission` grid (read as grey), active tiles in a chosen grid, or no
/// grid to render (the grid path reports it).
pub fn read_render_medium(path: &Path, density_scale: f64, emission_scale: f64) -> Result<Option<RenderMedium>, RenderReadError> {
    let start = std::time::Instant::now();
    let bytes = FileBytes::open(path).map_err(|source| VdbReadError::Io { path: path.to_path_buf(), source })?;
    render_medium_named(bytes.bytes(), &path.display().to_string(), start, density_scale, emission_scale)
}

/// A file's bytes: mapped into memory where the system allows (the pages
/// come straight from the page cache: no copy of a 190 MB file, a fault
/// per 64 KiB instead of per 4 KiB), else read.
///
/// The map is private and read-only. If another process truncates the
/// file while it is mapped, reading the lost pages raises SIGBUS, as with
/// any mapped file (OpenVDB maps its files the same way, with
/// `boost::interprocess`); aurora never writes a file in place (its
/// outputs are staged and renamed, `crate::atomic`), so its own writes
/// cannot do this to a file being read.
enum FileBytes {
    #[cfg(unix)]
    Mapped {
        ptr: *mut libc::c_void,
        len: usize,
    },
    Read(Vec<u8>),
}

impl FileBytes {
    fn open(path: &Path) -> std::io::Result<FileBytes> {
        // Only a regular file is mapped or read (`crate::input_file`).
        let file = crate::input_file::open(path)?;
        let len = file.metadata()?.len();
        #[cfg(unix)]
        if len > 0 && len <= isize::MAX as u64 {
            use std::os::fd::AsRawFd;
            let len = len as usize;
            // SAFETY: a fresh private read-only mapping of `len` bytes of an
            // open file; the result is checked against MAP_FAILED.
            let ptr = unsafe { libc::mmap(std::ptr::null_mut(), len, libc::PROT_READ, libc::MAP_PRIVATE, file.as_raw_fd(), 0) };
            if ptr != libc::MAP_FAILED {
                return Ok(FileBytes::Mapped { ptr, len });
            }
        }
        let mut bytes = Vec::with_capacity(len as usize);
        std::io::Read::read_to_end(&mut &file, &mut bytes)?;
        Ok(FileBytes::Read(bytes))
    }

    fn bytes(&self) -> &[u8] {
        match self {
            // SAFETY: the mapping is `len` readable bytes, alive until drop.
            #[cfg(unix)]
            FileBytes::Mapped { ptr, len } => unsafe { std::slice::from_raw_parts(ptr.cast::<u8>(), *len) },
            FileBytes::Read(b) => b,
        }
    }
}

impl Drop for FileBytes {
    fn drop(&mut self) {
        #[cfg(unix)]
        if let FileBytes::Mapped { ptr, len } = self {
            // SAFETY: unmaps exactly the mapping made in `open`, once.
            unsafe { libc::munmap(*ptr, *len) };
        }
    }
}

/// [`read_render_medium`] of a file held in memory.
pub fn read_render_medium_bytes(bytes: &[u8], density_scale: f64, emission_scale: f64) -> Result<Option<RenderMedium>, RenderReadError> {
    render_medium_named(bytes, "<memory>", std::time::Instant::now(), density_scale, emission_scale)
}

fn render_medium_named(
    bytes: &[u8],
    file: &str,
    start: std::time::Instant,
    density_scale: f64,
    emission_scale: f64,
) -> Result<Option<RenderMedium>, RenderReadError> {
    use crate::render::grids::{check_types, Listed};
    let file = file.to_string();
    let invalid = |source: ParseError| VdbReadError::Invalid { file: file.clone(), source };
    let parsed = parse::parse_file_with(bytes, &|gh| {
        if gh.kind.is_some() {
            parse::Decode::Locate
        } else {
            parse::Decode::Skip
        }
    })
    .map_err(invalid)?;
    let names: Vec<String> = parsed.grids.iter().map(|g| g.header.name()).collect();
    let listing: Vec<Listed<'_>> = parsed
        .grids
        .iter()
        .zip(&names)
        .map(|(g, name)| Listed { name, type_name: &g.header.type_name, kind: grid_type(g.header.kind) })
        .collect();
    check_types(&listing).map_err(|source| RenderReadError::Grids { file: file.clone(), source })?;
    let transform_of = |g: &parse::ParsedGrid| g.header.transform.unwrap_or(Transform::new(1.0, DVec3::ZERO));
    let mut density = None;
    let mut emission = None;
    let mut float_emission = false;
    let mut used = [None, None];
    for (i, (g, name)) in parsed.grids.iter().zip(&names).enumerate() {
        match (&g.tree, name.as_str()) {
            (Some(AnyTree::Float(t)), "density") if density.is_none() => {
                used[0] = Some(i);
                density = Some(FileLeaves { name: name.clone(), transform: transform_of(g), tree: t, data: bytes })
            }
            (Some(AnyTree::Vec3(t)), "emission") if emission.is_none() => {
                used[1] = Some(i);
                emission = Some(FileLeaves { name: name.clone(), transform: transform_of(g), tree: t, data: bytes })
            }
            (Some(AnyTree::Float(_)), "emission") => float_emission = true,
            _ => {}
        }
    }
    let tiles =
        density.as_ref().is_some_and(|d| d.tree.active_tile_count > 0) || emission.as_ref().is_some_and(|e| e.tree.active_tile_count > 0);
    if (emission.is_none() && float_emission) || (density.is_none() && emission.is_none()) || tiles {
        return Ok(None);
    }
    // What the grid reader refuses is refused here too: its tile limit on
    // every grid, and the records of the grids the medium does not use
    // checked as decoding them would (`parse::check_located`); the builder
    // checks the used grids' records as it decodes them.
    for (i, (g, name)) in parsed.grids.iter().zip(&names).enumerate() {
        let Some(tree) = &g.tree else { continue };
        check_tile_voxels(tree.tile_voxels(), name, &file)?;
        if !used.contains(&Some(i)) {
            tree.check_located(bytes, &g.header.unique_name).map_err(invalid)?;
        }
    }
    let open_seconds = start.elapsed().as_secs_f64();
    let build = std::time::Instant::now();
    let medium = Medium::from_sources(
        density.as_ref().map(|s| s as &dyn LeafSource),
        emission.as_ref().map(|s| s as &dyn LeafSource),
        density_scale,
        emission_scale,
    )
    .map_err(|source| RenderReadError::Render { file: file.clone(), source })?;
    Ok(Some(RenderMedium { medium, open_seconds, build_seconds: build.elapsed().as_secs_f64() }))
}
