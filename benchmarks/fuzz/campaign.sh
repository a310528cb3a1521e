#!/usr/bin/env bash
# A fuzz campaign of the file readers: the VDB reader (both of the render's
# paths), the EXR reader (a background image) and the PNG reader (a terrain
# heightmap), each given N seeded mutations of small valid files
# (tests/fuzz_readers.rs; the test suite runs 2000 per reader). Every file
# must be read or refused: a panic, an abort (a failed allocation) or a
# file taking more than 5 s fails the run. Prints each reader's count of
# files read and refused, and its time.
#   benchmarks/fuzz/campaign.sh [N] [SEED] > benchmarks/fuzz/DATE-2core-campaign.txt
set -euo pipefail
cd "$(dirname "$0")/../.."
N=${1:-100000}
SEED=${2:-1}
echo "# aurora reader fuzz campaign, $(date -u +%Y-%m-%dT%H:%MZ)"
echo "# build $(git rev-parse --short HEAD)$(git diff --quiet HEAD -- src || echo '+changes'), $(nproc) cores; $N mutations per reader, seed $SEED"
cargo test --release --locked --test fuzz_readers --no-run >&2
start=$(date +%s)
AURORA_FUZZ_MUTATIONS=$N AURORA_FUZZ_SEED=$SEED cargo test --release --locked --test fuzz_readers -- --nocapture --test-threads 1 2>&1 \
  | grep -oE "(vdb|exr|png): [0-9]+ mutations.*|test result.*"
echo "# total $(($(date +%s) - start)) s"
