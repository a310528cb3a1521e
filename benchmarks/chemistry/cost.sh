#!/usr/bin/env bash
# The chemistry's cost on the default bake: two binaries (the simple line
# model's, OLD, and the chemistry's, NEW) bake the default scene in turns,
# REPEATS times each, in one run; prints each wall time and the ratio of the
# medians. Usage: benchmarks/chemistry/cost.sh OLD_BIN NEW_BIN [REPEATS]
set -euo pipefail
OLD=$1
NEW=$2
N=${3:-3}
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
run() {
  local s e
  s=$(date +%s.%N)
  "$1" bake -q --out "$T/out" default >/dev/null 2>&1
  e=$(date +%s.%N)
  rm -rf "$T/out"
  echo "$e - $s" | bc
}
old=()
new=()
for i in $(seq "$N"); do
  o=$(run "$OLD")
  n=$(run "$NEW")
  old+=("$o")
  new+=("$n")
  echo "repeat $i: old $o s, new $n s"
done
median() { printf '%s\n' "$@" | sort -n | awk '{a[NR]=$1} END {print (NR % 2) ? a[(NR+1)/2] : (a[NR/2] + a[NR/2+1]) / 2}'; }
mo=$(median "${old[@]}")
mn=$(median "${new[@]}")
echo "median old $mo s, new $mn s, ratio $(echo "scale=3; $mn / $mo" | bc)"
