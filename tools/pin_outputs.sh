#!/usr/bin/env bash
# Pins the bake's and the renderer's output bytes, a second set beside
# benchmarks/pins/pin.sh (whose hashes benchmarks/pins/current.txt holds),
# with determinism checked on the way. Run from the repository root after
# `cargo build --release`; prints one "sha256  name" line per output. Save
# its output before a change that must not alter behaviour and diff it with
# the output after: every line must be the same. The default bake with
# --threads 1 and --threads 2 (must agree: determinism), a 160x90 4 spp PNG
# render of it at a fixed seed (PNG: byte-deterministic, unlike tiled EXR),
# and the VDBs of a --frames 1-3 sequence.
set -euo pipefail
BIN=${AURORA_BIN:-./target/release/aurora}
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
h() { sha256sum "$1" | cut -d' ' -f1; }

"$BIN" bake default --out "$TMP/t1" --threads 1 -q
"$BIN" bake default --out "$TMP/t2" --threads 2 -q
a=$(h "$TMP/t1/aurora.vdb"); b=$(h "$TMP/t2/aurora.vdb")
if [ "$a" != "$b" ]; then
    echo "threads 1 and 2 disagree: $a vs $b" >&2
    exit 1
fi
echo "$a  default/aurora.vdb"

"$BIN" scene default | sed -e '/^\[render\]/,/^\[/ s/^width = .*/width = 160/' \
    -e '/^\[render\]/,/^\[/ s/^height = .*/height = 90/' > "$TMP/small.toml"
"$BIN" render "$TMP/small.toml" --vdb "$TMP/t2/aurora.vdb" --out "$TMP/r.png" --spp 4 --seed 7 -q
echo "$(h "$TMP/r.png")  render_160x90_4spp_seed7.png"

"$BIN" bake default --out "$TMP/seq" --frames 1-3 -q
for f in "$TMP"/seq/aurora.*.vdb; do
    echo "$(h "$f")  frames/$(basename "$f")"
done
