//! Damaged VDB files, made from small valid files of our writer: the one
//! list both readers (the grid reader and the renderer's records path) are
//! run on (`tests/vdb/verdicts.rs`), and the generators the grid reader's
//! own corruption tests use (`tests/vdb/roundtrip.rs`).
//!
//! Kinds of damage: truncations (with the descriptor's offsets left alone
//! or patched to the cut), corrupt ZIP payloads and checksums, corrupt or
//! zeroed Blosc (LZ4) payloads, wrong chunk lengths and Blosc header sizes,
//! invalid record metadata, leaf masks whose buffer copy differs from the
//! topology, repeated, unaligned and active root tiles (duplicate leaf
//! origins, tiles beyond the reader's limit), negative and NaN voxels, and
//! seeded random byte changes. Every kind is applied to each grid of a
//! four-grid file (the renderer's `density` and `emission`, and a float
//! `temperature` and vec3 `velocity` it does not use), in every
//! compression mode, full and half float.

use super::modes;
use aurora::grid::{Grid, Transform};
use aurora::io::vdb::parse::{parse_file_with, read_meta_map, Cursor, Decode, LeafSpan, ValueKind};
use aurora::io::vdb::write::{write_vdb_bytes, GridRef, WriteOptions};
use aurora::scene::Compression;
use aurora::util::fmath;
use glam::{DVec3, IVec3};
use rand::{Rng, SeedableRng};

/// What a damaged file must do.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Expect {
    /// Both readers refuse it.
    Refused,
    /// Both read it (an undamaged control, or damage to values only).
    Read,
    /// Either, as long as both readers agree (random changes, truncations
    /// of value bytes that the format cannot tell from values).
    Agree,
}

/// One damaged file.
pub struct Damaged {
    /// The base file and the damage, e.g. `Zip half: temperature: zip checksum`.
    pub name: String,
    pub bytes: Vec<u8>,
    pub expect: Expect,
    /// A text a refusal must contain on both paths (empty: any).
    pub message: &'static str,
}

/// A small valid file with `density` and `emission`, a few voxels, in the
/// given mode (emission as half floats if `half`).
pub fn small_file(comp: Compression, half: bool) -> Vec<u8> {
    let mut d = Grid::new("density", 0.0f32, Transform::new(0.5, DVec3::new(1.0, 2.0, 3.0)));
    let mut e = Grid::new("emission", [0.0f32; 3], Transform::new(0.5, DVec3::new(1.0, 2.0, 3.0)));
    for (i, p) in [IVec3::new(-1, 2, 3), IVec3::new(4096, 0, -5), IVec3::new(9, 9, 9), IVec3::new(10, 9, 9)].into_iter().enumerate() {
        d.set(p, 0.5 + i as f32);
        e.set(p, [i as f32, 1.0, -0.5]);
    }
    let opts = WriteOptions {
        compression: comp,
        half: if half { vec!["emission".into()] } else { vec![] },
        metadata: vec![],
        ..Default::default()
    };
    write_vdb_bytes(&[GridRef::Float(&d), GridRef::Vec3(&e)], &opts).unwrap()
}

