//! Native OpenVDB writer: file format version 224, byte for byte what
//! OpenVDB 10 to 12 write for fog-volume `float` and `vec3s` grids made of
//! leaves (the byte layout: `super::layout`; metadata maps: `super::meta`;
//! the tree's topology: `super::topology`).
//!
//! File layout, in byte order (OpenVDB `io/Archive.cc`, `Archive::writeHeader`
//! then `Archive::write` / `writeGrid`):
//!
//! 1. magic number, `i64` `0x56444220`;
//! 2. file format version, `u32` 224;
//! 3. library major and minor version, 2 x `u32`;
//! 4. has-grid-offsets flag, `u8` 1;
//! 5. (the compression byte of versions 220-221 is omitted since 222);
//! 6. UUID, 36 ASCII characters. OpenVDB draws it at random; we derive it
//!    from a hash of everything after the header (see [`content_uuid`]), so
//!    identical inputs give byte-identical files;
//! 7. file MetaMap (empty);
//! 8. `i32` grid count;
//! 9. per grid: descriptor (name, type, instance parent, `gridPos`,
//!    `blockPos`, `endPos`), compression flags, grid MetaMap (keys sorted, as
//!    `std::map` orders them), transform (`UniformScaleTranslateMap`), tree
//!    topology, then the leaf buffers.
//!
//! The tree is regrouped from the grid's keyed leaves into the 5-4-3
//! hierarchy: root children in ascending signed (x, y, z) order, Internal32
//! and Internal16 children in ascending slot order, identically in the
//! topology and buffer passes (a different order makes OpenVDB silently
//! misassign buffers). Each node level writes its own bytes.
//!
//! The file is streamed: the header is written last over a placeholder, and
//! each grid's three offsets are patched once the grid is written (as
//! `Archive::writeGrid` does). Leaf buffers are encoded in parallel in chunks
//! of 64 leaves, batch by batch, and written in order, so memory stays bounded
//! and the output does not depend on the thread count. All values are checked
//! before anything is renamed into place: NaN or infinity, and in half mode
//! magnitudes above 65504, are refused with the grid name and voxel.

use super::codec::{Deflate, Encoder, Storage};
use super::fileid::piece_hash;
/// The file-ID code, re-exported for the writer's callers.
pub use super::fileid::{content_uuid, xxh64};
use super::layout::{self};
use super::mantissa;
pub use super::meta::MetaValue;
use super::meta::{push_dvec3, push_string, write_meta_map};
use super::topology::{build_tree, write_mask, write_root_topology};
use crate::grid::{Grid, Leaf, VoxelValue, LEAF_NUM_VALUES};
use crate::scene::Compression;
use glam::IVec3;
use rayon::prelude::*;
use std::path::{Path, PathBuf};

/// A grid to write, of either value type.
#[derive(Clone, Copy, Debug)]
pub enum GridRef<'a> {
    Float(&'a Grid<f32>),
    Vec3(&'a Grid<[f32; 3]>),
}

impl GridRef<'_> {
    pub fn name(&self) -> &str {
        match self {
            GridRef::Float(g) => &g.name,
            GridRef::Vec3(g) => &g.name,
        }
    }
}

/// How to write a file.
#[derive(Clone, Debug, PartialEq)]
pub struct WriteOptions {
    /// Compression of every grid's value arrays.
    pub compression: Compression,
    /// Names of grids stored as half floats (typically `emission`).
    pub half: Vec<String>,
    /// Grids whose values are rounded to fewer mantissa bits
    /// ([`super::mantissa`]), with the bits kept (1 to 23; a half float
    /// keeps at most its 10). The grid's metadata `aurora_mantissa_bits`
    /// records the width.
    pub mantissa_bits: Vec<(String, u32)>,
    /// The deflate of ZIP records (OpenVDB's zlib by default).
    pub deflate: Deflate,
    /// Extra metadata added to every grid (units, seed, scene hash...).
    pub metadata: Vec<(String, MetaValue)>,
}

impl Default for WriteOptions {
    /// Blosc + active-mask compression (OpenVDB's default), no half grids,
    /// no extra metadata.
    fn default() -> Self {
        Self {
            compression: Compression::BloscActiveMask,
            half: Vec::new(),
            mantissa_bits: Vec::new(),
            deflate: Deflate::OpenVdb,
            metadata: Vec::new(),
        }
    }
}

