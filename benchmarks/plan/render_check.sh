#!/usr/bin/env bash
# The plan's render CPU per frame against a measured render: `aurora bake
# SCENE --frames 1 --plan` (the estimate, calibrated at a reduced size),
# then frame 1 baked and rendered for real at the scene's size under
# /usr/bin/time (user + system CPU seconds), in one run. Prints both and
# their ratio. Extra arguments (e.g. --set render.width=2048) go to every
# command. Usage: benchmarks/plan/render_check.sh [BIN] [SCENE] [ARGS...]
set -euo pipefail
BIN=${1:-target/release/aurora}
SCENE=${2:-default}
shift 2 || true
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
echo "date: $(date -u +%Y-%m-%dT%H:%M:%SZ)"
echo "machine: $(nproc) CPUs, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs)"
echo "build: $("$BIN" --version)"
echo "scene: $SCENE $*; loadavg before: $(cut -d' ' -f1-3 /proc/loadavg)"
"$BIN" bake "$SCENE" "$@" --frames 1 --plan --progress json --out "$T/planned" 2>/dev/null > "$T/plan.json"
"$BIN" bake "$SCENE" "$@" --frames 1 -q --out "$T/seq"
/usr/bin/time -f '%U %S %e' -o "$T/time" "$BIN" render "$SCENE" "$@" --vdb "$T/seq" --frame 1 -q --out "$T/frame.exr"
read -r user sys wall < "$T/time"
python3 - "$T/plan.json" "$user" "$sys" "$wall" <<'PY'
import json, sys
r = json.load(open(sys.argv[1]))["render"]
user, sys_, wall = map(float, sys.argv[2:5])
cpu = user + sys_
print(f"plan:   {r['cpu_per_frame_s']:.2f} CPU-s a frame at {r['width']}x{r['height']}, {r['spp']} spp "
      f"({r['fixed_cpu_s']:.2f} open and build + {r['cpu_per_sample_s'] * 1e6:.3f} us x {r['width'] * r['height'] * r['spp']} samples; "
      f"calibrated at {r['calibrated_width']}x{r['calibrated_height']})")
print(f"render: {cpu:.2f} CPU-s (user {user:.2f}, sys {sys_:.2f}; wall {wall:.2f} s)")
print(f"plan / render: {r['cpu_per_frame_s'] / cpu:.3f}")
PY
