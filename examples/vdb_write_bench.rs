//! VDB write benchmark: aurora's writer against OpenVDB's own (libopenvdb via
//! `benchmarks/vdb_write/openvdb_write_bench.cpp`), same grids, same compression, same
//! half-float setting; reports time ratio and file sizes.
//!
//! ```text
//! cargo run --release --example vdb_write_bench -- [--input BAKE.vdb] [--repeat N]
//!     [--threads N] [--half GRID]... [--modes none,zip,active-mask,zip+active-mask,blosc,blosc+active-mask]
//!     [--out-dir DIR]
//! ```
//!
//! Without `--input` it synthesises a `density` + `emission` pair of about
//! 1M active voxels each (curtain-like sheets with smooth profiles and a
//! little deterministic noise, so zlib sees realistic float data). With
//! `--input` (e.g. the default bake's `aurora.vdb`) it benchmarks those grids.
//! Each write is timed end to end (encode + write the file); the two writers
//! alternate run by run and the best of `--repeat` runs is compared. Prints a
//! table and CSV lines
//! (`csv,mode,voxels,threads,aurora_best,aurora_median,openvdb_best,openvdb_median,aurora_bytes,openvdb_bytes`).

use aurora::app::bench::vdb_write_timing::{bench_write, BenchWrite};
use aurora::grid::{Grid, Transform};
use aurora::io::vdb::read::read_vdb;
use aurora::io::vdb::write::{GridRef, WriteOptions};
use aurora::scene::Compression;
use aurora::util::fmath;
use glam::{DVec3, IVec3};
use std::path::{Path, PathBuf};
use std::process::Command;

#[path = "../tests/common/openvdb_tool.rs"]
mod openvdb_tool;

use openvdb_tool::mode_name;

struct Args {
    input: Option<PathBuf>,
    repeat: usize,
    threads: usize,
    half: Vec<String>,
    modes: Vec<Compression>,
    out_dir: PathBuf,
}

fn parse_args() -> anyhow::Result<Args> {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let mut a = Args {
        input: None,
        repeat: 5,
        threads: 0,
        half: Vec::new(),
        modes: vec![Compression::None, Compression::Zip, Compression::ActiveMask, Compression::ZipActiveMask],
        out_dir: root.join("target/vdb-bench"),
    };
    let mut it = std::env::args().skip(1);
    while let Some(arg) = it.next() {
        let mut val = || it.next().ok_or_else(|| anyhow::anyhow!("{arg} needs a value"));
        match arg.as_str() {
            "--input" => a.input = Some(PathBuf::from(val()?)),
            "--repeat" => a.repeat = val()?.parse()?,
            "--threads" => a.threads = val()?.parse()?,
            "--half" => a.half.push(val()?),
            "--out-dir" => a.out_dir = PathBuf::from(val()?),
            "--modes" => {
                a.modes = val()?
                    .split(',')
                    .map(|m| match m {
                        "none" => Ok(Compression::None),
                        "zip" => Ok(Compression::Zip),
                        "active-mask" => Ok(Compression::ActiveMask),
                        "zip+active-mask" => Ok(Compression::ZipActiveMask),
                        "blosc" => Ok(Compression::Blosc),
                        "blosc+active-mask" => Ok(Compression::BloscActiveMask),
                        other => Err(anyhow::anyhow!("unknown mode {other}")),
                    })
                    .collect::<anyhow::Result<_>>()?
            }
            other => anyhow::bail!("unknown argument {other}"),
        }
    }
    Ok(a)
}

/// Deterministic noise in [0, 1) from a voxel coordinate (a hash, no RNG state).
fn noise(p: IVec3, salt: u32) -> f32 {
    let mut h =
        (p.x as u32).wrapping_mul(0x8DA6_B343) ^ (p.y as u32).wrapping_mul(0xD816_3841) ^ (p.z as u32).wrapping_mul(0xCB1A_B31F) ^ salt;
    h ^= h >> 15;
    h = h.wrapping_mul(0x2C1B_3C6D);
    h ^= h >> 12;
    (h >> 8) as f32 / (1u32 << 24) as f32
}

/// Two sinuous curtains, 10 voxels thick, 100 tall, ~1M active voxels per grid.
fn synthetic() -> (Grid<f32>, Grid<[f32; 3]>) {
    let tr = Transform::new(0.05, DVec3::new(-25.0, -10.0, 95.0));
    let mut d = Grid::new("density", 0.0f32, tr);
    let mut e = Grid::new("emission", [0.0f32; 3], tr);
    for (c, (y_base, amp)) in [(200.0f64, 60.0f64), (-150.0, 40.0)].into_iter().enumerate() {
        for x in -250..250 {
            let y0 = (y_base + amp * fmath::sin(x as f64 / (80.0 + 20.0 * c as f64))).round() as i32;
            for dy in -5..5 {
                for z in 0..100 {
                    let p = IVec3::new(x, y0 + dy, z);
                    let h = z as f32 / 100.0;
                    let across = 1.0 - (dy as f32 + 0.5).abs() / 5.5;
                    let n = 1.0 + 0.05 * (noise(p, 1) - 0.5);
                    d.set(p, 0.02 * fmath::exp(-3.0 * h) * n);
                    let green = across * fmath::exp(-fmath::powi((h - 0.3) / 0.2, 2)) * n;
                    let red = across * 0.3 * h * h * (1.0 + 0.05 * (noise(p, 2) - 0.5));
                    e.set(p, [red * 1e-3, green * 1e-3, 0.05 * green * 1e-3]);
                }
            }
        }
    }
    (d, e)
}

