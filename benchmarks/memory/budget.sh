#!/usr/bin/env bash
# The memory budget against the bake's measured peak: for each scene, one
# `aurora bake --plan --frames 1` (which bakes the frame and prints the
# budget's estimate) under an 8 GiB address-space limit on 2 threads, timed
# by /usr/bin/time -v; prints the estimate, the peak resident set
# ("Maximum resident set size") and their ratio, which the budget keeps at
# 1 or above (an upper bound).
#   benchmarks/memory/budget.sh [AURORA_BIN] > benchmarks/memory/DATE-2core-....txt
set -euo pipefail
cd "$(dirname "$0")/../.."
BIN=${1:-./target/release/aurora}
LIMIT=8589934592
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
echo "# aurora memory budget against the measured peak, $(date -u +%Y-%m-%dT%H:%MZ)"
echo "# build $(git rev-parse --short HEAD)$(git diff --quiet || echo '+changes'), $(nproc) cores, $(lscpu | sed -n 's/^Model name: *//p')"
echo "# load before: $(cut -d' ' -f1-3 /proc/loadavg); limit: prlimit --as=$LIMIT, --threads 2"
printf '%-14s %12s %12s %7s %9s %s\n' scene estimate_GiB peak_GiB ratio wall_s args
run() {
  local name=$1
  shift
  /usr/bin/time -v -o "$T/time" prlimit --as=$LIMIT "$BIN" bake --plan --frames 1 --threads 2 "$@" >"$T/plan" 2>"$T/err" || {
    echo "$name: failed" >&2
    cat "$T/err" >&2
    return 1
  }
  local est peak wall
  est=$(sed -n 's/.*measured (\([0-9.]*\) GiB by the memory budget.s model).*/\1/p' "$T/plan")
  peak=$(awk -F': ' '/Maximum resident set size/ {printf "%.3f", $2 / 1048576}' "$T/time")
  wall=$(awk -F': ' '/Elapsed \(wall clock\)/ {n = split($2, a, ":"); s = 0; for (i = 1; i <= n; i++) s = s * 60 + a[i]; print s}' "$T/time")
  printf '%-14s %12s %12s %7.2f %9.0f %s\n' "$name" "$est" "$peak" "$(echo "$est / $peak" | bc -l)" "$wall" "$*"
}
run default default
run seed2014 seed2014
run oval oval
run lines default --set 'grid.lines=["5577","6300","4278"]'
echo "# load after: $(cut -d' ' -f1-3 /proc/loadavg)"
