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
//! path (`crate::app::vdb_for_render::read_render_medium`, over [`super::records`])
//! accept and refuse the same files. Both
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
//! [`read_vdb_bytes_with`] hands the plain `float` grids a second decoder
//! accepts to that decoder instead of ours ([`ExternalFloatDecoder`]): the
//! tests plug in the vdb-rs crate there as an independent oracle for our
//! decoder (`tests/common/vdbrs.rs`; vdb-rs is a dev-dependency only, so
//! the product never builds it). It runs only on files our validation
//! accepted and gets the located grids' names; its leaves replace ours.
//!
//! Every grid comes back with its inactive voxels at the background value
//! (the [`Grid`] invariant). The magic is always checked here, whichever
//! decoder reads the values.

use super::parse::{self, AnyTree, GridHeader, ParseError, ParsedFile, Tree, ValueKind};
use crate::grid::{Grid, Leaf, Transform, VoxelValue, LEAF_DIM};
use glam::{DVec3, IVec3};
use std::collections::HashSet;
use std::path::{Path, PathBuf};

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
    /// A second decoder ([`ExternalFloatDecoder`]) failed on a file our
    /// validation accepted.
    #[error("`{file}`: grid `{grid}`: the external decoder could not read it: {message}")]
    External { file: String, grid: String, message: String },
    /// Tiles would densify into too many voxels.
    #[error("`{file}`: grid `{grid}`: active tiles cover {voxels} voxels, more than the {limit} this reader densifies into leaves")]
    TooManyTileVoxels { file: String, grid: String, voxels: u128, limit: u128 },
    /// Tiles would densify into too many voxels in the file's grids
    /// together, each grid's under the limit.
    #[error("`{file}`: the active tiles of its {grids} grids cover {voxels} voxels together, more than the {limit} this reader densifies into leaves")]
    TooManyFileTileVoxels { file: String, grids: usize, voxels: u128, limit: u128 },
}

impl VdbReadError {
    /// The user's input: the file given to read (exit status 2), but for
    /// one that changed size while it was read, an I/O failure (exit status
    /// 1: `crate::util::input_file::is_input_io`).
    pub fn is_input(&self) -> bool {
        match self {
            VdbReadError::Io { source, .. } => crate::util::input_file::is_input_io(source),
            _ => true,
        }
    }
}

/// Which decoder produced a grid.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Decoder {
    /// An [`ExternalFloatDecoder`] (the tests' oracle).
    External,
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
    let bytes = super::records::FileBytes::open(path).map_err(|source| VdbReadError::Io { path: path.to_path_buf(), source })?;
    read_vdb_named(bytes.bytes(), &path.display().to_string(), None, false)
}

/// [`read_vdb`] for the renderer: leaves whose active voxels are all 0 are
/// dropped while decoding (every record is still decoded and validated).
/// On a grid with background 0 (the only kind the renderer accepts) an
/// active 0 samples exactly as an inactive voxel, so the rendered field is
/// the same; the default bake's shell of zero voxels for Cycles (a third of
/// its leaves) then costs no memory.
pub fn read_vdb_for_render(path: &Path) -> Result<VdbFile, VdbReadError> {
    let bytes = super::records::FileBytes::open(path).map_err(|source| VdbReadError::Io { path: path.to_path_buf(), source })?;
    read_vdb_named(bytes.bytes(), &path.display().to_string(), None, true)
}

/// Reads a VDB file held in memory.
pub fn read_vdb_bytes(bytes: &[u8]) -> Result<VdbFile, VdbReadError> {
    read_vdb_named(bytes, "<memory>", None, false)
}

/// [`read_vdb_for_render`] of a file held in memory.
pub fn read_vdb_bytes_for_render(bytes: &[u8]) -> Result<VdbFile, VdbReadError> {
    read_vdb_named(bytes, "<memory>", None, true)
}

/// One grid's leaves (mask and values) and transform, as a second decoder
/// read them.
pub type FloatLeaves = (Vec<Leaf<f32>>, Transform);

/// A second decoder's answer for the named grids: their leaves in the order
/// asked, or the grid it failed on and why.
pub type ExternalDecode = Result<Vec<FloatLeaves>, (String, String)>;

/// Grids to decode: each one's display name and its descriptor name's bytes.
pub type GridNames = [(String, Vec<u8>)];

/// A second decoder for plain `float` grids, for tests that check ours
/// against an independent one.
pub struct ExternalFloatDecoder<'a> {
    /// Whether it reads this grid (the others are decoded by ours). Grids
    /// with active tiles are always ours.
    pub reads: &'a dyn Fn(&GridHeader) -> bool,
    /// Decodes the named grids (display name, descriptor name bytes) of the
    /// file's bytes, in the order given; an error names the grid and says why.
    pub decode: &'a dyn Fn(&[u8], &GridNames) -> ExternalDecode,
}

/// [`read_vdb_bytes`] with the plain float grids `external` reads decoded
/// by it (module docs): how the tests run an oracle for our decoder.
pub fn read_vdb_bytes_with(bytes: &[u8], external: &ExternalFloatDecoder) -> Result<VdbFile, VdbReadError> {
    read_vdb_named(bytes, "<memory>", Some(external), false)
}