/// Why a file was not written.
#[derive(Debug, thiserror::Error)]
pub enum VdbWriteError {
    /// A voxel value is NaN or infinite.
    #[error("grid `{grid}`: voxel ({}, {}, {}) holds {value}, which is not finite", ijk[0], ijk[1], ijk[2])]
    NonFinite { grid: String, ijk: [i32; 3], value: String },
    /// A voxel value cannot be stored as a half float without becoming infinite.
    #[error("grid `{grid}`: voxel ({}, {}, {}) holds {value}, beyond the half-float range (|x| <= 65504); store this grid as full float", ijk[0], ijk[1], ijk[2])]
    HalfOverflow { grid: String, ijk: [i32; 3], value: String },
    /// The background value is not finite or not representable as half.
    #[error("grid `{grid}`: background {value} is not finite or not representable in the chosen precision")]
    BadBackground { grid: String, value: String },
    /// The transform has a zero or non-finite voxel size or translation.
    #[error("grid `{grid}`: invalid transform (voxel size {voxel_size}, translation {translation})")]
    BadTransform { grid: String, voxel_size: f64, translation: String },
    /// Grid names must be non-empty and unique (OpenVDB would rename duplicates).
    #[error("grid name `{0}` is empty or used twice")]
    BadName(String),
    /// `WriteOptions::half` names a grid that is not being written.
    #[error("half-float storage requested for grid `{0}`, which is not among the grids written")]
    UnknownHalfGrid(String),
    /// `WriteOptions::mantissa_bits` names a grid that is not being written,
    /// twice, or a width outside 1..=23.
    #[error(
        "mantissa rounding to {bits} bits for grid `{grid}`: the grid must be among those written, named once, and the bits in 1..=23"
    )]
    BadMantissaBits { grid: String, bits: u32 },
    /// Extra metadata may not replace what the writer sets itself.
    #[error("metadata key `{0}` is reserved by the writer, empty, or given twice")]
    ReservedMetadata(String),
    #[error("writing `{path}`: {source}")]
    Io { path: PathBuf, source: std::io::Error },
    /// The destination is not ours to replace, or the temporary could not be made or renamed.
    #[error(transparent)]
    Output(Box<crate::util::atomic_write::AtomicError>),
}

impl VdbWriteError {
    /// True when the user's choice of output is at fault (exit status 2); the other variants are values or I/O this process failed to write.
    pub fn is_input(&self) -> bool {
        matches!(self, VdbWriteError::Output(a) if a.is_input())
    }
}

/// What was written, per grid.
#[derive(Clone, Debug, PartialEq)]
pub struct GridStats {
    pub name: String,
    pub active_voxels: u64,
    pub leaves: usize,
    /// Bytes of this grid, descriptor included.
    pub bytes: u64,
}

/// What was written.
#[derive(Clone, Debug, PartialEq)]
pub struct WriteStats {
    /// File size.
    pub bytes: u64,
    /// The file's UUID: a hash of its content ([`content_uuid`]), so it
    /// identifies these bytes (bake.json names it).
    pub uuid: String,
    pub grids: Vec<GridStats>,
}

/// Grid metadata naming the mantissa bits kept ([`WriteOptions::mantissa_bits`]),
/// written only when some were cleared.
pub const META_MANTISSA_BITS: &str = "aurora_mantissa_bits";

/// Metadata keys the writer sets itself.
const RESERVED_KEYS: &[&str] = &[
    META_MANTISSA_BITS,
    "class",
    "creator",
    "file_bbox_max",
    "file_bbox_min",
    "file_compression",
    "file_delayed_load",
    "file_mem_bytes",
    "file_voxel_count",
    "is_local_space",
    "is_saved_as_half_float",
    "name",
    "value_type",
    "vector_type",
];

/// Value of the `creator` metadata.
pub const CREATOR: &str = concat!("aurora ", env!("CARGO_PKG_VERSION"));

/// Per-grid compression flags of a [`Compression`] choice.
pub fn compression_flags(c: Compression) -> u32 {
    match c {
        Compression::None => 0,
        Compression::Zip => layout::COMPRESS_ZIP,
        Compression::ActiveMask => layout::COMPRESS_ACTIVE_MASK,
        Compression::ZipActiveMask => layout::COMPRESS_ZIP | layout::COMPRESS_ACTIVE_MASK,
        Compression::Blosc => layout::COMPRESS_BLOSC,
        Compression::BloscActiveMask => layout::COMPRESS_BLOSC | layout::COMPRESS_ACTIVE_MASK,
    }
}

