#!/bin/sh
# A 2048x2048 dome master of the default scene (dome.toml beside this script: the fisheye on the
# ground looking up, no stars, no terrain), rendered from one VDB by two builds: the reference is
# OLD at 64 spp (seed 1001), then OLD at 1, 2, 4, 8 spp and NEW at 1, 2, 4 spp (the scene's seed).
# Each run's CPU time (user + sys, /usr/bin/time) and its mean relative error against the
# reference over the pixels whose R+G+B is above 1 % of the reference's peak
# (tools/aurora_tools/image_compare.py, `metrics`, threshold 0.01).
#
#   benchmarks/render_speed/dome_master.sh OLD_BIN NEW_BIN VDB OUT_DIR [SIZE]
#
# NEW also gets `--set airglow.on=false --set colour.observer=eye`: the airglow did not exist in
# OLD (37d3c93), and OLD weighed the air's channels for the eye (today's default observer is the
# camera, which changes the air's transmittance, not the volume). Python: the project venv
# ($PYTHON, default .venv/bin/python). Reruns reuse an OUT_DIR's finished images and times.
set -eu
OLD=$1 NEW=$2 VDB=$3 OUT=$4 SIZE=${5:-2048}
HERE=$(cd "$(dirname "$0")" && pwd)
ROOT=$(cd "$HERE/../.." && pwd)
PYTHON=${PYTHON:-$ROOT/.venv/bin/python}
mkdir -p "$OUT"
SCENE=$OUT/dome-$SIZE.toml
sed "s/^width = .*/width = $SIZE/;s/^height = .*/height = $SIZE/" "$HERE/dome.toml" > "$SCENE"

run() { # NAME BIN SPP [ARGS...]
    name=$1 bin=$2 spp=$3
    shift 3
    [ -s "$OUT/$name.time" ] && [ -s "$OUT/$name.exr" ] && return 0
    /usr/bin/time -f "%U %S %e %M" -o "$OUT/$name.time" \
        "$bin" render "$SCENE" --vdb "$VDB" --spp "$spp" --threads 2 -q --out "$OUT/$name.exr" "$@"
}

NEWSET="--set airglow.on=false --set colour.observer=eye"
run ref-old-64 "$OLD" 64 --seed 1001
for spp in 1 2 4 8; do run "old-$spp" "$OLD" "$spp"; done
# shellcheck disable=SC2086
for spp in 1 2 4; do run "new-$spp" "$NEW" "$spp" $NEWSET; done

"$PYTHON" "$HERE/table.py" "$OUT"
