//! Bounds-checked parser of OpenVDB files (file versions 222 to 225), used
//! three ways by [`super::read`]:
//!
//! - *validation* (`decode = false`): walks every byte the way OpenVDB's
//!   `io::File` does (header, metadata, descriptors, transform, topology and
//!   buffers), checking every length, offset, count, mask, root origin
//!   (aligned, one entry per origin: two would give two leaves one origin)
//!   and Blosc header against the bytes that exist, and decompressing every
//!   ZIP and Blosc stream into a scratch buffer that is then dropped (a
//!   damaged ZIP payload or checksum, or LZ4 payload, shows only there).
//!   A file that passes cannot make a second decoder (the tests' vdb-rs)
//!   allocate from a garbage length or read past the end;
//! - *native decoding* (`decode = true`): the same walk, decoding values, for
//!   every grid the reader is not told to leave to a second decoder;
//! - *locating* ([`Decode::Locate`]): the validation walk, keeping each
//!   leaf's origin, mask and record offset, for a caller that decodes the
//!   records itself, in parallel, straight where it wants the values (the
//!   renderer's medium, `crate::app::vdb_for_render::read_render_medium`). The leaf
//!   records' streams are not decompressed here: the caller decodes them,
//!   or checks them with [`check_located`] (the same verdict as decoding).
//!
//! Every mode makes every check above on every grid of a type we read, so
//! a file gets the same verdict from each (with `Locate`, once the caller
//! has decoded or checked every located record); each leaf record's stream
//! is decompressed once, by whichever step reads it.
//!
//! Nothing here panics on input and every loop is bounded by bytes consumed:
//! descriptors only move forward (`gridPos >= descriptor end`,
//! `endPos >= blockPos >= gridPos`) and every count is checked against the
//! bytes left before it is used.

pub use super::cursor::{Cursor, ParseError};
use super::decode::{self, Destination, RecordFormat};
use super::layout::{self, INTERNAL16, INTERNAL32};
use crate::grid::{Leaf, Transform, VoxelValue, LEAF_MASK_WORDS, LEAF_NUM_VALUES};
use glam::{DVec3, IVec3};
use std::collections::HashSet;

/// One metadata value as stored (OpenVDB `TypedMetadata` type names).
#[derive(Clone, Debug, PartialEq)]
pub enum RawMeta {
    String(String),
    Bool(bool),
    Int32(i32),
    Int64(i64),
    Float(f32),
    Double(f64),
    Vec3i([i32; 3]),
    Vec3s([f32; 3]),
    Vec3d([f64; 3]),
    /// Any other type, kept as raw bytes (e.g. `__delayedload`).
    Other {
        type_name: String,
        bytes: Vec<u8>,
    },
}

/// MetaMap: `u32 count`, then `count` x {key, type name, `u32 size`, value}.
/// The size of a known type must match it (both OpenVDB and vdb-rs read known
/// types by their own size, so a mismatch would misalign everything after).
pub fn read_meta_map(cur: &mut Cursor) -> Result<Vec<(String, RawMeta)>, ParseError> {
    let at = cur.pos();
    let count = cur.u32()? as usize;
    // Each entry takes at least 12 bytes (three u32 lengths).
    if count > cur.remaining() / 12 {
        return Err(cur.err_at(at, format!("metadata count {count} cannot fit in the {} bytes left", cur.remaining())));
    }
    let mut out = Vec::with_capacity(count);
    for _ in 0..count {
        let key = cur.string()?;
        let type_name = cur.string()?;
        let size_at = cur.pos();
        let size = cur.u32()? as usize;
        let v = cur.bytes(size)?;
        let want = match type_name.as_str() {
            "bool" => Some(1),
            "int32" | "float" => Some(4),
            "int64" | "double" => Some(8),
            "vec3i" | "vec3s" => Some(12),
            "vec3d" => Some(24),
            _ => None,
        };
        if let Some(w) = want {
            if size != w {
                return Err(cur.err_at(size_at, format!("metadata `{key}` of type {type_name} has size {size}, expected {w}")));
            }
        }
        let f32_at = |i: usize| f32::from_le_bytes(v[4 * i..4 * i + 4].try_into().expect("4 bytes"));
        let i32_at = |i: usize| i32::from_le_bytes(v[4 * i..4 * i + 4].try_into().expect("4 bytes"));
        let f64_at = |i: usize| f64::from_le_bytes(v[8 * i..8 * i + 8].try_into().expect("8 bytes"));
        let value = match type_name.as_str() {
            "string" => RawMeta::String(String::from_utf8_lossy(v).into_owned()),
            "bool" => RawMeta::Bool(v[0] != 0),
            "int32" => RawMeta::Int32(i32_at(0)),
            "int64" => RawMeta::Int64(i64::from_le_bytes(v.try_into().expect("8 bytes"))),
            "float" => RawMeta::Float(f32_at(0)),
            "double" => RawMeta::Double(f64_at(0)),
            "vec3i" => RawMeta::Vec3i([i32_at(0), i32_at(1), i32_at(2)]),
            "vec3s" => RawMeta::Vec3s([f32_at(0), f32_at(1), f32_at(2)]),
            "vec3d" => RawMeta::Vec3d([f64_at(0), f64_at(1), f64_at(2)]),
            _ => RawMeta::Other { type_name: type_name.clone(), bytes: v.to_vec() },
        };
        out.push((key, value));
    }
    Ok(out)
}