/// A renderable file of four grids: `density` and `emission` (what the
/// renderer uses) and `temperature` (float) and `velocity` (vec3, with
/// negative components) that it does not. Each grid has a fully active
/// leaf of smooth values (its ZIP and Blosc streams really compress), a
/// sheet, and a single voxel in another root child. `half`:
/// emission and velocity as half floats.
pub fn four_grids(comp: Compression, half: bool) -> Vec<u8> {
    let tr = Transform::new(0.5, DVec3::new(-2.0, 1.0, 90.0));
    let mut d = Grid::new("density", 0.0f32, tr);
    let mut t = Grid::new("temperature", 0.0f32, tr);
    let mut e = Grid::new("emission", [0.0f32; 3], tr);
    let mut v = Grid::new("velocity", [0.0f32; 3], tr);
    let dense = |g: usize, origin: IVec3| -> Vec<(IVec3, f32)> {
        (0..512).map(|n| (origin + aurora::grid::offset_to_local(n), 0.25 + 0.01 * (n / 8) as f32 + g as f32)).collect()
    };
    for (p, x) in dense(0, IVec3::new(8, 0, 16)) {
        d.set(p, x);
        t.set(p - IVec3::X * 16, 200.0 + x);
        e.set(p, [x, 0.5 * x, 0.25]);
        v.set(p + IVec3::Z * 8, [x, -x, 1.0]);
    }
    for i in -6..6 {
        for k in 0..12 {
            let x = fmath::exp(-(k as f32) / 5.0) * (1.0 + 0.05 * i as f32);
            let p = IVec3::new(i, 3, 40 + k);
            d.set(p, x);
            t.set(p, 300.0 * x);
            e.set(p, [0.1 * x, x, 0.0]);
            v.set(p, [-x, 0.0, x]);
        }
    }
    let p = IVec3::new(-4097, 5, 9);
    d.set(p, 1.5);
    t.set(p, 250.0);
    e.set(p, [0.0, 2.0, 1.0]);
    v.set(p, [1.0, -1.0, 0.5]);
    let opts = WriteOptions {
        compression: comp,
        half: if half { vec!["emission".into(), "velocity".into()] } else { vec![] },
        metadata: vec![],
        ..Default::default()
    };
    write_vdb_bytes(&[GridRef::Float(&d), GridRef::Float(&t), GridRef::Vec3(&e), GridRef::Vec3(&v)], &opts).unwrap()
}

/// Where one grid lies in a file, from our parser (the files here are
/// valid, so it can be trusted to find things).
pub struct GridAt {
    pub name: String,
    pub comps: usize,
    pub half: bool,
    pub grid_pos: usize,
    pub block_pos: usize,
    pub end_pos: usize,
    pub spans: Vec<LeafSpan>,
}

/// Every grid of a valid file, in file order.
pub fn grids_of(bytes: &[u8]) -> Vec<GridAt> {
    let parsed = parse_file_with(bytes, &|_| Decode::Locate).expect("a valid base file");
    parsed
        .grids
        .into_iter()
        .map(|g| {
            let spans = match &g.tree {
                Some(aurora::io::vdb::parse::AnyTree::Float(t)) => t.spans.clone(),
                Some(aurora::io::vdb::parse::AnyTree::Vec3(t)) => t.spans.clone(),
                None => Vec::new(),
            };
            GridAt {
                name: g.header.name(),
                comps: if g.header.kind == Some(ValueKind::Vec3) { 3 } else { 1 },
                half: g.header.half,
                grid_pos: g.header.grid_pos as usize,
                block_pos: g.header.block_pos as usize,
                end_pos: g.header.end_pos as usize,
                spans,
            }
        })
        .collect()
}

fn i64_at(b: &[u8], at: usize) -> i64 {
    i64::from_le_bytes(b[at..at + 8].try_into().unwrap())
}

fn put_i64(b: &mut [u8], at: usize, v: i64) {
    b[at..at + 8].copy_from_slice(&v.to_le_bytes());
}

fn u32_at(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes(b[at..at + 4].try_into().unwrap())
}

/// Offset of a grid's descriptor offsets (gridPos, blockPos, endPos): the
/// 24 bytes just before its data, as OpenVDB and our writer lay them out.
pub fn descriptor_offsets_at(b: &[u8], g: &GridAt) -> usize {
    let at = g.grid_pos - 24;
    assert_eq!(i64_at(b, at) as usize, g.grid_pos, "descriptor of `{}`", g.name);
    at
}

/// A leaf record's compressed chunk: offset of its `i64` length, and the
/// length (the record's metadata byte, stored inactive values and
/// selection mask skipped as `codec` lays them out).
fn chunk_of(b: &[u8], span: &LeafSpan, comps: usize) -> (usize, i64) {
    let m = b[span.start];
    let n_inactive = match m {
        2 | 4 => 1,
        5 => 2,
        _ => 0,
    };
    let mut at = span.start + 1 + n_inactive * 4 * comps;
    if matches!(m, 3..=5) {
        at += 64;
    }
    (at, i64_at(b, at))
}

/// The leaf record of `g` with the longest compressed chunk (the fully
/// active leaf): the chunk's offset and length.
fn longest_chunk(b: &[u8], g: &GridAt) -> (usize, i64) {
    g.spans.iter().map(|s| chunk_of(b, s, g.comps)).max_by_key(|c| c.1).expect("a leaf")
}

