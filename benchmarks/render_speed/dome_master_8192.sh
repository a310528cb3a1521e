#!/bin/sh
# An 8192x8192 dome master of the default scene (dome.toml beside this script) at 1 spp: CPU time
# (user + sys) and peak resident memory (/usr/bin/time -v), which must stay under 8 GiB.
#
#   benchmarks/render_speed/dome_master_8192.sh BIN VDB OUT_DIR [EXTRA RENDER ARGS...]
#
# For today's build pass `--set airglow.on=false --set colour.observer=eye` as dome_master.sh does.
set -eu
BIN=$1 VDB=$2 OUT=$3
shift 3
HERE=$(cd "$(dirname "$0")" && pwd)
mkdir -p "$OUT"
sed "s/^width = .*/width = 8192/;s/^height = .*/height = 8192/" "$HERE/dome.toml" > "$OUT/dome-8192.toml"
/usr/bin/time -v -o "$OUT/8192.timev" "$BIN" render "$OUT/dome-8192.toml" --vdb "$VDB" --spp 1 --threads 2 -q \
    --out "$OUT/dome-8192.exr" "$@"
awk -F': ' '/User time/ {u = $2} /System time/ {s = $2} /Maximum resident/ {m = $2}
    END {printf "8192x8192, 1 spp: %.1f CPU-s, peak RSS %.2f GiB\n", u + s, m / 1048576}' "$OUT/8192.timev"