/// The value type of a grid we read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ValueKind {
    /// `Tree_float_5_4_3`
    Float,
    /// `Tree_vec3s_5_4_3`
    Vec3,
}

/// File header (OpenVDB `Archive::readHeader`).
#[derive(Clone, Debug)]
pub struct Header {
    pub file_version: u32,
    pub library_major: u32,
    pub library_minor: u32,
    pub uuid: String,
    pub metadata: Vec<(String, RawMeta)>,
}

/// A grid's descriptor and everything before its tree.
#[derive(Clone, Debug)]
pub struct GridHeader {
    /// Name in the descriptor (unique in the file), lossily decoded as UTF-8.
    pub unique_name: String,
    /// The descriptor name's bytes as stored.
    pub unique_name_raw: Vec<u8>,
    /// Grid type as stored, e.g. `Tree_float_5_4_3_HalfFloat`.
    pub type_name: String,
    /// `None` for types aurora does not read (they are skipped).
    pub kind: Option<ValueKind>,
    pub instance_parent: String,
    pub grid_pos: u64,
    pub block_pos: u64,
    pub end_pos: u64,
    pub compression: u32,
    pub metadata: Vec<(String, RawMeta)>,
    /// Stored as half floats (decided by `is_saved_as_half_float`, as OpenVDB does).
    pub half: bool,
    /// Map type name, e.g. `UniformScaleTranslateMap`.
    pub map_name: String,
    /// `None` for skipped grids.
    pub transform: Option<Transform>,
}

impl GridHeader {
    /// The grid's name: metadata `name` (where OpenVDB takes it from), else
    /// the descriptor name without OpenVDB's `"\x1e" + N` uniquifying suffix.
    pub fn name(&self) -> String {
        match self.metadata.iter().find(|(k, _)| k == "name") {
            Some((_, RawMeta::String(s))) => s.clone(),
            _ => self.unique_name.split('\x1e').next().unwrap_or("").to_string(),
        }
    }
    /// Metadata `class` (e.g. `fog volume`), or `unknown`.
    pub fn class(&self) -> String {
        match self.metadata.iter().find(|(k, _)| k == "class") {
            Some((_, RawMeta::String(s))) => s.clone(),
            _ => "unknown".to_string(),
        }
    }
}

/// A parsed tree: leaves with their stored values (inactive values rebuilt as
/// OpenVDB does) and active tiles. Empty vectors when not decoding.
#[derive(Clone, Debug)]
pub struct Tree<T> {
    pub background: T,
    pub leaves: Vec<Leaf<T>>,
    /// Active tiles: (origin, log2 of the edge in voxels, value).
    pub tiles: Vec<(IVec3, u32, T)>,
    /// Number of leaves, counted even when not decoding.
    pub leaf_count: usize,
    /// Number of active tiles at any level, counted even when not decoding.
    pub active_tile_count: usize,
    /// Voxels the active tiles cover (what densifying them would create),
    /// counted even when not decoding.
    pub tile_voxels: u128,
    /// With [`Decode::Locate`]: every leaf's origin, mask and record, in
    /// file order (empty otherwise), for the caller to decode
    /// (`decode::read_stored_f32` at `start`).
    pub spans: Vec<LeafSpan>,
    /// How the records are stored.
    pub format: RecordFormat,
}

