//! The file readers under seeded mutation: the VDB reader (both paths, the
//! grids and the renderer's records), the EXR reader (a background image)
//! and the PNG reader (a terrain heightmap) are given small valid files
//! changed at random (bits flipped, bytes and 32- and 64-bit words set to
//! the ends of their ranges, spans cut, repeated or removed) and must answer
//! each with a value or an error: never a panic, an abort from an
//! allocation a damaged size asked for, or a hang.
//!
//! Each reader gets [`MUTATIONS`] changed files here, from fixed seeds, so
//! a failure repeats. A campaign of more is the same test with
//! `AURORA_FUZZ_MUTATIONS=N` (and `AURORA_FUZZ_SEED=S` for other files):
//! `benchmarks/fuzz/campaign.sh` runs 100000 per reader and prints the
//! counts and the time.

use aurora::grid::{Grid, Transform};
use aurora::io::vdb::write::{write_vdb_bytes, GridRef, WriteOptions};
use aurora::render::{Heightfield, Image, RenderStats};
use aurora::scene::{Compression, Terrain};
use glam::{DVec3, IVec3};
use rand::{Rng, SeedableRng};
use std::path::Path;
use std::time::{Duration, Instant};

/// Changed files per reader in the test suite (about 10 s in all in a
/// release build).
const MUTATIONS: usize = 2_000;

/// The longest one reader may take on one file.
const PER_FILE: Duration = Duration::from_secs(5);

fn mutations() -> usize {
    std::env::var("AURORA_FUZZ_MUTATIONS").ok().and_then(|v| v.parse().ok()).unwrap_or(MUTATIONS)
}

fn base_seed() -> u64 {
    std::env::var("AURORA_FUZZ_SEED").ok().and_then(|v| v.parse().ok()).unwrap_or(0x5eed)
}

/// Words a damaged size or count is likely to hold.
const EXTREMES32: [u32; 8] = [0, 1, 0x7fff_ffff, 0x8000_0000, 0xffff_ffff, 0x0001_0000, 0x00ff_ffff, 0xffff_fffe];
const EXTREMES64: [u64; 6] = [0, u64::MAX, i64::MAX as u64, 1 << 40, 1 << 32, 0x8000_0000_0000_0000];

/// One random change of `base` (one to four edits).
fn mutate(base: &[u8], rng: &mut rand_pcg::Pcg64) -> Vec<u8> {
    let mut b = base.to_vec();
    for _ in 0..rng.random_range(1..=4) {
        if b.is_empty() {
            break;
        }
        let at = rng.random_range(0..b.len());
        match rng.random_range(0..8) {
            0 => b[at] ^= 1 << rng.random_range(0..8),
            1 => b[at] = [0u8, 0xff, 0x7f, 0x80, 1][rng.random_range(0..5)],
            2 | 3 => {
                let v = EXTREMES32[rng.random_range(0..EXTREMES32.len())].to_le_bytes();
                let n = v.len().min(b.len() - at);
                b[at..at + n].copy_from_slice(&v[..n]);
            }
            4 => {
                let v = EXTREMES64[rng.random_range(0..EXTREMES64.len())].to_le_bytes();
                let n = v.len().min(b.len() - at);
                b[at..at + n].copy_from_slice(&v[..n]);
            }
            5 => b.truncate(at),
            6 => {
                let end = (at + rng.random_range(1..64)).min(b.len());
                let span = b[at..end].to_vec();
                b.splice(at..at, span);
            }
            _ => {
                let end = (at + rng.random_range(1..64)).min(b.len());
                b.drain(at..end);
            }
        }
    }
    b
}

/// Runs `read` on [`mutations`] changes of each of `bases`, each in its
/// own unwinding scope, timed; panics naming the first seed that panicked
/// or took longer than [`PER_FILE`]. Returns (files read, files refused).
fn campaign(what: &str, bases: &[Vec<u8>], read: impl Fn(&[u8]) -> bool) -> (usize, usize) {
    let n = mutations();
    let seed0 = base_seed();
    let (mut ok, mut refused) = (0, 0);
    let start = Instant::now();
    for i in 0..n {
        let seed = seed0.wrapping_mul(1_000_003).wrapping_add(i as u64);
        let mut rng = rand_pcg::Pcg64::seed_from_u64(seed);
        let base = &bases[i % bases.len()];
        let bytes = mutate(base, &mut rng);
        let t = Instant::now();
        let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| read(&bytes)));
        let took = t.elapsed();
        match r {
            Ok(true) => ok += 1,
            Ok(false) => refused += 1,
            Err(_) => panic!("{what}: mutation {i} (seed {seed}, base {}) panicked", i % bases.len()),
        }
        assert!(took < PER_FILE, "{what}: mutation {i} (seed {seed}) took {took:?}");
    }
    eprintln!("{what}: {n} mutations, {ok} read, {refused} refused, {:.1} s", start.elapsed().as_secs_f64());
    (ok, refused)
}

