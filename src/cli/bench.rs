//! `aurora bench`: the speed-against-accuracy studies of `aurora::app::bench`,
//! their files written and their summary table printed.

use super::args::BenchArgs;
use super::{load_scene, with_threads};
use anyhow::Result;

pub fn run(a: BenchArgs) -> Result<()> {
    let BenchArgs { scene: scene_arg, out, quick, storage, common, overrides } = a;
    let scene = load_scene(&scene_arg, &overrides)?;
    let quiet = common.quiet;
    with_threads(common.threads, || {
        let log = |line: &str| {
            if !quiet {
                eprintln!("bench: {line}");
            }
        };
        let run = if storage {
            aurora::app::bench::run_storage(&scene, &scene_arg, &log)?
        } else {
            aurora::app::bench::run(&scene, &scene_arg, quick, &log)?
        };
        let written = aurora::app::bench::report::write(&run, &out)?;
        print!("{}", aurora::app::bench::report::summary(&run));
        if !quiet {
            eprintln!("wrote {} files to {}", written.len(), out.display());
        }
        Ok(())
    })
}
