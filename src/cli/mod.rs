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

use anyhow::{Context, Result};
use args::{Cli, Command};
use aurora::scene::Scene;
use std::path::{Path, PathBuf};

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
/// applied in command-line order, validated.
fn load_scene(arg: &str, overrides: &args::SceneOverrides) -> Result<Scene> {
    let scene = Scene::load_with(arg, overrides.in_order())?;
    // A table the scene names that is not compiled in is read now (and kept):
    // a missing or damaged one is refused before any work (exit status 2).
    aurora::physics::atmosphere::Atmosphere::of_params(&scene.atmosphere)?;
    Ok(scene)
}

/// The folder relative paths in a scene file (a heightmap) are resolved
/// against: the scene file's own folder, or "." for a preset.
fn scene_dir(scene_arg: &str) -> PathBuf {
    let p = Path::new(scene_arg);
    if p.exists() {
        p.parent().filter(|d| !d.as_os_str().is_empty()).map(Path::to_path_buf).unwrap_or_else(|| PathBuf::from("."))
    } else {
        PathBuf::from(".")
    }
}

/// Runs `f` on a thread pool of `threads` workers (default: all cores).
fn with_threads<T>(threads: Option<u64>, f: impl FnOnce() -> Result<T> + Send) -> Result<T>
where
    T: Send,
{
    let mut b = rayon::ThreadPoolBuilder::new();
    if let Some(n) = threads {
        // 1..=MAX_THREADS, checked by clap.
        b = b.num_threads(n as usize);
    }
    let pool = b.build().context("cannot start the thread pool")?;
    pool.install(f)
}

/// Bake warnings (under-resolved kernel or curtains) on stderr, even with --quiet.
fn print_warnings(warnings: &[String]) {
    for w in warnings {
        eprintln!("aurora: warning: {w}");
    }
}