/// Where one leaf's value record lies in the file (its mask already read
/// from the topology and checked against the buffers' copy).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LeafSpan {
    pub origin: IVec3,
    pub mask: [u64; LEAF_MASK_WORDS],
    /// Byte offset of the value record (after the mask copy).
    pub start: usize,
}

/// A decoded grid tree of either value type.
#[derive(Clone, Debug)]
pub enum AnyTree {
    Float(Tree<f32>),
    Vec3(Tree<[f32; 3]>),
}

impl AnyTree {
    /// [`Tree::tile_voxels`].
    pub fn tile_voxels(&self) -> u128 {
        match self {
            AnyTree::Float(t) => t.tile_voxels,
            AnyTree::Vec3(t) => t.tile_voxels,
        }
    }
    /// [`check_located`] of this tree.
    pub fn check_located(&self, data: &[u8], name: &str) -> Result<(), ParseError> {
        match self {
            AnyTree::Float(t) => check_located(data, t, name),
            AnyTree::Vec3(t) => check_located(data, t, name),
        }
    }
}

/// One grid of the file: header and, for grids of a kind we read, its tree.
#[derive(Clone, Debug)]
pub struct ParsedGrid {
    pub header: GridHeader,
    /// `None` for skipped grid types.
    pub tree: Option<AnyTree>,
}

/// A whole parsed file.
#[derive(Clone, Debug)]
pub struct ParsedFile {
    pub header: Header,
    pub grids: Vec<ParsedGrid>,
}

/// Parses a whole file. `decode(grid)` says whether to decode that grid's
/// values (otherwise they are validated and skipped).
pub fn parse_file(bytes: &[u8], decode: &dyn Fn(&GridHeader) -> bool) -> Result<ParsedFile, ParseError> {
    parse_file_with(bytes, &|gh| if decode(gh) { Decode::All } else { Decode::Skip })
}

/// What to do with one grid's leaf values.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Decode {
    /// Validate and skip them.
    Skip,
    /// Decode every leaf.
    All,
    /// Decode every leaf, keep only those with a non-zero active value: for
    /// a reader to whom an active 0 is the same as an inactive voxel (the
    /// renderer, on a background-0 grid), such as the shell of zero voxels
    /// our bakes add for Cycles. Every record is still decoded and checked.
    NonZero,
    /// Validate every record and list where each leaf's lies
    /// ([`Tree::spans`]) without decoding: the caller decodes them where
    /// and when it wants the values.
    Locate,
}

/// The number of grids after the file header, refused where that many
/// descriptors (each at least 3 string lengths and 3 offsets, 36 bytes)
/// cannot fit in what is left.
fn read_grid_count(cur: &mut Cursor) -> Result<usize, ParseError> {
    let at = cur.pos();
    let grid_count = cur.i32()?;
    if grid_count < 0 || grid_count as usize > cur.remaining() / 36 {
        return Err(cur.err_at(at, format!("grid count {grid_count} cannot fit in the {} bytes left", cur.remaining())));
    }
    Ok(grid_count as usize)
}

/// [`parse_file`] with a per-grid [`Decode`] choice.
pub fn parse_file_with(bytes: &[u8], decode: &dyn Fn(&GridHeader) -> Decode) -> Result<ParsedFile, ParseError> {
    let mut cur = Cursor::new(bytes);
    let header = read_header(&mut cur)?;
    let grid_count = read_grid_count(&mut cur)?;
    let mut grids: Vec<ParsedGrid> = Vec::with_capacity(grid_count);
    for _ in 0..grid_count {
        let g = read_grid(&mut cur, &header, decode)?;
        if grids.iter().any(|o| o.header.unique_name_raw == g.header.unique_name_raw) {
            return Err(ParseError {
                offset: g.header.grid_pos,
                message: format!("two grids share the descriptor name `{}`", g.header.unique_name),
            });
        }
        grids.push(g);
    }
    Ok(ParsedFile { header, grids })
}

