#!/usr/bin/env bash
# What the arcs' choices cost: the default bake against the same bake with
# one choice changed (the body's width, the filaments, the voxel size, the
# kernel, the beams), and, when BASE_BIN is given, the bake of another
# build's default (the cost caps: 3x its CPU, 2x its bytes). For each:
# CPU seconds (user + system of /usr/bin/time, the best of RUNS runs at 2
# threads: CPU time, so a loaded machine moves it less than wall time),
# the VDB's bytes, the peak resident set and the brightest 557.7 nm column
# along B is left to tests/physics/ibc.rs.
#   cargo build --release
#   benchmarks/arcs/cost.sh [AURORA_BIN] > benchmarks/arcs/DATE-2core-cost.txt
#   BASE_BIN=path/to/older/aurora benchmarks/arcs/cost.sh ...
set -euo pipefail
cd "$(dirname "$0")/../.."
BIN=${1:-./target/release/aurora}
RUNS=${RUNS:-2}
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
echo "# aurora: the arcs' choices and their cost, $(date -u +%Y-%m-%dT%H:%MZ)"
echo "# build $(git rev-parse --short HEAD)$(git diff --quiet HEAD -- src || echo '+changes'), $(nproc) cores, $(lscpu | sed -n 's/^Model name: *//p')"
echo "# load before: $(cut -d' ' -f1-3 /proc/loadavg); best of $RUNS runs of aurora bake -q --threads 2"
printf '%-34s %8s %10s %9s %9s  %s\n' case cpu_s vdb_MB rss_MB cpu/def set
measure() {
  local bin=$1
  shift
  local best=1e9 bytes=0 rss=0 c
  for _ in $(seq "$RUNS"); do
    rm -rf "$T/out"
    /usr/bin/time -f '%U %S %M' -o "$T/time" "$bin" bake -q --threads 2 --out "$T/out" "$@" >/dev/null 2>"$T/err" || {
      cat "$T/err" >&2
      echo refused
      return 0
    }
    c=$(awk '{print $1 + $2}' "$T/time")
    best=$(awk -v a="$best" -v b="$c" 'BEGIN {print (b < a) ? b : a}')
    rss=$(awk '{print $3 / 1024}' "$T/time")
    bytes=$(stat -c %s "$T/out/aurora.vdb")
  done
  echo "$best $bytes $rss"
}
DEF=""
row() {
  local name=$1 bin=$2
  shift 2
  read -r cpu bytes rss <<<"$(measure "$bin" "$@")"
  if [ "$cpu" = refused ]; then
    printf '%-34s %s  %s\n' "$name" "refused by the memory budget (its message on stderr)" "$*"
    return
  fi
  [ -z "$DEF" ] && DEF=$cpu
  printf '%-34s %8.2f %10.1f %9.0f %9.2f  %s\n' "$name" "$cpu" "$(awk -v b="$bytes" 'BEGIN {print b / 1e6}')" "$rss" "$(awk -v a="$cpu" -v b="$DEF" 'BEGIN {print a / b}')" "$*"
}
row "default" "$BIN"
if [ -n "${BASE_BIN:-}" ]; then
  row "default of BASE_BIN ($("$BASE_BIN" --version | cut -d' ' -f2))" "$BASE_BIN"
fi
row "body 4 km" "$BIN" --set footprint.sheet_thickness_km=4
row "body 16 km" "$BIN" --set footprint.sheet_thickness_km=16
row "no filaments" "$BIN" --set 'curtain[0].filament_energy_flux=0' --set 'curtain[1].filament_energy_flux=0' --set 'curtain[2].filament_energy_flux=0'
row "voxel 0.4 km" "$BIN" --set grid.voxel_size=0.4
row "voxel 0.35 km" "$BIN" --set grid.voxel_size=0.35
row "voxel 0.7 km" "$BIN" --set grid.voxel_size=0.7
row "kernel 0.25 km" "$BIN" --set photons.radius_km=0.25
row "kernel 1 km" "$BIN" --set photons.radius_km=1.0
row "beams 16000" "$BIN" --set beams.count=16000
row "beams 4000" "$BIN" --set beams.count=4000
row "2014 walk (alpha_D 5, delta 3)" "$BIN" --set beams.alpha_d_deg=5 --set beams.delta_alpha_deg=3
