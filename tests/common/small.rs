//! The small scene the command-line tests bake (about a second a frame: one
//! curtain, a coarse footprint, 400 beams, 1 km voxels) and the bake command
//! they run, clear of the farm's variables.

use std::path::Path;
use std::process::Command;

/// The bake keys every small scene of the command-line tests shares, as TOML;
/// a test appends its own sections with `concat!`.
#[macro_export]
macro_rules! small_bake_toml {
    () => {
        r#"
seed = 7
[[curtain]]
center = [0.0, 0.0]
length = 40.0
width = 12.0
bend_km = 3.0
[footprint]
resolution = [96, 32]
steps = 4
[beams]
count = 400
[photons]
radius_km = 0.8
[grid]
voxel_size = 1.0
"#
    };
}

/// The variables `--shard auto` reads (Slurm's job array, a Kubernetes
/// Indexed Job): removed, so a test runs the same inside a farm job.
pub const FARM_VARS: [&str; 5] =
    ["SLURM_ARRAY_TASK_ID", "SLURM_ARRAY_TASK_MIN", "SLURM_ARRAY_TASK_COUNT", "SLURM_ARRAY_TASK_STEP", "JOB_COMPLETION_INDEX"];

/// `aurora bake SCENE --out OUT`, without [`FARM_VARS`]; the caller adds
/// its flags and runs it.
pub fn bake_command(scene: &Path, out: &Path) -> Command {
    let mut c = Command::new(super::AURORA_BIN);
    c.arg("bake").arg(scene).arg("--out").arg(out);
    for v in FARM_VARS {
        c.env_remove(v);
    }
    c
}