/// Header steps in byte order (OpenVDB `Archive::readHeader`): 1) magic,
/// 2) file version, 3) library version, 4) has-grid-offsets flag, 5) (no
/// compression byte since 222), 6) UUID; then the file MetaMap.
fn read_header(cur: &mut Cursor) -> Result<Header, ParseError> {
    let magic = cur.i64().map_err(|_| cur.err_at(0, "not a VDB file: shorter than the 8-byte magic number".into()))?;
    if magic != layout::MAGIC {
        return Err(cur.err_at(0, format!("not a VDB file: magic number {magic:#x}, expected {:#x}", layout::MAGIC)));
    }
    let file_version = cur.u32()?;
    if !(layout::MIN_READ_VERSION..=layout::MAX_READ_VERSION).contains(&file_version) {
        return Err(cur.err_at(
            8,
            format!(
                "unsupported file format version {file_version} (this reader handles {}..={})",
                layout::MIN_READ_VERSION,
                layout::MAX_READ_VERSION
            ),
        ));
    }
    let library_major = cur.u32()?;
    let library_minor = cur.u32()?;
    let has_offsets = cur.u8()?;
    if has_offsets != 1 {
        return Err(cur.err_at(20, format!("has-grid-offsets flag is {has_offsets}: streamed archives without offsets are not supported")));
    }
    let uuid = String::from_utf8_lossy(cur.bytes(layout::UUID_LEN)?).into_owned();
    let metadata = read_meta_map(cur)?;
    Ok(Header { file_version, library_major, library_minor, uuid, metadata })
}

/// A grid's descriptor, then at its offset its compression flags and
/// metadata: the cursor is left after the metadata (at the transform).
fn read_grid_header(cur: &mut Cursor) -> Result<GridHeader, ParseError> {
    let desc_at = cur.pos();
    let unique_name_raw = cur.string_bytes()?.to_vec();
    let unique_name = String::from_utf8_lossy(&unique_name_raw).into_owned();
    let type_name = cur.string()?;
    let instance_parent = cur.string()?;
    let grid_pos = cur.i64()?;
    let block_pos = cur.i64()?;
    let end_pos = cur.i64()?;
    let desc_end = cur.pos() as i64;
    let len = cur.data().len() as i64;
    if !(desc_end <= grid_pos && grid_pos <= block_pos && block_pos <= end_pos && end_pos <= len) {
        return Err(cur.err_at(
            desc_at,
            format!(
                "grid `{unique_name}`: offsets out of order or past the end (descriptor ends at {desc_end}, \
                 gridPos {grid_pos}, blockPos {block_pos}, endPos {end_pos}, file length {len})"
            ),
        ));
    }
    let base = type_name.strip_suffix(layout::HALF_FLOAT_SUFFIX).unwrap_or(&type_name);
    let kind = match base {
        "Tree_float_5_4_3" => Some(ValueKind::Float),
        "Tree_vec3s_5_4_3" => Some(ValueKind::Vec3),
        _ => None,
    };
    cur.seek(grid_pos as u64)?;
    let comp_at = cur.pos();
    let compression = cur.u32()?;
    if compression & !(layout::COMPRESS_ZIP | layout::COMPRESS_ACTIVE_MASK | layout::COMPRESS_BLOSC) != 0 {
        return Err(cur.err_at(comp_at, format!("grid `{unique_name}`: invalid compression flags {compression:#x}")));
    }
    let metadata = read_meta_map(cur)?;
    let half = metadata.iter().any(|(k, v)| k == layout::META_HALF && *v == RawMeta::Bool(true));
    Ok(GridHeader {
        unique_name,
        unique_name_raw,
        type_name,
        kind,
        instance_parent,
        grid_pos: grid_pos as u64,
        block_pos: block_pos as u64,
        end_pos: end_pos as u64,
        compression,
        metadata,
        half,
        map_name: String::new(),
        transform: None,
    })
}

