#!/usr/bin/env bash
# Where two builds spend a bake, stage by stage: OLD_BIN and NEW_BIN bake
# SCENE in turns, N times each, at one thread (so a stage's wall time is its
# CPU time), and the medians of each stage's seconds from bake.json
# (`stats.times_s`: footprints, beams, gather, density, prune; `files.
# vdb_write_seconds`: the VDB's encoding and writing) are printed beside
# each other, with the process's CPU time (user + sys, GNU time). The rest
# of a bake (scene, budget check, colour tables, USD, bake.json) is the
# difference between the CPU time and the stages' sum.
# Usage: benchmarks/bake/stages.sh OLD_BIN NEW_BIN SCENE [N]   (N = 3)
set -euo pipefail
DEFAULT_N=3
RUNS_AT="at --threads 1"
# shellcheck source=benchmarks/bake/two_builds.sh
source "$(dirname "$0")/two_builds.sh"
for i in $(seq "$N"); do
  for which in old new; do
    if [ "$which" = old ]; then bin=$OLD; else bin=$NEW; fi
    "$TIME" -f '%U %S' -o "$T/time" "$bin" bake -q --threads 1 --out "$T/out" "$SCENE" >/dev/null 2>"$T/err" || {
      cat "$T/err" >&2
      exit 1
    }
    read -r u s < <(tail -n 1 "$T/time")
    python3 - "$T/out/bake.json" "$which" "$u" "$s" >>"$T/rows" <<'EOF'
import json, sys
d = json.load(open(sys.argv[1]))
t = d["stats"]["times_s"]
row = {k: t.get(k, 0.0) for k in ("footprints", "beams", "gather", "density", "prune")}
row["write"] = d["files"]["vdb_write_seconds"]
row["cpu"] = float(sys.argv[3]) + float(sys.argv[4])
print(sys.argv[2], json.dumps(row))
EOF
    rm -rf "$T/out"
  done
done
echo "load after: $(cut -d' ' -f1-3 /proc/loadavg)"
python3 - "$T/rows" <<'EOF'
import json, statistics, sys
rows = {"old": [], "new": []}
for line in open(sys.argv[1]):
    which, data = line.split(" ", 1)
    rows[which].append(json.loads(data))
keys = ["footprints", "beams", "gather", "density", "prune", "write"]
med = {w: {k: statistics.median(r[k] for r in rs) for k in keys + ["cpu"]} for w, rs in rows.items()}
print(f"{'median s':<12} {'old':>7} {'new':>7} {'new/old':>8}")
for k in keys + ["cpu"]:
    o, n = med["old"][k], med["new"][k]
    print(f"{k:<12} {o:7.3f} {n:7.3f} {n / o if o else float('nan'):8.3f}")
for w in ("old", "new"):
    print(f"{w}: the rest (cpu - stages) {med[w]['cpu'] - sum(med[w][k] for k in keys):.3f} s")
EOF