/// Encodes a whole VDB file in memory.
pub fn write_vdb_bytes(grids: &[GridRef], opts: &WriteOptions) -> Result<Vec<u8>, VdbWriteError> {
    let mut out = Vec::new();
    encode_file(&mut out, grids, opts)?;
    Ok(out)
}

/// Writes a VDB file atomically: streamed to a locked temporary in the same
/// folder, then renamed over `path` ([`crate::util::atomic_write`]: only a regular file is
/// ever replaced). On any error the temporary is removed and `path` is
/// untouched. The bytes are those of [`write_vdb_bytes`].
pub fn write_vdb(path: &Path, grids: &[GridRef], opts: &WriteOptions) -> Result<WriteStats, VdbWriteError> {
    let mut tmp = crate::util::atomic_write::TempFile::create(path).map_err(|e| VdbWriteError::Output(Box::new(e)))?;
    let stats = write_vdb_into(&mut tmp, grids, opts)?;
    tmp.commit().map_err(|e| VdbWriteError::Output(Box::new(e)))?;
    Ok(stats)
}

/// Streams a VDB file into a staged temporary (committed by the caller, for
/// example as a member of a [`crate::util::atomic_write::Unit`]).
pub fn write_vdb_into(
    tmp: &mut crate::util::atomic_write::TempFile,
    grids: &[GridRef],
    opts: &WriteOptions,
) -> Result<WriteStats, VdbWriteError> {
    let path = tmp.dest().to_path_buf();
    let mut target = FileTarget(tmp.file());
    encode_file(&mut target, grids, opts).map_err(|e| match e {
        VdbWriteError::Io { source, .. } => VdbWriteError::Io { path, source },
        other => other,
    })
}

/// Where the file goes: appended in order, with a few fixed-size fields
/// (descriptor offsets, UUID) patched in place at the end.
trait Target {
    fn append(&mut self, bytes: &[u8]) -> std::io::Result<()>;
    fn patch(&mut self, at: u64, bytes: &[u8]) -> std::io::Result<()>;
}

impl Target for Vec<u8> {
    fn append(&mut self, bytes: &[u8]) -> std::io::Result<()> {
        self.extend_from_slice(bytes);
        Ok(())
    }
    fn patch(&mut self, at: u64, bytes: &[u8]) -> std::io::Result<()> {
        self[at as usize..at as usize + bytes.len()].copy_from_slice(bytes);
        Ok(())
    }
}

/// A file written sequentially (pieces are leaf chunks of ~100 KB or a few
/// headers, so no buffering is needed), patched with positioned writes.
struct FileTarget<'f>(&'f mut std::fs::File);

impl Target for FileTarget<'_> {
    fn append(&mut self, bytes: &[u8]) -> std::io::Result<()> {
        use std::io::Write;
        self.0.write_all(bytes)
    }
    fn patch(&mut self, at: u64, bytes: &[u8]) -> std::io::Result<()> {
        use std::io::{Seek, SeekFrom, Write};
        let end = self.0.stream_position()?;
        self.0.seek(SeekFrom::Start(at))?;
        self.0.write_all(bytes)?;
        self.0.seek(SeekFrom::Start(end))?;
        Ok(())
    }
}

/// Appends pieces to a [`Target`], tracking the file offset and the hash of
/// every piece after the header (for the UUID).
struct Stream<'t> {
    target: &'t mut dyn Target,
    pos: u64,
    hashes: Vec<(u64, u64)>,
}

impl Stream<'_> {
    fn put(&mut self, bytes: &[u8]) -> std::io::Result<()> {
        self.put_hashed(bytes, piece_hash(bytes))
    }
    fn put_hashed(&mut self, bytes: &[u8], hash: (u64, u64)) -> std::io::Result<()> {
        self.target.append(bytes)?;
        self.pos += bytes.len() as u64;
        self.hashes.push(hash);
        Ok(())
    }
}

/// How `opts` stores the grid `name`.
fn storage(opts: &WriteOptions, name: &str) -> Storage {
    let half = opts.half.iter().any(|h| h == name);
    let kept = opts.mantissa_bits.iter().find(|(g, _)| g == name).map(|&(_, b)| b);
    Storage { half, mantissa_bits: kept.unwrap_or(mantissa::FLOAT_MANTISSA_BITS), deflate: opts.deflate }
}