/// Every grid's header: its descriptor, compression flags and metadata,
/// without its transform, topology or values (nothing is decoded or
/// validated past the metadata): a cheap listing of what a file's grids
/// say of themselves, for a reader deciding how to read it.
pub fn list_grids(bytes: &[u8]) -> Result<Vec<GridHeader>, ParseError> {
    let mut cur = Cursor::new(bytes);
    read_header(&mut cur)?;
    let grid_count = read_grid_count(&mut cur)?;
    let mut grids = Vec::with_capacity(grid_count);
    for _ in 0..grid_count {
        let gh = read_grid_header(&mut cur)?;
        cur.seek(gh.end_pos)?;
        grids.push(gh);
    }
    Ok(grids)
}

fn read_grid(cur: &mut Cursor, header: &Header, decode: &dyn Fn(&GridHeader) -> Decode) -> Result<ParsedGrid, ParseError> {
    let desc_at = cur.pos();
    let mut gh = read_grid_header(cur)?;
    let kind = gh.kind;
    let tree = match kind {
        None => None,
        Some(kind) => {
            if !gh.instance_parent.is_empty() {
                return Err(cur.err_at(
                    desc_at,
                    format!("grid `{}` is an instance of `{}`: instanced grids are not supported", gh.unique_name, gh.instance_parent),
                ));
            }
            let (map_name, transform) = read_transform(cur, &gh.unique_name)?;
            gh.map_name = map_name;
            gh.transform = Some(transform);
            let fmt = RecordFormat { flags: gh.compression, half: gh.half };
            let dec = decode(&gh);
            let named = |e| in_grid(e, &gh.unique_name);
            let tree = match kind {
                ValueKind::Float => AnyTree::Float(read_tree::<f32>(cur, &gh, fmt, dec).map_err(named)?),
                ValueKind::Vec3 => AnyTree::Vec3(read_tree::<[f32; 3]>(cur, &gh, fmt, dec).map_err(named)?),
            };
            if cur.pos() as u64 != gh.end_pos {
                return Err(cur.err(format!("grid `{}`: data end at {} but endPos says {}", gh.unique_name, cur.pos(), gh.end_pos)));
            }
            Some(tree)
        }
    };
    let _ = header;
    cur.seek(gh.end_pos)?;
    Ok(ParsedGrid { header: gh, tree })
}

/// `e` naming grid `name` (the record decoder's errors do not know it).
fn in_grid(e: ParseError, name: &str) -> ParseError {
    if e.message.starts_with("grid `") {
        return e;
    }
    ParseError { offset: e.offset, message: format!("grid `{name}`: {}", e.message) }
}

/// Reads a transform (OpenVDB `Transform::read`: map type name, then the
/// map's fields) and reduces it to a uniform scale + translation.
fn read_transform(cur: &mut Cursor, grid: &str) -> Result<(String, Transform), ParseError> {
    let at = cur.pos();
    let name = cur.string()?;
    let (scale, translation) = match name.as_str() {
        "UniformScaleTranslateMap" | "ScaleTranslateMap" => {
            let t = cur.dvec3()?;
            let s = cur.dvec3()?;
            for _ in 0..4 {
                cur.dvec3()?; // voxelSize, scaleInverse, invScaleSqr, invTwiceScale
            }
            (s, t)
        }
        "UniformScaleMap" | "ScaleMap" => {
            let s = cur.dvec3()?;
            for _ in 0..4 {
                cur.dvec3()?;
            }
            (s, DVec3::ZERO)
        }
        "TranslationMap" => (DVec3::ONE, cur.dvec3()?),
        "AffineMap" => {
            // Mat4d, row-major, row-vector convention: translation in row 3.
            let mut m = [0f64; 16];
            for v in m.iter_mut() {
                *v = cur.f64()?;
            }
            let s = DVec3::new(m[0], m[5], m[10]);
            let off_diag = [1, 2, 3, 4, 6, 7, 8, 9, 11];
            if off_diag.iter().any(|&i| m[i] != 0.0) || m[15] != 1.0 {
                return Err(cur.err_at(at, format!("grid `{grid}`: AffineMap with rotation, shear or projection is not supported")));
            }
            (s, DVec3::new(m[12], m[13], m[14]))
        }
        other => {
            return Err(cur.err_at(
                at,
                format!("grid `{grid}`: unsupported transform map `{other}` (only uniform scale + translation maps are read)"),
            ))
        }
    };
    if !(scale.x == scale.y && scale.y == scale.z) {
        return Err(cur.err_at(at, format!("grid `{grid}`: non-uniform voxel scale {scale} is not supported")));
    }
    if !(scale.x.is_finite() && scale.x != 0.0 && translation.is_finite()) {
        return Err(cur.err_at(at, format!("grid `{grid}`: degenerate transform (scale {}, translation {translation})", scale.x)));
    }
    Ok((name, Transform::new(scale.x, translation)))
}

