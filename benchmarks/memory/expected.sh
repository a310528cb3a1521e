#!/usr/bin/env bash
# The expected peak against the bake's measured peak: for each scene, the
# refusal's bound and the expected peak `aurora bake --plan` prints
# (`examples/memory_expected.rs`: `aurora::pipeline::memory::expected`, from a
# traced sample of the beams, and `aurora::pipeline::memory::budget`), and
# the largest peak resident set ("Maximum resident set size" of
# /usr/bin/time -v) of RUNS runs of `aurora bake -q` at 2 threads and at 1.
# Prints bound, expected, measured and their ratios: expected / measured is
# aimed at 0.95-1.3, bound / measured stays at 1 or above (the refusal's
# upper bound). The expected peak's terms go to stderr.
#   cargo build --release --example memory_expected
#   benchmarks/memory/expected.sh [AURORA_BIN] > benchmarks/memory/DATE-2core-expected.txt
set -euo pipefail
cd "$(dirname "$0")/../.."
BIN=${1:-./target/release/aurora}
EXP=${EXPECTED_BIN:-./target/release/examples/memory_expected}
RUNS=${RUNS:-3}
# Runs at 1 thread (the thread count's effect; fewer to save time).
RUNS1=${RUNS1:-$RUNS}
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
echo "# aurora expected peak against the bound and the measured peak, $(date -u +%Y-%m-%dT%H:%MZ)"
echo "# build $(git rev-parse --short HEAD)$(git diff --quiet HEAD -- src || echo '+changes'), $(nproc) cores, $(lscpu | sed -n 's/^Model name: *//p')"
echo "# load before: $(cut -d' ' -f1-3 /proc/loadavg); measured: the largest max-RSS of $RUNS runs of aurora bake -q --threads 2 ($RUNS1 at 1 thread)"
printf '%-9s %7s %9s %9s %12s %12s %11s %9s %s\n' scene threads bound_GiB exp_GiB measured_GiB exp/measured bound/meas est_s scene_args
peak() {
  local toml=$1 threads=$2 runs=$3 best=0 p
  for _ in $(seq "$runs"); do
    /usr/bin/time -v -o "$T/time" "$BIN" bake -q --threads "$threads" --out "$T/out" "$toml" >/dev/null 2>"$T/err" || {
      echo "the bake of $toml failed" >&2
      cat "$T/err" >&2
      return 1
    }
    rm -rf "$T/out"
    p=$(awk -F': ' '/Maximum resident set size/ {print $2 * 1024}' "$T/time")
    best=$(awk -v a="$best" -v b="$p" 'BEGIN {print (b > a) ? b : a}')
  done
  echo "$best"
}
run() {
  local name=$1
  shift
  "$BIN" scene "$@" >"$T/$name.toml"
  for threads in 2 1; do
    echo "== $name, $threads threads" >&2
    local t0 t1 out bound exp measured
    t0=$(date +%s.%N)
    out=$("$EXP" "$T/$name.toml" "$threads")
    t1=$(date +%s.%N)
    read -r bound exp <<<"$out"
    measured=$(peak "$T/$name.toml" "$threads" "$([ "$threads" = 1 ] && echo "$RUNS1" || echo "$RUNS")")
    awk -v n="$name" -v th="$threads" -v b="$bound" -v e="$exp" -v m="$measured" -v s="$(echo "$t1 - $t0" | bc)" -v a="$*" \
      'BEGIN {printf "%-9s %7d %9.3f %9.3f %12.3f %12.2f %11.2f %9.1f %s\n", n, th, b / 2^30, e / 2^30, m / 2^30, e / m, b / m, s, a}'
  done
}
run default default
run lines default --set 'grid.lines=["5577", "6300", "4278"]'
run oval oval
run seed2014 seed2014
echo "# load after: $(cut -d' ' -f1-3 /proc/loadavg)"