fn check_options(grids: &[GridRef], opts: &WriteOptions) -> Result<(), VdbWriteError> {
    for (i, g) in grids.iter().enumerate() {
        if g.name().is_empty() || grids[..i].iter().any(|o| o.name() == g.name()) {
            return Err(VdbWriteError::BadName(g.name().to_string()));
        }
    }
    for h in &opts.half {
        if !grids.iter().any(|g| g.name() == h) {
            return Err(VdbWriteError::UnknownHalfGrid(h.clone()));
        }
    }
    for (i, (g, bits)) in opts.mantissa_bits.iter().enumerate() {
        let named_once = grids.iter().any(|x| x.name() == g) && !opts.mantissa_bits[..i].iter().any(|(o, _)| o == g);
        if !named_once || !(1..=mantissa::FLOAT_MANTISSA_BITS).contains(bits) {
            return Err(VdbWriteError::BadMantissaBits { grid: g.clone(), bits: *bits });
        }
    }
    for (i, (k, _)) in opts.metadata.iter().enumerate() {
        if k.is_empty() || RESERVED_KEYS.contains(&k.as_str()) || opts.metadata[..i].iter().any(|(o, _)| o == k) {
            return Err(VdbWriteError::ReservedMetadata(k.clone()));
        }
    }
    Ok(())
}

/// Streams the whole file into `target`; IO errors name `<output>` and are
/// renamed by the caller.
fn encode_file(target: &mut dyn Target, grids: &[GridRef], opts: &WriteOptions) -> Result<WriteStats, VdbWriteError> {
    check_options(grids, opts)?;
    let io = |source| VdbWriteError::Io { path: PathBuf::from("<output>"), source };
    let flags = compression_flags(opts.compression);
    // Steps 1-6, the header, are written last (the UUID hashes the content):
    // a placeholder of the same length first.
    target.append(&[0u8; layout::HEADER_LEN]).map_err(io)?;
    let mut out = Stream { target, pos: layout::HEADER_LEN as u64, hashes: Vec::new() };
    // 7. File MetaMap: empty. 8. Grid count.
    let mut head = Vec::new();
    head.extend_from_slice(&0u32.to_le_bytes());
    head.extend_from_slice(&(grids.len() as i32).to_le_bytes());
    out.put(&head).map_err(io)?;
    let mut stats = Vec::with_capacity(grids.len());
    for g in grids {
        let st = storage(opts, g.name());
        let start = out.pos;
        let (active_voxels, leaves) = match g {
            GridRef::Float(g) => write_grid(&mut out, g, flags, st, &opts.metadata)?,
            GridRef::Vec3(g) => write_grid(&mut out, g, flags, st, &opts.metadata)?,
        };
        stats.push(GridStats { name: g.name().to_string(), active_voxels, leaves, bytes: out.pos - start });
    }
    let uuid = content_uuid(&out.hashes);
    let mut h = Vec::with_capacity(layout::HEADER_LEN);
    h.extend_from_slice(&layout::MAGIC.to_le_bytes());
    h.extend_from_slice(&layout::FILE_VERSION.to_le_bytes());
    h.extend_from_slice(&layout::LIBRARY_MAJOR.to_le_bytes());
    h.extend_from_slice(&layout::LIBRARY_MINOR.to_le_bytes());
    h.push(1);
    h.extend_from_slice(uuid.as_bytes());
    debug_assert_eq!(h.len(), layout::HEADER_LEN);
    let bytes = out.pos;
    out.target.patch(0, &h).map_err(io)?;
    Ok(WriteStats { bytes, uuid, grids: stats })
}