fn read_vdb_named(bytes: &[u8], file: &str, external: Option<&ExternalFloatDecoder>, drop_zero: bool) -> Result<VdbFile, VdbReadError> {
    let invalid = |source: ParseError| VdbReadError::Invalid { file: file.to_string(), source };
    let external_reads = |gh: &GridHeader| external.is_some_and(|x| gh.kind == Some(ValueKind::Float) && (x.reads)(gh));
    let native = if drop_zero { parse::Decode::NonZero } else { parse::Decode::All };
    // 1. Validate everything; decode natively what the external decoder does not read.
    let mut parsed = parse::parse_file_with(bytes, &|gh| if external_reads(gh) { parse::Decode::Skip } else { native }).map_err(invalid)?;
    // Grids with active tiles go native too (a second decoder may drop root tiles).
    let retry: HashSet<Vec<u8>> = parsed
        .grids
        .iter()
        .filter(|g| external_reads(&g.header) && tree_tile_count(g.tree.as_ref()) > 0)
        .map(|g| g.header.unique_name_raw.clone())
        .collect();
    if !retry.is_empty() {
        parsed = parse::parse_file_with(bytes, &|gh| {
            if !external_reads(gh) || retry.contains(&gh.unique_name_raw) {
                native
            } else {
                parse::Decode::Skip
            }
        })
        .map_err(invalid)?;
    }
    let use_external = |gh: &GridHeader| external_reads(gh) && !retry.contains(&gh.unique_name_raw);
    // 2. The external decoder for the plain float grids it reads.
    let external_names: Vec<(String, Vec<u8>)> = parsed
        .grids
        .iter()
        .filter(|g| use_external(&g.header))
        .map(|g| (g.header.unique_name.clone(), g.header.unique_name_raw.clone()))
        .collect();
    let mut from_external = match external {
        Some(x) if !external_names.is_empty() => (x.decode)(bytes, &external_names)
            .map_err(|(grid, message)| VdbReadError::External { file: file.into(), grid, message })?
            .into_iter(),
        _ => Vec::new().into_iter(),
    };
    // 3. Assemble in file order, the tiles' voxels of all grids within the
    // limit together first (each grid's is checked as it is assembled).
    let tiled: Vec<u128> = parsed.grids.iter().filter_map(|g| g.tree.as_ref()).map(|t| t.tile_voxels()).collect();
    if tiled.iter().all(|&v| v <= MAX_TILE_VOXELS) {
        check_file_tile_voxels(tiled.iter().sum(), tiled.len(), file)?;
    }
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
        let decoder = match (&pg.tree, use_external(&gh)) {
            (None, _) => Decoder::Skipped,
            (Some(_), true) => Decoder::External,
            (Some(_), false) => Decoder::Native,
        };
        let transform = gh.transform.unwrap_or(Transform::new(1.0, DVec3::ZERO));
        match (pg.tree, decoder) {
            (Some(AnyTree::Float(tree)), Decoder::External) => {
                let Some((leaves, external_transform)) = from_external.next() else {
                    return Err(VdbReadError::External {
                        file: file.into(),
                        grid: name,
                        message: "returned fewer grids than asked for".into(),
                    });
                };
                let mut g = Grid::new(name.clone(), tree.background, external_transform);
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

/// Refuses a file whose grids' active tiles (`voxels`, over `grids` grids)
/// would densify into more than [`MAX_TILE_VOXELS`] voxels together: the
/// limit holds for the file as for each grid, so that many grids each just
/// under it cannot add up to more memory than one grid may take.
pub(crate) fn check_file_tile_voxels(voxels: u128, grids: usize, file: &str) -> Result<(), VdbReadError> {
    if voxels > MAX_TILE_VOXELS {
        return Err(VdbReadError::TooManyFileTileVoxels { file: file.into(), grids, voxels, limit: MAX_TILE_VOXELS });
    }
    Ok(())
}

/// Refuses a tree whose active tiles would densify into more than
/// [`MAX_TILE_VOXELS`] voxels (both reading paths, whether or not they
/// densify that grid).
pub(crate) fn check_tile_voxels(voxels: u128, name: &str, file: &str) -> Result<(), VdbReadError> {
    if voxels > MAX_TILE_VOXELS {
        return Err(VdbReadError::TooManyTileVoxels { file: file.into(), grid: name.into(), voxels, limit: MAX_TILE_VOXELS });
    }
    Ok(())
}

/// Decodes every `float` grid of a file with our parser alone: what the
/// tests compare a second decoder against.
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

    /// The renderer's read drops exactly the leaves whose active voxels are
    /// all 0 (float and vec3, every compression) and keeps the others
    /// bit for bit; a negative value is never dropped (validation sees it).
    #[test]
    fn render_read_drops_only_zero_leaves() {
        use crate::io::vdb::write::{write_vdb_bytes, GridRef, WriteOptions};
        use crate::scene::Compression;
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
            let all = read_vdb_named(&bytes, "t", None, false).unwrap();
            let some = read_vdb_named(&bytes, "t", None, true).unwrap();
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
}
