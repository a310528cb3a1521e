//! The command line: [`args`] defines the commands and their flags, [`run`]
//! sends each to its own file, [`exit`] turns the result into the exit
//! status. Each command composes the library's stages (bake -> files, files
//! -> render) and prints what it did on stderr.

// First: its print!/eprintln! shadow std's in every module below.
#[macro_use]
pub mod out;

pub mod args;
mod bake;
mod bars;
mod bench;
mod cancel;
pub mod exit;
mod frames;
mod help;
mod keogram;
mod preview;
mod profile;
mod render;
mod render_checks;
mod scene;
mod sky;

use anyhow::Result;
use args::{Cli, Command};
use aurora::scene::Scene;
use std::path::PathBuf;

/// Runs one command.
pub fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Bake(a) => bake::run(a),
        Command::Render(a) => render::run(a),
        Command::Bench(a) => bench::run(a),
        Command::Profile(a) => profile::run(a),
        Command::Keogram(a) => keogram::run(a),
        Command::Scene(a) => scene::print(a),
        Command::Preview(a) => preview::run(a),
        Command::Footprint(a) => scene::footprint(a),
        Command::Terrain(a) => scene::terrain(a),
        Command::Sky(a) => sky::run(a),
    }
}

/// The scene a command names: a scene file or a preset, its overrides
/// applied in command-line order, validated, what it names outside itself
/// read, its curtains in magnetic coordinates placed
/// (`aurora::app::scene_input`); its warnings on stderr.
fn load_scene(arg: &str, overrides: &args::SceneOverrides) -> Result<Scene> {
    let input = aurora::app::scene_input::load(arg, overrides.in_order())?;
    print_warnings(&input.warnings);
    Ok(input.scene)
}

/// The scene as [`load_scene`] takes it, but with `[oval]` and
/// `magnetic_path` as written, not placed (what `aurora scene` prints).
fn load_scene_as_given(arg: &str, overrides: &args::SceneOverrides) -> Result<Scene> {
    let input = aurora::app::scene_input::load_as_given(arg, overrides.in_order())?;
    print_warnings(&input.warnings);
    Ok(input.scene)
}

/// The folder relative paths in a scene file are resolved against
/// (`aurora::app::scene_input::scene_dir`).
fn scene_dir(scene_arg: &str) -> PathBuf {
    aurora::app::scene_input::scene_dir(scene_arg)
}

/// Runs `f` on a thread pool of `threads` workers (default: all cores).
fn with_threads<T>(threads: Option<u64>, f: impl FnOnce() -> Result<T> + Send) -> Result<T>
where
    T: Send,
{
    let mut b = rayon::ThreadPoolBuilder::new();
    if let Some(n) = threads {
        // 1..=MAX_THREADS, checked by clap; their stacks within the limit here.
        threads_within_memory(n, &aurora::util::memory::available())?;
        b = b.num_threads(n as usize);
    }
    let pool = b.build().map_err(|e| match threads {
        Some(n) => anyhow::Error::from(exit::InputError(format!("--threads {n}: cannot start {n} threads: {e}; use fewer"))),
        None => anyhow::Error::from(e).context("cannot start the thread pool"),
    })?;
    pool.install(f)
}

/// Bytes of address space a worker thread reserves for its stack (Rust's
/// default, which rayon keeps) and its guard page, rounded up.
const THREAD_STACK_BYTES: f64 = (2u64 << 20) as f64 + 65536.0;

/// The share of the process's memory limit the workers' stacks may take.
const THREAD_STACKS_FRACTION: f64 = 0.25;

/// Refuses (exit status 2) `--threads n` when the threads' stacks would
/// take more than [`THREAD_STACKS_FRACTION`] of `limit`: under an
/// address-space cap the stacks count in full, and starting a thread beyond
/// it fails; the message names the count, the limit and the most that fit.
fn threads_within_memory(n: u64, limit: &aurora::util::memory::MemoryLimit) -> Result<()> {
    let room = limit.bytes * THREAD_STACKS_FRACTION;
    if n as f64 * THREAD_STACK_BYTES <= room {
        return Ok(());
    }
    let most = ((room / THREAD_STACK_BYTES).floor() as u64).max(1);
    Err(exit::InputError(format!(
        "--threads {n}: {n} threads' stacks would take about {} of the {limit} this process may use; use --threads {most} or fewer",
        aurora::util::memory::gib(n as f64 * THREAD_STACK_BYTES)
    ))
    .into())
}

/// Bake warnings (under-resolved kernel or curtains) on stderr, even with --quiet.
fn print_warnings(warnings: &[String]) {
    for w in warnings {
        eprintln!("aurora: warning: {w}");
    }
}
