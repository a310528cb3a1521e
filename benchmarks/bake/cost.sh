#!/usr/bin/env bash
# The bake's cost, two builds against each other: OLD_BIN and NEW_BIN bake
# SCENE (a scene file, or a preset name such as `default`) in turns, N times
# each, in one run, at the default thread count. Each run's user, sys and
# wall time and peak resident set (GNU time: getrusage of the bake process
# and its threads) are printed, then the medians and the NEW / OLD ratio of
# the median CPU time (user + sys). On a shared machine the CPU time is the
# steadier measure: other processes stretch a run's wall time but add little
# to its own CPU time. Alternating the builds spreads any drift in the
# machine's load over both.
# Usage: benchmarks/bake/cost.sh OLD_BIN NEW_BIN SCENE [N]   (N = 5)
set -euo pipefail
DEFAULT_N=5
# shellcheck source=benchmarks/bake/two_builds.sh
source "$(dirname "$0")/two_builds.sh"
# One bake by binary $1; prints "user sys wall peak_kb".
run() {
  "$TIME" -f '%U %S %e %M' -o "$T/time" "$1" bake -q --out "$T/out" "$SCENE" >/dev/null 2>"$T/err" || {
    cat "$T/err" >&2
    exit 1
  }
  rm -rf "$T/out"
  tail -n 1 "$T/time"
}
median() { printf '%s\n' "$@" | sort -g | awk '{a[NR]=$1} END {print (NR % 2) ? a[(NR+1)/2] : (a[NR/2] + a[NR/2+1]) / 2}'; }
old_c=() new_c=() old_w=() new_w=() old_m=() new_m=()
printf '%-4s %-3s %8s %8s %8s %8s %10s\n' run bin user_s sys_s cpu_s wall_s peak_MB
for i in $(seq "$N"); do
  for which in old new; do
    if [ "$which" = old ]; then bin=$OLD; else bin=$NEW; fi
    read -r u s w m < <(run "$bin")
    c=$(echo "$u + $s" | bc)
    mb=$(echo "scale=1; $m / 1024" | bc)
    printf '%-4s %-3s %8.2f %8.2f %8.2f %8.2f %10.1f\n' "$i" "$which" "$u" "$s" "$c" "$w" "$mb"
    if [ "$which" = old ]; then
      old_c+=("$c") old_w+=("$w") old_m+=("$mb")
    else
      new_c+=("$c") new_w+=("$w") new_m+=("$mb")
    fi
  done
done
echo "load after: $(cut -d' ' -f1-3 /proc/loadavg)"
moc=$(median "${old_c[@]}") mnc=$(median "${new_c[@]}")
mow=$(median "${old_w[@]}") mnw=$(median "${new_w[@]}")
mom=$(median "${old_m[@]}") mnm=$(median "${new_m[@]}")
echo "median cpu:  old $moc s, new $mnc s, ratio $(echo "scale=3; $mnc / $moc" | bc)"
echo "median wall: old $mow s, new $mnw s, ratio $(echo "scale=3; $mnw / $mow" | bc)"
echo "median peak: old $mom MB, new $mnm MB"
