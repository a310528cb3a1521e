#!/usr/bin/env bash
# Behaviour pins: SHA-256 hashes of outputs that a change which must not
# alter behaviour keeps, byte for byte. Prints `sha256  name` lines;
# benchmarks/pins/current.txt holds them for the tree as committed:
#   benchmarks/pins/pin.sh [AURORA_BIN] | diff benchmarks/pins/current.txt -
# A change that alters outputs on purpose (new physics, a new default)
# rewrites current.txt with it and says why.
#
# Pins, each checked for determinism where it is cheap to:
# - the default bake's aurora.vdb (at 1 and 2 threads: they must agree),
#   aurora.usda, and `aurora scene --schema`;
# - a 160x90 4-spp PNG render of that VDB (PNG is byte-deterministic, tiled
#   EXR is not), the same with `[sky] extinction = false`, and a flat-ground
#   bake without the air and its render;
# - a two-frame sequence of a reduced scene (400 beams, 64x16 footprint):
#   its aurora.usda and VDBs;
# - the default's altitude-profile CSV and footprint PNGs;
# - `bake --plan --frames 1-3` with its measured columns (bytes of the
#   timing-bearing report, CPU, wall, memory) removed.
set -euo pipefail
cd "$(dirname "$0")/../.."
BIN=${1:-./target/release/aurora}
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
"$BIN" bake -q --threads 2 --out "$T/bake" default >/dev/null 2>&1
"$BIN" bake -q --threads 1 --out "$T/bake1" default >/dev/null 2>&1
if ! cmp -s "$T/bake/aurora.vdb" "$T/bake1/aurora.vdb"; then
  echo "pin.sh: the default bake differs between 1 and 2 threads" >&2
  exit 1
fi
"$BIN" scene --schema >"$T/schema.json"
"$BIN" scene default | sed -e 's/^width = 640$/width = 160/' -e 's/^height = 360$/height = 90/' \
  -e 's/^spp = 16$/spp = 4/' >"$T/small.toml"
grep -q '^width = 160$' "$T/small.toml" && grep -q '^spp = 4$' "$T/small.toml"
"$BIN" render -q --vdb "$T/bake/aurora.vdb" --threads 2 --out "$T/render.png" "$T/small.toml" >/dev/null 2>&1
# The same render without the air.
sed -e 's/^extinction = true$/extinction = false/' "$T/small.toml" >"$T/noair.toml"
grep -q '^extinction = false$' "$T/noair.toml"
"$BIN" render -q --vdb "$T/bake/aurora.vdb" --threads 2 --out "$T/render-noair.png" "$T/noair.toml" >/dev/null 2>&1
# Flat ground and no air (`[earth] radius_km = 0`, `[sky] extinction = false`).
sed -e 's/^radius_km = 6371.0$/radius_km = 0.0/' "$T/noair.toml" >"$T/flat.toml"
grep -q '^radius_km = 0.0$' "$T/flat.toml"
"$BIN" bake -q --out "$T/flat" "$T/flat.toml" >/dev/null 2>&1
"$BIN" render -q --vdb "$T/flat/aurora.vdb" --threads 2 --out "$T/render-flat-noair.png" "$T/flat.toml" >/dev/null 2>&1
"$BIN" scene default | sed -e 's/^count = 30000$/count = 400/' -e 's/^resolution = \[512, 128\]$/resolution = [64, 16]/' \
  >"$T/seq.toml"
grep -q '^count = 400$' "$T/seq.toml"
"$BIN" bake -q --out "$T/seq" --frames 1-2 "$T/seq.toml" >/dev/null 2>&1
"$BIN" profile -q --threads 2 --out "$T/profile.csv" default >/dev/null 2>&1
"$BIN" footprint --out "$T/footprint" default >/dev/null 2>&1
ls "$T"/footprint/footprint-*.png >/dev/null
"$BIN" bake --plan --frames 1-3 --threads 2 default 2>&1 \
  | awk '/^ +frame +time_s/ { print $1, $2, $3; next }
         /^ +[0-9]+ +[0-9.]+ +[0-9]+ / { print $1, $2, $3; next }
         /^plan for / { print; next }' >"$T/plan.txt"
[ "$(wc -l <"$T/plan.txt")" -eq 5 ]
cd "$T"
sha256sum bake/aurora.vdb bake/aurora.usda schema.json render.png render-noair.png render-flat-noair.png \
  seq/aurora.usda seq/aurora.0001.vdb seq/aurora.0002.vdb profile.csv footprint/footprint-*.png plan.txt
