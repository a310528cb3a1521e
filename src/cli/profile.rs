//! `aurora profile`: the altitude profiles of the bake's beam deposits as
//! CSV, on stdout or into a file (with each curtain's column brightness
//! beside it, [`columns_path`]), and where the electron power went.

use super::args::ProfileArgs;
use super::bars::Bars;
use super::{load_scene, with_threads};
use anyhow::{Context, Result};
use aurora::scene::Scene;
use std::path::{Path, PathBuf};

/// `FILE.columns.csv` beside `--out FILE.csv` (or `FILE.columns.csv` beside
/// any other name `FILE`): each curtain's column brightness.
pub fn columns_path(out: &Path) -> PathBuf {
    let name = out.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let stem = name.strip_suffix(".csv").unwrap_or(&name);
    out.with_file_name(format!("{stem}.columns.csv"))
}

pub fn run(a: ProfileArgs) -> Result<()> {
    // --seed is one of the overrides, applied in command-line order.
    let ProfileArgs { scene, out, seed: _, common, overrides } = a;
    let scene = load_scene(&scene, &overrides)?;
    // Both outputs must be ours to replace before the beams are traced.
    if let Some(path) = &out {
        aurora::util::atomic_write::check_replaceable(path)?;
        aurora::util::atomic_write::check_replaceable(&columns_path(path))?;
    }
    with_threads(common.threads, || profile(&scene, out.as_deref(), common.quiet))
}

fn profile(scene: &Scene, out: Option<&Path>, quiet: bool) -> Result<()> {
    let bars = Bars::new(quiet);
    let p = aurora::pipeline::altitude_profile::profile(scene, bars.progress())?;
    let csv = aurora::pipeline::altitude_profile::to_csv(&p);
    match out {
        Some(path) => {
            let columns = columns_path(path);
            let columns_csv = aurora::pipeline::altitude_profile::columns_to_csv(&p);
            aurora::util::atomic_write::write_atomic(&columns, columns_csv.as_bytes())
                .with_context(|| format!("cannot write {}", columns.display()))?;
            aurora::util::atomic_write::write_atomic(path, csv.as_bytes()).with_context(|| format!("cannot write {}", path.display()))?;
            if !quiet {
                eprintln!("wrote {} and {}", path.display(), columns.display());
            }
        }
        None => print!("{csv}"),
    }
    if !quiet {
        let s = &p.beam_stats.power;
        eprintln!(
            "electron power {:.4e} W: deposited {:.4e}, backscattered {:.4e}, above the beams' top {:.4e}, undeposited {:.4e}",
            s.electron_power_w, s.deposited_power_w, s.backscattered_power_w, s.above_top_power_w, s.undeposited_power_w
        );
    }
    Ok(())
}
