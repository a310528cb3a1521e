#!/usr/bin/env bash
# The chemistry's cost on the default bake: two binaries (the simple line
# model's, OLD, and the chemistry's, NEW) bake the default scene in turns,
# REPEATS times each, in one run. Each run's wall time and CPU time (user +
# sys of the bake process and its threads, from getrusage via GNU time) are
# printed, then the medians and the NEW / OLD ratios. On a shared machine the
# CPU time is the steadier of the two: other processes stretch the wall time
# of a run but add little to its own CPU time.
# Usage: benchmarks/chemistry/cost.sh OLD_BIN NEW_BIN [REPEATS]
set -euo pipefail
OLD=$1
NEW=$2
N=${3:-3}
TIME=/usr/bin/time
[ -x "$TIME" ] || { echo "needs GNU time at $TIME" >&2; exit 1; }
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
# Prints "wall cpu" in seconds for one default bake by binary $1.
run() {
  "$TIME" -f '%e %U %S' -o "$T/time" "$1" bake -q --out "$T/out" default >/dev/null 2>&1
  rm -rf "$T/out"
  awk '{printf "%.3f %.3f\n", $1, $2 + $3}' "$T/time"
}
old_w=()
old_c=()
new_w=()
new_c=()
echo "old: $OLD"
echo "new: $NEW"
echo "nproc $(nproc), load before: $(cut -d' ' -f1-3 /proc/loadavg)"
for i in $(seq "$N"); do
  read -r ow oc < <(run "$OLD")
  read -r nw nc < <(run "$NEW")
  old_w+=("$ow")
  old_c+=("$oc")
  new_w+=("$nw")
  new_c+=("$nc")
  echo "repeat $i: old wall $ow s cpu $oc s, new wall $nw s cpu $nc s"
done
median() { printf '%s\n' "$@" | sort -n | awk '{a[NR]=$1} END {print (NR % 2) ? a[(NR+1)/2] : (a[NR/2] + a[NR/2+1]) / 2}'; }
mow=$(median "${old_w[@]}")
mnw=$(median "${new_w[@]}")
moc=$(median "${old_c[@]}")
mnc=$(median "${new_c[@]}")
echo "load after: $(cut -d' ' -f1-3 /proc/loadavg)"
echo "median wall: old $mow s, new $mnw s, ratio $(echo "scale=3; $mnw / $mow" | bc)"
echo "median cpu:  old $moc s, new $mnc s, ratio $(echo "scale=3; $mnc / $moc" | bc)"