/// Runs OpenVDB's writer on `input` with the same settings; returns (best s, bytes).
fn openvdb_write(tool: &Path, input: &Path, out: &Path, mode: Compression, half: &[String], repeat: usize) -> anyhow::Result<(f64, u64)> {
    let mut cmd = Command::new(tool);
    cmd.arg(input).arg(out).arg(mode_name(mode)).args(["--repeat", &repeat.to_string()]);
    for h in half {
        cmd.args(["--half", h]);
    }
    let o = cmd.output()?;
    anyhow::ensure!(o.status.success(), "openvdb_write_bench failed: {}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout)?;
    Ok((v["best"].as_f64().unwrap_or(f64::NAN), v["bytes"].as_u64().unwrap_or(0)))
}

fn main() -> anyhow::Result<()> {
    let args = parse_args()?;
    std::fs::create_dir_all(&args.out_dir)?;
    let (floats, vec3s) = match &args.input {
        Some(p) => {
            let f = read_vdb(p)?;
            (f.float_grids, f.vec3_grids)
        }
        None => {
            let (d, e) = synthetic();
            (vec![d], vec![e])
        }
    };
    let grids: Vec<GridRef> = floats.iter().map(GridRef::Float).chain(vec3s.iter().map(GridRef::Vec3)).collect();
    let voxels: u64 = floats.iter().map(|g| g.active_voxel_count()).chain(vec3s.iter().map(|g| g.active_voxel_count())).sum();
    let leaves: usize = floats.iter().map(|g| g.leaf_count()).chain(vec3s.iter().map(|g| g.leaf_count())).sum();
    let pool = rayon::ThreadPoolBuilder::new().num_threads(args.threads).build()?;
    let threads = pool.current_num_threads();
    println!(
        "grids: {} ({} active voxels, {} leaves); aurora threads: {threads}; half: {:?}; best of {} runs",
        grids.iter().map(|g| g.name()).collect::<Vec<_>>().join(", "),
        voxels,
        leaves,
        args.half,
        args.repeat
    );
    let tool = openvdb_tool::build(Path::new(env!("CARGO_MANIFEST_DIR"))).map_err(anyhow::Error::msg)?;
    println!("{:<16} {:>10} {:>10} {:>7} {:>12} {:>12} {:>7}", "mode", "aurora s", "openvdb s", "ratio", "aurora B", "openvdb B", "size");
    for &mode in &args.modes {
        let opts = WriteOptions { compression: mode, half: args.half.clone(), metadata: vec![], ..Default::default() };
        let ours_path = args.out_dir.join(format!("aurora_{}.vdb", mode_name(mode)));
        // Alternate the two writers run by run so that load from other
        // processes on the machine hits both alike; compare the best runs.
        let theirs_path = args.out_dir.join(format!("openvdb_{}.vdb", mode_name(mode)));
        let (mut ours_s, mut theirs_s) = (Vec::new(), Vec::new());
        let (mut ours_bytes, mut t_bytes) = (0, 0);
        for _ in 0..args.repeat.max(1) {
            let r = pool.install(|| bench_write(&ours_path, &grids, &opts, 1))?;
            ours_s.push(r.best());
            ours_bytes = r.bytes;
            let (t, b) = openvdb_write(&tool, &ours_path, &theirs_path, mode, &args.half, 1)?;
            theirs_s.push(t);
            t_bytes = b;
        }
        let best = |v: &[f64]| v.iter().copied().fold(f64::INFINITY, f64::min);
        let median = |v: &[f64]| {
            let mut v = v.to_vec();
            v.sort_by(f64::total_cmp);
            v[v.len() / 2]
        };
        let ours = BenchWrite { seconds: ours_s.clone(), bytes: ours_bytes };
        let t_best = best(&theirs_s);
        let t_median = median(&theirs_s);
        println!(
            "{:<16} {:>10.4} {:>10.4} {:>7.3} {:>12} {:>12} {:>7.4}",
            mode_name(mode),
            ours.best(),
            t_best,
            ours.best() / t_best,
            ours.bytes,
            t_bytes,
            ours.bytes as f64 / t_bytes as f64
        );
        println!(
            "csv,{},{},{},{:.6},{:.6},{:.6},{:.6},{},{}",
            mode_name(mode),
            voxels,
            threads,
            ours.best(),
            ours.median(),
            t_best,
            t_median,
            ours.bytes,
            t_bytes
        );
    }
    Ok(())
}