/// Streams descriptor and body of one grid; returns (active voxels, leaves).
/// The descriptor's three offsets are hashed as zeros and patched once the
/// grid is written (as OpenVDB's `Archive::writeGrid` seeks back for them).
fn write_grid<T: VoxelValue>(
    out: &mut Stream,
    grid: &Grid<T>,
    flags: u32,
    st: Storage,
    extra: &[(String, MetaValue)],
) -> Result<(u64, usize), VdbWriteError> {
    let half = st.half;
    let io = |source| VdbWriteError::Io { path: PathBuf::from("<output>"), source };
    let name = &grid.name;
    let tr = grid.transform;
    if !(tr.voxel_size.is_finite() && tr.voxel_size != 0.0 && tr.translation.is_finite()) {
        return Err(VdbWriteError::BadTransform {
            grid: name.clone(),
            voxel_size: tr.voxel_size,
            translation: format!("{}", tr.translation),
        });
    }
    let bg = grid.background;
    let bg_ok = bg.is_finite() && (!half || bg.components()[..T::COMPONENTS].iter().all(|x| x.abs() <= HALF_MAX));
    if !bg_ok {
        return Err(VdbWriteError::BadBackground { grid: name.clone(), value: format!("{bg:?}") });
    }
    let tree = build_tree(grid);
    let (active, bbox) = leaf_statistics(&tree.leaves);

    // Descriptor: name, type, instance parent, then gridPos/blockPos/endPos.
    let mut head = Vec::new();
    let type_name = if half { format!("{}{}", T::TREE_TYPE, layout::HALF_FLOAT_SUFFIX) } else { T::TREE_TYPE.to_string() };
    push_string(&mut head, name);
    push_string(&mut head, &type_name);
    push_string(&mut head, "");
    let offsets_at = out.pos + head.len() as u64;
    head.extend_from_slice(&[0u8; 24]);
    let grid_pos = out.pos + head.len() as u64;
    head.extend_from_slice(&flags.to_le_bytes());

    // Grid metadata.
    let (bmin, bmax) = bbox
        .map(|(lo, hi)| (lo.to_array(), hi.to_array()))
        // OpenVDB's empty CoordBBox: min = INT_MAX, max = INT_MIN.
        .unwrap_or(([i32::MAX; 3], [i32::MIN; 3]));
    let mut meta: Vec<(String, MetaValue)> = vec![
        ("class".into(), MetaValue::String("fog volume".into())),
        ("creator".into(), MetaValue::String(CREATOR.into())),
        ("file_bbox_max".into(), MetaValue::Vec3i(bmax)),
        ("file_bbox_min".into(), MetaValue::Vec3i(bmin)),
        ("file_compression".into(), MetaValue::String(layout::compression_name(flags))),
        ("file_voxel_count".into(), MetaValue::Int64(active as i64)),
        ("name".into(), MetaValue::String(name.clone())),
        ("value_type".into(), MetaValue::String(if T::COMPONENTS == 1 { "float" } else { "vec3s" }.into())),
    ];
    if half {
        meta.push((layout::META_HALF.into(), MetaValue::Bool(true)));
    }
    let full_width = if half { mantissa::HALF_MANTISSA_BITS } else { mantissa::FLOAT_MANTISSA_BITS };
    if st.mantissa_bits < full_width {
        meta.push((META_MANTISSA_BITS.into(), MetaValue::Int64(st.mantissa_bits as i64)));
    }
    meta.extend(extra.iter().cloned());
    write_meta_map(&mut head, meta);
    write_transform(&mut head, tr.voxel_size, tr.translation.to_array());
    write_root_topology(&mut head, &tree, bg, flags, st);
    out.put(&head).map_err(io)?;
    drop(head);
    let block_pos = out.pos;
    write_buffers(out, &tree.leaves, name, bg, flags, st)?;
    let end_pos = out.pos;
    let mut offsets = [0u8; 24];
    for (i, p) in [grid_pos, block_pos, end_pos].into_iter().enumerate() {
        offsets[8 * i..8 * i + 8].copy_from_slice(&(p as i64).to_le_bytes());
    }
    out.target.patch(offsets_at, &offsets).map_err(io)?;
    Ok((active, tree.leaves.len()))
}

/// `UniformScaleTranslateMap`: translation, scale, voxel size, then the
/// inverse scale `inv = 1/s`, `inv * inv` (not `1/(s*s)`, which differs in
/// the last bit) and `inv / 2` (OpenVDB `ScaleTranslateMap::write`).
fn write_transform(out: &mut Vec<u8>, s: f64, t: [f64; 3]) {
    push_string(out, "UniformScaleTranslateMap");
    let inv = 1.0 / s;
    push_dvec3(out, t);
    push_dvec3(out, [s; 3]);
    push_dvec3(out, [s.abs(); 3]);
    push_dvec3(out, [inv; 3]);
    push_dvec3(out, [inv * inv; 3]);
    push_dvec3(out, [inv / 2.0; 3]);
}

/// Largest finite half float.
const HALF_MAX: f32 = 65504.0;

/// Leaf buffers (OpenVDB `LeafNode::writeBuffers`): a copy of the value mask,
/// then the value record.
fn write_leaf_buffers<T: VoxelValue>(out: &mut Vec<u8>, leaf: &Leaf<T>, bg: T, enc: &mut Encoder) {
    write_mask(out, &leaf.mask);
    enc.write_values(out, &leaf.values[..], &leaf.mask, None, bg);
}