/// A full-precision value.
fn read_value<T: VoxelValue>(cur: &mut Cursor) -> Result<T, ParseError> {
    let mut c = [0f32; 3];
    for x in c[..T::COMPONENTS].iter_mut() {
        *x = cur.f32()?;
    }
    Ok(T::from_components(&c))
}

/// Topology of one Internal16 node: slot in its parent, masks and leaf masks.
struct Node16<T> {
    origin: IVec3,
    child_mask: Vec<u64>,
    leaf_masks: Vec<[u64; LEAF_MASK_WORDS]>,
    _t: std::marker::PhantomData<T>,
}

/// Reads an internal node's masks and value array (OpenVDB
/// `InternalNode::readTopology`), collecting its active tiles.
fn read_internal<T: VoxelValue>(
    cur: &mut Cursor,
    level: layout::InternalLevel,
    origin: IVec3,
    fmt: RecordFormat,
    background: T,
    decode: bool,
    tree: &mut Tree<T>,
) -> Result<Vec<u64>, ParseError> {
    let child_mask = cur.u64s(level.mask_words())?;
    let value_mask = cur.u64s(level.mask_words())?;
    let values = decode::read_values::<T>(cur, fmt, level.num_values(), &value_mask, background, decode)?;
    for n in layout::mask_ones(&value_mask) {
        if layout::mask_bit(&child_mask, n) {
            continue;
        }
        tree.active_tile_count += 1;
        tree.tile_voxels += 1u128 << (3 * level.child_log2);
        if let Some(v) = &values {
            let o =
                if level == INTERNAL32 { layout::internal32_child_origin(origin, n) } else { layout::internal16_child_origin(origin, n) };
            tree.tiles.push((o, level.child_log2, v[n]));
        }
    }
    Ok(child_mask)
}