/// `b` with root tiles (origin, active) inserted in grid `name`'s root,
/// tile count and every offset after them patched: the file stays
/// consistent but for what the tiles themselves say. Tile values are 1.
pub fn with_root_tiles(b: &[u8], name: &str, tiles: &[(IVec3, bool)]) -> Vec<u8> {
    let grids = grids_of(b);
    let k = grids.iter().position(|g| g.name == name).expect("grid present");
    let g = &grids[k];
    let mut cur = Cursor::new(b);
    cur.seek(g.grid_pos as u64 + 4).unwrap();
    read_meta_map(&mut cur).unwrap();
    let map = cur.string().unwrap();
    assert_eq!(map, "UniformScaleTranslateMap", "our writer's map");
    // Six DVec3 map fields, the buffer count, the background.
    let count_at = cur.pos() + 6 * 24 + 4 + 4 * g.comps;
    let mut ins = Vec::new();
    for &(o, active) in tiles {
        for c in [o.x, o.y, o.z] {
            ins.extend_from_slice(&c.to_le_bytes());
        }
        for _ in 0..g.comps {
            ins.extend_from_slice(&1.0f32.to_le_bytes());
        }
        ins.push(u8::from(active));
    }
    // Tiles precede the children (OpenVDB `RootNode::readTopology`).
    let existing = u32_at(b, count_at) as usize;
    let tiles_at = count_at + 8 + existing * (12 + 4 * g.comps + 1);
    let mut out = b[..tiles_at].to_vec();
    out.extend_from_slice(&ins);
    out.extend_from_slice(&b[tiles_at..]);
    out[count_at..count_at + 4].copy_from_slice(&((existing + tiles.len()) as u32).to_le_bytes());
    let shift = ins.len() as i64;
    let at = descriptor_offsets_at(b, g);
    put_i64(&mut out, at + 8, g.block_pos as i64 + shift);
    put_i64(&mut out, at + 16, g.end_pos as i64 + shift);
    for later in &grids[k + 1..] {
        let at = descriptor_offsets_at(b, later) + shift as usize;
        for (i, v) in [later.grid_pos, later.block_pos, later.end_pos].into_iter().enumerate() {
            put_i64(&mut out, at + 8 * i, v as i64 + shift);
        }
    }
    out
}

/// The origin of grid `name`'s first root child.
fn first_root_child(b: &[u8], name: &str) -> IVec3 {
    let g = grids_of(b).into_iter().find(|g| g.name == name).unwrap();
    let o = g.spans[0].origin;
    IVec3::new(o.x & !4095, o.y & !4095, o.z & !4095)
}

/// The lengths of `n` bytes that [`truncations`] keeps: every length up
/// to 64 KiB (header, metadata, descriptors and the first tree nodes) and
/// over the last 4 KiB, a stride of 61 (prime, so it hits every field
/// alignment) in between.
pub fn truncation_lengths(n: usize) -> impl Iterator<Item = usize> {
    (0..n).filter(move |&l| l < 65536 || l + 4096 >= n || l % 61 == 0)
}

/// Where [`cut_body`] cuts the last grid's body: every cut in the
/// metadata, transform, first topology bytes and the whole buffers, a
/// stride of 7 (prime: all field alignments) through the long runs of node
/// masks in between.
pub fn body_cuts(full: &[u8]) -> Vec<usize> {
    let grids = grids_of(full);
    let g = grids.last().expect("a grid");
    assert_eq!(g.end_pos, full.len());
    (g.grid_pos..full.len()).filter(|&c| c < g.grid_pos + 2048 || c + 64 >= g.block_pos || (c - g.grid_pos).is_multiple_of(7)).collect()
}

/// `full` truncated at `cut` inside its last grid's body, with the grid's
/// descriptor offsets patched to the cut, so a parser gets past the offset
/// check and must catch the missing bytes in the metadata, transform,
/// topology or buffers themselves.
pub fn cut_body(full: &[u8], cut: usize) -> Vec<u8> {
    let grids = grids_of(full);
    let g = grids.last().expect("a grid");
    let offsets_at = descriptor_offsets_at(full, g);
    let mut b = full[..cut].to_vec();
    put_i64(&mut b, offsets_at + 8, g.block_pos.min(cut) as i64);
    put_i64(&mut b, offsets_at + 16, cut as i64);
    b
}