/// Checks a leaf's values (every one is written in some mode): finite, and
/// within half range in half mode. The error names the first bad voxel in
/// offset order.
fn check_leaf<T: VoxelValue>(leaf: &Leaf<T>, grid: &str, half: bool) -> Result<(), VdbWriteError> {
    let limit = if half { HALF_MAX } else { f32::MAX };
    // Fast path: `x.abs() <= limit` is false for NaN and infinities. Every
    // value is tested, without an early exit, so the loop vectorises.
    let all_ok = leaf.values.iter().fold(true, |ok, v| v.components()[..T::COMPONENTS].iter().fold(ok, |ok, x| ok & (x.abs() <= limit)));
    if all_ok {
        return Ok(());
    }
    for n in 0..LEAF_NUM_VALUES {
        let v = leaf.values[n];
        let c = v.components();
        let c = &c[..T::COMPONENTS];
        let ijk = (leaf.origin + crate::grid::offset_to_local(n)).to_array();
        if !c.iter().all(|x| x.is_finite()) {
            return Err(VdbWriteError::NonFinite { grid: grid.to_string(), ijk, value: format!("{v:?}") });
        }
        if !c.iter().all(|x| x.abs() <= limit) {
            return Err(VdbWriteError::HalfOverflow { grid: grid.to_string(), ijk, value: format!("{v:?}") });
        }
    }
    Ok(())
}

/// Inclusive index bounding box of a leaf's active voxels, from its mask:
/// word `w` holds the voxels with local x = w, byte `j` of it those with
/// y = j, bit `b` of a byte z = b (offset `x<<6 | y<<3 | z`).
fn leaf_active_bbox(origin: IVec3, mask: &[u64; crate::grid::LEAF_MASK_WORDS]) -> Option<(IVec3, IVec3)> {
    let (mut x0, mut x1, mut ys, mut zs) = (8i32, -1i32, 0u8, 0u8);
    for (w, &word) in mask.iter().enumerate() {
        if word == 0 {
            continue;
        }
        x0 = x0.min(w as i32);
        x1 = w as i32;
        for (j, b) in word.to_le_bytes().into_iter().enumerate() {
            if b != 0 {
                ys |= 1 << j;
                zs |= b;
            }
        }
    }
    if x1 < 0 {
        return None;
    }
    let lo = IVec3::new(x0, ys.trailing_zeros() as i32, zs.trailing_zeros() as i32);
    let hi = IVec3::new(x1, 7 - ys.leading_zeros() as i32, 7 - zs.leading_zeros() as i32);
    Some((origin + lo, origin + hi))
}

/// Active voxel count and bounding box of the leaves (OpenVDB's
/// `file_voxel_count`, `file_bbox_min/max`), from the masks alone.
fn leaf_statistics<T: VoxelValue>(leaves: &[&Leaf<T>]) -> (u64, Option<(IVec3, IVec3)>) {
    leaves.par_iter().map(|l| (l.active_count(), leaf_active_bbox(l.origin, &l.mask))).reduce(
        || (0, None),
        |(n, a), (m, b)| {
            let bb = match (a, b) {
                (Some(a), Some(b)) => Some((a.0.min(b.0), a.1.max(b.1))),
                (a, b) => a.or(b),
            };
            (n + m, bb)
        },
    )
}

/// Leaves per parallel work item: enough to amortise the zlib stream setup.
const LEAVES_PER_CHUNK: usize = 64;
/// Chunks encoded per parallel batch before they are written out: bounds the
/// memory held to about 1024 leaves' buffers (~6 MB for vec3s).
const CHUNKS_PER_BATCH: usize = 16;

