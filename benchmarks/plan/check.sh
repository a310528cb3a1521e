#!/usr/bin/env bash
# The plan's CPU estimate against a measured bake: `aurora bake SCENE
# --frames 1-N --plan` (the estimate), then the same range baked for real
# under /usr/bin/time (user + system CPU seconds), in one run. Prints both
# and their ratio; the byte estimate is compared too (tests/cli/plan.rs
# checks bytes in the test command; CPU time is too noisy for a test).
# Usage: benchmarks/plan/check.sh [BIN] [SCENE] [N]
set -euo pipefail
BIN=${1:-target/release/aurora}
SCENE=${2:-default}
N=${3:-24}
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
echo "date: $(date -u +%Y-%m-%dT%H:%M:%SZ)"
echo "machine: $(nproc) CPUs, $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs)"
echo "build: $("$BIN" --version)"
echo "scene: $SCENE, frames 1-$N; loadavg before: $(cut -d' ' -f1-3 /proc/loadavg)"
"$BIN" bake "$SCENE" --frames "1-$N" --plan --progress json --out "$T/planned" 2>/dev/null > "$T/plan.json"
/usr/bin/time -f '%U %S %e' -o "$T/time" "$BIN" bake "$SCENE" --frames "1-$N" -q --out "$T/baked"
read -r user sys wall < "$T/time"
bytes=$(find "$T/baked" -maxdepth 1 -name 'aurora.*' -type f -printf '%s\n' | awk '{s += $1} END {print s}')
python3 - "$T/plan.json" "$user" "$sys" "$wall" "$bytes" <<'PY'
import json, sys
plan = json.load(open(sys.argv[1]))
user, sys_, wall, nbytes = map(float, sys.argv[2:6])
cpu = user + sys_
print(f"plan: {plan['total_cpu_s']:.1f} CPU-s ({plan['cpu_per_frame_s']:.2f} per frame + {plan['setup_cpu_s']:.2f} setup), {plan['total_bytes']:.0f} B")
print(f"bake: {cpu:.1f} CPU-s (user {user:.1f}, sys {sys_:.1f}; wall {wall:.1f} s), {nbytes:.0f} B")
print(f"plan / bake: CPU {plan['total_cpu_s'] / cpu:.3f}, bytes {plan['total_bytes'] / nbytes:.3f}")
PY
echo "loadavg after: $(cut -d' ' -f1-3 /proc/loadavg)"
