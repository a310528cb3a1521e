#!/bin/sh
# Bake an aurora animation as a Slurm job array: each array task bakes every
# N-th frame of the range (N = the number of tasks), all into one folder.
#
#   sbatch --array=0-31 farm/slurm/aurora-array.sh scene.toml 1-720 shots/sky
#
# Arguments: SCENE (file or preset), FRAMES (Open Job Description range
# syntax: 1-720, 1,3,7-20:2), OUT (shared folder). Use a contiguous array
# (--array=A-B, optionally %K to throttle): `aurora --shard auto` takes
# I = SLURM_ARRAY_TASK_ID - SLURM_ARRAY_TASK_MIN, N = SLURM_ARRAY_TASK_COUNT
# and refuses stepped arrays. Resubmitting the same command resumes: frames
# already complete (of the same bake) are skipped; after an edit of the scene
# that changes the bake, the folder is refused: use a new OUT, or set
# AURORA_REBAKE=1 to rebake it. AURORA overrides the binary (default: aurora
# on PATH).
#SBATCH --job-name=aurora-frames
#SBATCH --cpus-per-task=2
#SBATCH --output=aurora-%A_%a.log
set -eu
SCENE=${1:?scene file or preset}
FRAMES=${2:?frame range, e.g. 1-720}
OUT=${3:?output folder}
exec "${AURORA:-aurora}" bake "$SCENE" --frames "$FRAMES" --out "$OUT" \
    --shard auto --threads "${SLURM_CPUS_PER_TASK:-2}" --quiet ${AURORA_REBAKE:+--rebake}