/// Encodes and streams all leaf buffers in file order, in parallel chunks
/// (each hashed where it is encoded). On bad values, the error is the one of
/// the first bad leaf in file order (deterministic).
fn write_buffers<T: VoxelValue>(
    out: &mut Stream,
    leaves: &[&Leaf<T>],
    grid: &str,
    bg: T,
    flags: u32,
    st: Storage,
) -> Result<(), VdbWriteError> {
    let half = st.half;
    let io = |source| VdbWriteError::Io { path: PathBuf::from("<output>"), source };
    for batch in leaves.chunks(LEAVES_PER_CHUNK * CHUNKS_PER_BATCH) {
        type Encoded = Result<(Vec<u8>, (u64, u64)), VdbWriteError>;
        let chunks: Vec<Encoded> = batch
            .par_chunks(LEAVES_PER_CHUNK)
            // One encoder (and its deflate state) per worker, not per chunk:
            // every record resets it, so the bytes are the same.
            .map_init(
                || Encoder::new(flags, st),
                |enc, chunk| {
                    let elem = if half { 2 } else { 4 } * T::COMPONENTS;
                    let mut bytes = Vec::with_capacity(chunk.len() * (64 + 1 + 8 + LEAF_NUM_VALUES * elem));
                    for leaf in chunk {
                        check_leaf(leaf, grid, half)?;
                        write_leaf_buffers(&mut bytes, leaf, bg, enc);
                    }
                    let h = piece_hash(&bytes);
                    Ok((bytes, h))
                },
            )
            .collect();
        for c in chunks {
            let (bytes, h) = c?;
            out.put_hashed(&bytes, h).map_err(io)?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grid::Transform;
    use glam::DVec3;

    fn grid_with(points: &[(IVec3, f32)]) -> Grid<f32> {
        let mut g = Grid::new("density", 0.0f32, Transform::new(0.5, DVec3::new(1.0, -2.0, 3.0)));
        for &(p, v) in points {
            g.set(p, v);
        }
        g
    }

    /// Leaves are emitted root by root in ascending signed (x, y, z), then by
    /// Internal32 slot, then by Internal16 slot, whatever the insertion order.
    #[test]
    fn tree_order_is_openvdb_order() {
        let pts = [
            IVec3::new(5000, 0, 0),
            IVec3::new(-1, 0, 0),
            IVec3::new(0, 0, -1),
            IVec3::new(0, 200, 0),
            IVec3::new(130, 0, 0),
            IVec3::new(0, 0, 8),
            IVec3::new(0, 0, 0),
            IVec3::new(8, 0, 0),
        ];
        let g = grid_with(&pts.iter().map(|&p| (p, 1.0)).collect::<Vec<_>>());
        let tree = build_tree(&g);
        let origins: Vec<IVec3> = tree.leaves.iter().map(|l| l.origin).collect();
        assert_eq!(
            origins,
            vec![
                IVec3::new(-8, 0, 0),   // root (-4096, 0, 0)
                IVec3::new(0, 0, -8),   // root (0, 0, -4096)
                IVec3::new(0, 0, 0),    // root (0,0,0), slot32 0, slot16 0
                IVec3::new(0, 0, 8),    //   slot16 1
                IVec3::new(8, 0, 0),    //   slot16 256
                IVec3::new(0, 200, 0),  // slot32 32
                IVec3::new(128, 0, 0),  // slot32 1024
                IVec3::new(5000, 0, 0), // root (4096, 0, 0)
            ]
        );
        assert_eq!(tree.roots.len(), 4);
        assert_eq!(tree.roots[2].nodes.len(), 3);
        assert_eq!(tree.roots[2].nodes[0].leaves, 2..5);
    }

    #[test]
    fn header_offsets_and_determinism() {
        let g = grid_with(&[(IVec3::new(1, 2, 3), 0.5), (IVec3::new(-100, 7, 9000), 2.0)]);
        let a = write_vdb_bytes(&[GridRef::Float(&g)], &WriteOptions::default()).unwrap();
        let b = write_vdb_bytes(&[GridRef::Float(&g)], &WriteOptions::default()).unwrap();
        assert_eq!(a, b, "identical inputs give identical bytes");
        assert_eq!(&a[0..8], &[0x20, 0x42, 0x44, 0x56, 0, 0, 0, 0]);
        assert_eq!(u32::from_le_bytes(a[8..12].try_into().unwrap()), 224);
        assert_eq!(a[20], 1);
        let uuid = std::str::from_utf8(&a[21..57]).unwrap();
        assert_eq!(uuid.len(), 36);
        assert_eq!(uuid.as_bytes()[14], b'8');
        assert!(uuid.chars().enumerate().all(|(i, c)| if [8, 13, 18, 23].contains(&i) { c == '-' } else { c.is_ascii_hexdigit() }));
        // Empty file MetaMap, one grid; the descriptor starts at 65.
        assert_eq!(&a[57..65], &[0, 0, 0, 0, 1, 0, 0, 0]);
        let desc = 65 + 4 + 7 + 4 + 16 + 4;
        let grid_pos = i64::from_le_bytes(a[desc..desc + 8].try_into().unwrap());
        let end_pos = i64::from_le_bytes(a[desc + 16..desc + 24].try_into().unwrap());
        assert_eq!(grid_pos as usize, desc + 24);
        assert_eq!(end_pos as usize, a.len());
        // A different value gives a different UUID.
        let g2 = grid_with(&[(IVec3::new(1, 2, 3), 0.25), (IVec3::new(-100, 7, 9000), 2.0)]);
        let c = write_vdb_bytes(&[GridRef::Float(&g2)], &WriteOptions::default()).unwrap();
        assert_ne!(&a[21..57], &c[21..57]);
    }

    #[test]
    fn transform_bytes_match_openvdb() {
        let mut out = Vec::new();
        write_transform(&mut out, 0.3, [1.0, 2.0, 3.0]);
        assert_eq!(out.len(), 4 + 24 + 144);
        let f = |i: usize| f64::from_le_bytes(out[28 + 8 * i..36 + 8 * i].try_into().unwrap());
        assert_eq!((f(0), f(1), f(2)), (1.0, 2.0, 3.0));
        assert_eq!(f(3), 0.3);
        let inv = 1.0 / 0.3;
        assert_eq!(f(9), inv);
        assert_eq!(f(12), inv * inv);
        assert_eq!(f(15), inv / 2.0);
    }

    #[test]
    fn bad_values_are_refused_with_grid_and_voxel() {
        let mut g = grid_with(&[(IVec3::new(1, 2, 3), 0.5)]);
        g.set(IVec3::new(-9, 4, 100), f32::NAN);
        let e = write_vdb_bytes(&[GridRef::Float(&g)], &WriteOptions::default()).unwrap_err();
        let msg = e.to_string();
        assert!(msg.contains("`density`") && msg.contains("(-9, 4, 100)") && msg.contains("NaN"), "{msg}");
        let mut g = grid_with(&[]);
        g.set(IVec3::new(0, 0, 0), f32::INFINITY);
        assert!(matches!(write_vdb_bytes(&[GridRef::Float(&g)], &WriteOptions::default()), Err(VdbWriteError::NonFinite { .. })));
        let mut e = Grid::new("emission", [0.0f32; 3], Transform::new(1.0, DVec3::ZERO));
        e.set(IVec3::new(3, -4, 5), [1.0, 70000.0, 0.0]);
        let opts = WriteOptions { half: vec!["emission".into()], ..Default::default() };
        let err = write_vdb_bytes(&[GridRef::Vec3(&e)], &opts).unwrap_err();
        assert!(matches!(err, VdbWriteError::HalfOverflow { ref grid, ijk: [3, -4, 5], .. } if grid == "emission"), "{err}");
        // 65504 itself is the largest half and is accepted.
        e.set(IVec3::new(3, -4, 5), [1.0, 65504.0, -65504.0]);
        assert!(write_vdb_bytes(&[GridRef::Vec3(&e)], &opts).is_ok());
        // Full-float storage of the same grid is fine with large values.
        e.set(IVec3::new(3, -4, 5), [1.0, 7.0e5, 0.0]);
        assert!(write_vdb_bytes(&[GridRef::Vec3(&e)], &WriteOptions::default()).is_ok());
    }

    #[test]
    fn option_errors() {
        let g = grid_with(&[(IVec3::ZERO, 1.0)]);
        let opts = WriteOptions { half: vec!["nope".into()], ..Default::default() };
        assert!(matches!(write_vdb_bytes(&[GridRef::Float(&g)], &opts), Err(VdbWriteError::UnknownHalfGrid(_))));
        let opts = WriteOptions { metadata: vec![("name".into(), MetaValue::Bool(true))], ..Default::default() };
        assert!(matches!(write_vdb_bytes(&[GridRef::Float(&g)], &opts), Err(VdbWriteError::ReservedMetadata(_))));
        assert!(matches!(write_vdb_bytes(&[GridRef::Float(&g), GridRef::Float(&g)], &Default::default()), Err(VdbWriteError::BadName(_))));
        let mut bad = g.clone();
        bad.transform.voxel_size = 0.0;
        assert!(matches!(write_vdb_bytes(&[GridRef::Float(&bad)], &Default::default()), Err(VdbWriteError::BadTransform { .. })));
    }

    /// The mask-derived leaf bbox equals brute force over random masks.
    #[test]
    fn leaf_bbox_from_mask_matches_brute_force() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_pcg::Pcg64::seed_from_u64(7);
        let origin = IVec3::new(-16, 8, 4096);
        for trial in 0..500 {
            let mut leaf = Leaf::new(origin, 0.0f32);
            let k = if trial % 50 == 0 { 0 } else { rng.random_range(1..20) };
            for _ in 0..k {
                leaf.set_active(rng.random_range(0..512), true);
            }
            let mut brute: Option<(IVec3, IVec3)> = None;
            for (p, _) in leaf.iter_active() {
                brute = Some(brute.map_or((p, p), |(a, b)| (a.min(p), b.max(p))));
            }
            assert_eq!(leaf_active_bbox(origin, &leaf.mask), brute);
        }
    }
}