/// About `k` lengths spread evenly over `0..n`, the first `head` and the
/// last 64 (the end of the last record).
fn sampled(n: usize, k: usize, head: usize) -> Vec<usize> {
    let mut v: Vec<usize> = (0..n).step_by((n / k).max(1)).chain(0..n.min(head)).chain(n.saturating_sub(64)..n).collect();
    v.sort_unstable();
    v.dedup();
    v
}

/// `trials` copies of `full`, each with one to three bytes replaced by
/// seeded random values.
pub fn random_changes(full: &[u8], seed: u64, trials: usize) -> Vec<Vec<u8>> {
    let mut rng = rand_pcg::Pcg64::seed_from_u64(seed);
    (0..trials)
        .map(|_| {
            let mut b = full.to_vec();
            for _ in 0..rng.random_range(1..=3) {
                let at = rng.random_range(0..b.len());
                b[at] = rng.random();
            }
            b
        })
        .collect()
}

/// The damages of one grid `g` of `base` (a [`four_grids`] file in mode
/// `comp`). Damage to a grid the renderer does not use must be refused
/// all the same: the grid reader refuses it.
fn grid_damages(base: &[u8], comp: Compression, g: &GridAt, out: &mut Vec<(String, Vec<u8>, Expect, &'static str)>) {
    let zip = matches!(comp, Compression::Zip | Compression::ZipActiveMask);
    let blosc = matches!(comp, Compression::Blosc | Compression::BloscActiveMask);
    let mut push = |what: &str, b: Vec<u8>, e: Expect, m: &'static str| out.push((format!("{}: {what}", g.name), b, e, m));
    if zip || blosc {
        let (at, len) = longest_chunk(base, g);
        assert!(len > 0, "`{}`: the dense leaf's stream is compressed", g.name);
        let (s, l) = (at + 8, len as usize);
        let mut b = base.to_vec();
        b[s + l / 2] ^= 0x5a;
        // A flipped byte inside an LZ4 literal run decodes to other values
        // (Blosc frames carry no checksum); zlib's Adler-32 catches it.
        push("payload byte flipped", b, if zip { Expect::Refused } else { Expect::Agree }, "");
        let mut b = base.to_vec();
        put_i64(&mut b, at, len + 1);
        push("chunk length + 1", b, Expect::Refused, "");
        let mut b = base.to_vec();
        put_i64(&mut b, at, -(len - 1));
        push("raw chunk of the wrong size", b, Expect::Refused, "");
        if zip {
            let mut b = base.to_vec();
            b[s + l - 1] ^= 0x01;
            push("zip checksum", b, Expect::Refused, "zip chunk");
            let mut b = base.to_vec();
            b[s] ^= 0x01; // CMF: compression method 9, not deflate's 8
            push("zip header", b, Expect::Refused, "zip chunk");
        } else {
            // Frame: 16-byte header, one u32 block start, then per split
            // an i32 compressed size and the LZ4 data.
            let mut b = base.to_vec();
            b[s + 24..s + l].fill(0);
            push("LZ4 payload zeroed", b, Expect::Refused, "Blosc");
            let mut b = base.to_vec();
            b[s + 20..s + 24].copy_from_slice(&1i32.to_le_bytes());
            push("LZ4 split size 1", b, Expect::Refused, "Blosc");
            let mut b = base.to_vec();
            let nbytes = u32_at(base, s + 4);
            b[s + 4..s + 8].copy_from_slice(&(nbytes + 4).to_le_bytes());
            push("Blosc header size", b, Expect::Refused, "Blosc");
        }
    }
    let span = g.spans[0];
    let mut b = base.to_vec();
    b[span.start] = 7;
    push("metadata byte 7", b, Expect::Refused, "metadata byte");
    let mut b = base.to_vec();
    b[span.start - 64] ^= 0x10;
    push("mask copy differs", b, Expect::Refused, "mask");
    let child = first_root_child(base, &g.name);
    let free = IVec3::new(-8192, 8192, 4096 * 9);
    for (what, tiles, e, m) in [
        ("root tile on a root child", vec![(child, false)], Expect::Refused, "duplicate leaf origins"),
        ("active root tile on a root child", vec![(child, true)], Expect::Refused, "duplicate leaf origins"),
        ("two root tiles at one origin", vec![(free, false), (free, false)], Expect::Refused, "duplicate leaf origins"),
        ("unaligned root tile", vec![(free + IVec3::new(8, 0, 0), false)], Expect::Refused, "multiple of 4096"),
        ("active root tile", vec![(free, true)], Expect::Refused, "active tiles cover"),
        ("inactive root tile", vec![(free, false)], Expect::Read, ""),
    ] {
        push(what, with_root_tiles(base, &g.name, &tiles), e, m);
    }
}

/// Voxel damage the format cannot see (a value is a value): negative and
/// NaN voxels written into an uncompressed file's bytes. The renderer
/// refuses them in a grid it uses, and ignores a grid it does not.
fn value_damages(base: &[u8], g: &GridAt, out: &mut Vec<(String, Vec<u8>, Expect, &'static str)>) {
    let span = g.spans.iter().max_by_key(|s| s.mask.iter().map(|w| w.count_ones()).sum::<u32>()).unwrap();
    let used = g.name == "density" || g.name == "emission";
    // An uncompressed full leaf: the metadata byte, then the floats.
    let at = span.start + 1 + 4 * g.comps * 5;
    for (what, v) in [("negative voxel", -1.0f32), ("NaN voxel", f32::NAN)] {
        let mut b = base.to_vec();
        b[at..at + 4].copy_from_slice(&v.to_le_bytes());
        let e = if used { Expect::Refused } else { Expect::Read };
        out.push((format!("{}: {what}", g.name), b, e, ""));
    }
}

/// The shared list: every damage of every grid of [`four_grids`] in every
/// mode, full and half float, and the undamaged files; truncations of
/// them and of [`small_file`], truncated bodies with consistent offsets
/// and seeded random byte changes (these three without the Zip-only and
/// Blosc-only modes, where every internal node's values are stored in full
/// and compressed: a few ms a read, and nothing the other modes miss).
pub fn damaged_files() -> Vec<Damaged> {
    let mut out = Vec::new();
    for comp in modes() {
        for half in [false, true] {
            let base = four_grids(comp, half);
            let mut list = vec![("intact".to_string(), base.clone(), Expect::Read, "")];
            for g in grids_of(&base) {
                grid_damages(&base, comp, &g, &mut list);
                if comp == Compression::None && !g.half {
                    value_damages(&base, &g, &mut list);
                }
            }
            if !matches!(comp, Compression::Zip | Compression::Blosc) {
                let n = base.len();
                for len in sampled(n, 40, 0) {
                    list.push((format!("truncated to {len} of {n}"), base[..len].to_vec(), Expect::Refused, ""));
                }
                let cuts = body_cuts(&base);
                for &cut in cuts.iter().step_by(cuts.len() / 40) {
                    let what = format!("last grid's body cut at {cut}, offsets patched");
                    list.push((what, cut_body(&base, cut), Expect::Refused, ""));
                }
                for (i, b) in random_changes(&base, 0x5eed_0000 + out.len() as u64, 40).into_iter().enumerate() {
                    list.push((format!("random change {i}"), b, Expect::Agree, ""));
                }
            }
            let label = format!("{comp:?}{}", if half { " half" } else { "" });
            out.extend(list.into_iter().map(|(what, bytes, expect, message)| Damaged {
                name: format!("{label}: {what}"),
                bytes,
                expect,
                message,
            }));
        }
    }
    for comp in [Compression::ZipActiveMask, Compression::BloscActiveMask, Compression::None] {
        let full = small_file(comp, comp == Compression::None);
        let n = full.len();
        for len in sampled(n, 300, 256) {
            out.push(Damaged {
                name: format!("small {comp:?}: truncated to {len} of {n}"),
                bytes: full[..len].to_vec(),
                expect: Expect::Refused,
                message: "",
            });
        }
    }
    out
}