fn vdb_bases() -> Vec<Vec<u8>> {
    let mut d = Grid::new("density", 0.0f32, Transform::new(0.5, DVec3::new(1.0, 2.0, 3.0)));
    let mut e = Grid::new("emission", [0.0f32; 3], Transform::new(0.5, DVec3::new(1.0, 2.0, 3.0)));
    for (i, p) in [IVec3::new(-1, 2, 3), IVec3::new(4096, 0, -5), IVec3::new(9, 9, 9), IVec3::new(10, 9, 9)].into_iter().enumerate() {
        d.set(p, 0.5 + i as f32);
        e.set(p, [i as f32, 1.0, 0.5]);
    }
    for x in 0..8 {
        for y in 0..8 {
            d.set(IVec3::new(16 + x, 16 + y, 16), 0.1 * (x + y) as f32);
        }
    }
    [Compression::None, Compression::Zip, Compression::ActiveMask, Compression::Blosc]
        .into_iter()
        .flat_map(|comp| {
            [false, true].map(|half| {
                let opts = WriteOptions {
                    compression: comp,
                    half: if half { vec!["emission".into()] } else { vec![] },
                    metadata: vec![],
                    ..Default::default()
                };
                write_vdb_bytes(&[GridRef::Float(&d), GridRef::Vec3(&e)], &opts).unwrap()
            })
        })
        .collect()
}

/// A scratch folder for the files the path-taking readers read.
fn scratch(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("aurora-fuzz-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[test]
fn the_vdb_readers_answer_every_changed_file() {
    let bases = vdb_bases();
    for b in &bases {
        assert!(aurora::io::vdb::read::read_vdb_bytes(b).is_ok());
    }
    let (ok, refused) = campaign("vdb", &bases, |bytes| {
        let grids = aurora::io::vdb::read::read_vdb_bytes_for_render(bytes).is_ok();
        let records = aurora::app::vdb_for_render::read_render_medium_bytes(bytes, 1.0, 1.0).is_ok();
        grids && records
    });
    // The changes reach past the header: both verdicts occur.
    assert!(ok > 0 && refused > 0, "{ok} read, {refused} refused");
}

#[test]
fn the_exr_reader_answers_every_changed_file() {
    let d = scratch("exr");
    let mut bases = Vec::new();
    for (w, h) in [(7, 5), (64, 3), (3, 70)] {
        let pixels = (0..w * h).map(|i| [i as f32 * 0.01, 0.5, 1.0 - i as f32 * 0.001, 1.0]).collect();
        let img = Image { width: w, height: h, pixels, stats: RenderStats::default() };
        let p = d.join(format!("base-{w}x{h}.exr"));
        aurora::render::image_file::write_exr(&p, &img).unwrap();
        bases.push(std::fs::read(&p).unwrap());
    }
    let p = d.join("changed.exr");
    let (ok, refused) = campaign("exr", &bases, |bytes| {
        std::fs::write(&p, bytes).unwrap();
        aurora::render::image_file::read_exr(&p).is_ok()
    });
    assert!(ok > 0 && refused > 0, "{ok} read, {refused} refused");
    std::fs::remove_dir_all(&d).unwrap();
}

fn png_grey(path: &Path, w: u32, h: u32, sixteen: bool) -> Vec<u8> {
    let f = std::fs::File::create(path).unwrap();
    let mut enc = png::Encoder::new(std::io::BufWriter::new(f), w, h);
    enc.set_color(png::ColorType::Grayscale);
    enc.set_depth(if sixteen { png::BitDepth::Sixteen } else { png::BitDepth::Eight });
    let n = (w * h) as usize * if sixteen { 2 } else { 1 };
    let data: Vec<u8> = (0..n).map(|i| (i * 37 % 251) as u8).collect();
    let mut wr = enc.write_header().unwrap();
    wr.write_image_data(&data).unwrap();
    wr.finish().unwrap();
    std::fs::read(path).unwrap()
}

#[test]
fn the_png_reader_answers_every_changed_file() {
    let d = scratch("png");
    let bases = vec![png_grey(&d.join("a.png"), 9, 7, false), png_grey(&d.join("b.png"), 5, 12, true)];
    let terrain = Terrain::default();
    let p = d.join("changed.png");
    let (ok, refused) = campaign("png", &bases, |bytes| {
        std::fs::write(&p, bytes).unwrap();
        Heightfield::from_heightmap(&p, &terrain).is_ok()
    });
    assert!(ok > 0 && refused > 0, "{ok} read, {refused} refused");
    std::fs::remove_dir_all(&d).unwrap();
}
