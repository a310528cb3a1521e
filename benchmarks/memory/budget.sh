#!/usr/bin/env bash
# The memory budget against the bake's measured peak: for each scene, the
# budget's estimate (`examples/memory_estimate.rs`, the estimate `aurora
# bake` checks) and one `aurora bake` under an 8 GiB address-space limit on
# 2 threads, timed by /usr/bin/time -v; prints the estimate, the peak
# resident set ("Maximum resident set size") and their ratio, which the
# budget keeps at 1 or above (an upper bound). The terms go to stderr.
#   cargo build --release --example memory_estimate
#   benchmarks/memory/budget.sh [AURORA_BIN] > benchmarks/memory/DATE-2core-....txt
set -euo pipefail
cd "$(dirname "$0")/../.."
BIN=${1:-./target/release/aurora}
EST=${ESTIMATE_BIN:-./target/release/examples/memory_estimate}
LIMIT=8589934592
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
echo "# aurora memory budget against the measured peak, $(date -u +%Y-%m-%dT%H:%MZ)"
echo "# build $(git rev-parse --short HEAD)$(git diff --quiet HEAD -- src || echo '+changes'), $(nproc) cores, $(lscpu | sed -n 's/^Model name: *//p')"
echo "# load before: $(cut -d' ' -f1-3 /proc/loadavg); bake: prlimit --as=$LIMIT aurora bake --threads 2"
printf '%-9s %13s %10s %6s %7s %s\n' scene estimate_GiB peak_GiB ratio wall_s scene_args
run() {
  local name=$1
  shift
  "$BIN" scene "$@" >"$T/$name.toml"
  echo "== $name" >&2
  local bytes
  bytes=$("$EST" "$T/$name.toml")
  /usr/bin/time -v -o "$T/time" prlimit --as=$LIMIT "$BIN" bake -q --threads 2 --out "$T/out-$name" "$T/$name.toml" >/dev/null 2>"$T/err" || {
    echo "$name: the bake failed" >&2
    cat "$T/err" >&2
    return 1
  }
  rm -rf "$T/out-$name"
  local peak wall
  peak=$(awk -F': ' '/Maximum resident set size/ {print $2 * 1024}' "$T/time")
  wall=$(awk -F': ' '/Elapsed \(wall clock\)/ {n = split($2, a, ":"); s = 0; for (i = 1; i <= n; i++) s = s * 60 + a[i]; print s}' "$T/time")
  awk -v n="$name" -v e="$bytes" -v p="$peak" -v w="$wall" -v a="$*" \
    'BEGIN {printf "%-9s %13.3f %10.3f %6.2f %7.0f %s\n", n, e / 2^30, p / 2^30, e / p, w, a}'
}
run default default
run seed2014 seed2014
run oval oval
run lines default --set 'grid.lines=["5577", "6300", "4278"]'
echo "# load after: $(cut -d' ' -f1-3 /proc/loadavg)"