/// Reads topology and buffers of a tree (OpenVDB `RootNode::readTopology`,
/// then `Tree::readBuffers`), in the depth-first order both passes share.
fn read_tree<T: VoxelValue>(cur: &mut Cursor, gh: &GridHeader, fmt: RecordFormat, how: Decode) -> Result<Tree<T>, ParseError> {
    let decode = matches!(how, Decode::All | Decode::NonZero);
    let name = &gh.unique_name;
    let at = cur.pos();
    let buffer_count = cur.i32()?;
    if buffer_count != 1 {
        return Err(cur.err_at(at, format!("grid `{name}`: buffer count {buffer_count}, expected 1")));
    }
    let background: T = read_value(cur)?;
    let at = cur.pos();
    let tile_count = cur.u32()? as usize;
    let child_count = cur.u32()? as usize;
    let full = 4 * T::COMPONENTS;
    if tile_count > cur.remaining() / (12 + full + 1) || child_count > cur.remaining() / 12 {
        return Err(cur.err_at(at, format!("grid `{name}`: {tile_count} root tiles and {child_count} children cannot fit in the file")));
    }
    let mut tree = Tree {
        background,
        leaves: Vec::new(),
        tiles: Vec::new(),
        leaf_count: 0,
        active_tile_count: 0,
        tile_voxels: 0,
        spans: Vec::new(),
        format: fmt,
    };
    // A root holds one entry per origin (OpenVDB's root table is a map
    // keyed by it, written aligned): an unaligned or repeated origin, tile
    // or child, would make two nodes cover the same voxels, and so two
    // leaves share an origin once the tiles are densified.
    let mut root_tiles: HashSet<(i32, i32, i32)> = HashSet::new();
    for _ in 0..tile_count {
        let at = cur.pos();
        let o = cur.ivec3()?;
        if layout::root_child_origin(o) != o {
            return Err(cur.err_at(at, format!("grid `{name}`: root tile origin {o} is not a multiple of 4096")));
        }
        if !root_tiles.insert((o.x, o.y, o.z)) {
            return Err(
                cur.err_at(at, format!("grid `{name}`: two root tiles at {o}: duplicate leaf origins (a root holds one entry per origin)"))
            );
        }
        let v: T = read_value(cur)?;
        let active = cur.u8()?;
        if active != 0 {
            tree.active_tile_count += 1;
            tree.tile_voxels += 1u128 << (3 * layout::ROOT_CHILD_LOG2);
            if decode {
                tree.tiles.push((o, layout::ROOT_CHILD_LOG2, v));
            }
        }
    }
    let mut nodes16: Vec<Node16<T>> = Vec::new();
    let mut prev: Option<IVec3> = None;
    for _ in 0..child_count {
        let at = cur.pos();
        let origin = cur.ivec3()?;
        if layout::root_child_origin(origin) != origin {
            return Err(cur.err_at(at, format!("grid `{name}`: root child origin {origin} is not a multiple of 4096")));
        }
        if root_tiles.contains(&(origin.x, origin.y, origin.z)) {
            return Err(cur.err_at(
                at,
                format!("grid `{name}`: a root tile and a root child both at {origin}: duplicate leaf origins (a root holds one entry per origin)"),
            ));
        }
        if let Some(p) = prev {
            if (p.x, p.y, p.z) >= (origin.x, origin.y, origin.z) {
                return Err(cur.err_at(
                    at,
                    format!("grid `{name}`: root children not in ascending (x, y, z) order ({p} then {origin}); OpenVDB would misassign their buffers"),
                ));
            }
        }
        prev = Some(origin);
        let cm32 = read_internal(cur, INTERNAL32, origin, fmt, background, decode, &mut tree)?;
        for n32 in layout::mask_ones(&cm32) {
            let o16 = layout::internal32_child_origin(origin, n32);
            let cm16 = read_internal(cur, INTERNAL16, o16, fmt, background, decode, &mut tree)?;
            let k = layout::mask_count(&cm16);
            if k * 64 > cur.remaining() {
                return Err(cur.err(format!("grid `{name}`: truncated leaf topology")));
            }
            let mut leaf_masks = Vec::with_capacity(k);
            for _ in 0..k {
                let m = cur.u64s(LEAF_MASK_WORDS)?;
                leaf_masks.push(m.try_into().expect("8 words"));
            }
            tree.leaf_count += k;
            nodes16.push(Node16 { origin: o16, child_mask: cm16, leaf_masks, _t: std::marker::PhantomData });
        }
    }
    if cur.pos() as u64 != gh.block_pos {
        return Err(cur.err(format!("grid `{name}`: topology ends at {} but blockPos says {}", cur.pos(), gh.block_pos)));
    }
    // Buffers: per leaf, a copy of the value mask and the value record. The
    // records are located in one serial pass (their lengths chain); when
    // decoding, the leaves are then decoded in parallel, each straight into
    // its own value array (no intermediate copies).
    let mut spans: Vec<(IVec3, &[u64; LEAF_MASK_WORDS], usize)> = Vec::new();
    let mut scratch = Vec::new();
    for node in &nodes16 {
        for (n16, mask) in layout::mask_ones(&node.child_mask).zip(&node.leaf_masks) {
            let at = cur.pos();
            let copy = cur.u64s(LEAF_MASK_WORDS)?;
            if copy[..] != mask[..] {
                return Err(cur.err_at(at, format!("grid `{name}`: leaf value mask in the buffers differs from the topology")));
            }
            let start = cur.pos();
            // A located record is decoded (and its stream checked) later, by
            // the caller or by [`check_located`].
            let check_streams = !decode && how != Decode::Locate;
            decode::read_values_into::<T>(cur, fmt, LEAF_NUM_VALUES, mask, background, Destination::Skip { check_streams }, &mut scratch)?;
            if decode {
                spans.push((layout::internal16_child_origin(node.origin, n16), mask, start));
            } else if how == Decode::Locate {
                let origin = layout::internal16_child_origin(node.origin, n16);
                tree.spans.push(LeafSpan { origin, mask: *mask, start });
            }
        }
    }
    if decode {
        use rayon::prelude::*;
        let data = cur.data();
        let leaves: Vec<Result<Option<Leaf<T>>, ParseError>> = spans
            .par_iter()
            .map_init(Vec::new, |scratch, &(origin, mask, start)| {
                let mut c = Cursor::new(data);
                c.seek(start as u64)?;
                let mut leaf = Leaf::new(origin, background);
                leaf.mask = *mask;
                decode::read_values_into(
                    &mut c,
                    fmt,
                    LEAF_NUM_VALUES,
                    mask,
                    background,
                    Destination::Slots(&mut leaf.values[..]),
                    scratch,
                )?;
                if how == Decode::NonZero && !has_nonzero_active(&leaf) {
                    return Ok(None);
                }
                Ok(Some(leaf))
            })
            .collect();
        // The first failing leaf in file order, whatever the thread count.
        let leaves: Vec<Option<Leaf<T>>> = leaves.into_iter().collect::<Result<_, _>>()?;
        tree.leaves = leaves.into_iter().flatten().collect();
    }
    Ok(tree)
}

/// Checks every record a [`Decode::Locate`] parse of `data` located in
/// `tree` as decoding it would ([`Decode::All`] gives the same verdict),
/// keeping no value: each record is walked again with its ZIP or Blosc
/// stream decompressed into a per-thread scratch buffer and dropped. For a
/// caller that decodes only some grids' records and must still refuse
/// what the grid reader refuses. Costs a decompression of every record
/// (nothing for uncompressed ones), in parallel; the first failing record
/// in file order is reported, naming the grid as `name`, whatever the
/// thread count.
pub fn check_located<T: VoxelValue>(data: &[u8], tree: &Tree<T>, name: &str) -> Result<(), ParseError> {
    use rayon::prelude::*;
    let first_err = tree
        .spans
        .par_iter()
        .map_init(Vec::new, |scratch, span| {
            let mut c = Cursor::new(data);
            c.seek(span.start as u64)?;
            decode::read_values_into::<T>(
                &mut c,
                tree.format,
                LEAF_NUM_VALUES,
                &span.mask,
                tree.background,
                Destination::Skip { check_streams: true },
                scratch,
            )
        })
        .find_first(|r| r.is_err());
    match first_err {
        Some(Err(e)) => Err(in_grid(e, name)),
        _ => Ok(()),
    }
}

/// Whether some active voxel of `leaf` is not 0 (a NaN or negative value
/// counts: the caller's validation reports it).
fn has_nonzero_active<T: VoxelValue>(leaf: &Leaf<T>) -> bool {
    leaf.mask.iter().enumerate().any(|(w, &word)| {
        let mut bits = word;
        while bits != 0 {
            let n = w * 64 + bits.trailing_zeros() as usize;
            bits &= bits - 1;
            if leaf.values[n] != T::ZERO {
                return true;
            }
        }
        false
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn meta_map_sizes_are_checked() {
        let mut b = Vec::new();
        b.extend_from_slice(&1u32.to_le_bytes());
        for s in ["flag", "bool"] {
            b.extend_from_slice(&(s.len() as u32).to_le_bytes());
            b.extend_from_slice(s.as_bytes());
        }
        b.extend_from_slice(&4u32.to_le_bytes());
        b.extend_from_slice(&[1, 0, 0, 0]);
        assert!(read_meta_map(&mut Cursor::new(&b)).is_err(), "a 4-byte bool is rejected");
        // A huge count is rejected before anything is allocated.
        let b = u32::MAX.to_le_bytes();
        assert!(read_meta_map(&mut Cursor::new(&b)).is_err());
    }
}
