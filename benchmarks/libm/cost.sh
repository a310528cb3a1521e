#!/bin/sh
# What routing the transcendental functions through the `libm` crate (src/util/fmath.rs) costs:
# two builds side by side in one run, runs alternating OLD, NEW, each at 2 threads:
#   bake default        the default bake (`aurora bake default`)
#   bake small          tests/data/small_bake.toml, the scene the Windows bake test bakes
#   render default      a 640x360 render of the default bake (the same VDB for both builds, baked
#                       once by OLD_BIN into OUT_DIR/bake-default)
# Each run's CPU time (user + sys, GNU time: the process and its threads) and wall time, the
# machine's load before and after, then per case the median CPU of each build and NEW / OLD;
# and whether the two builds' outputs are the same bytes (they are not: the functions round
# differently, so every output changes once).
#
#   benchmarks/libm/cost.sh OLD_BIN NEW_BIN OUT_DIR [RUNS]      (RUNS = 3)
set -eu
[ $# -ge 3 ] || { echo "usage: $0 OLD_BIN NEW_BIN OUT_DIR [RUNS]" >&2; exit 2; }
OLD=$1 NEW=$2 OUT=$3 RUNS=${4:-3}
TIME=/usr/bin/time
[ -x "$TIME" ] || { echo "needs GNU time at $TIME" >&2; exit 1; }
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
SMALL=$ROOT/tests/data/small_bake.toml
mkdir -p "$OUT"
echo "old: $OLD"
echo "new: $NEW"
echo "$RUNS runs each, alternating old, new; 2 threads"
echo "cpu: $(lscpu | sed -n 's/^Model name: *//p' | head -n 1), nproc $(nproc), load before: $(cut -d' ' -f1-3 /proc/loadavg)"
[ -s "$OUT/bake-default/aurora.vdb" ] || "$OLD" bake -q --threads 2 --out "$OUT/bake-default" default >/dev/null 2>&1

run() { # CASE NAME BIN RUN: prints one line, keeps the output as OUT/CASE-NAME
    case_=$1 name=$2 bin=$3 i=$4
    dest=$OUT/$case_-$name
    rm -rf "$dest" "$dest.png"
    case $case_ in
        bake-default) set -- "$bin" bake -q --threads 2 --out "$dest" default ;;
        bake-small) set -- "$bin" bake -q --threads 2 --out "$dest" "$SMALL" ;;
        render-default) set -- "$bin" render default --vdb "$OUT/bake-default/aurora.vdb" \
            --size 640x360 --threads 2 --out "$dest.png" ;;
    esac
    "$TIME" -f "%U %S %e" -o "$OUT/time" "$@" >/dev/null 2>"$OUT/err" || { cat "$OUT/err" >&2; exit 1; }
    read -r u s w <"$OUT/time"
    c=$(echo "$u + $s" | bc)
    printf '%-15s %-4s %2s  %7.2f  (%6.2f + %5.2f)  %6.2f  load %s\n' "$case_" "$name" "$i" "$c" "$u" "$s" "$w" \
        "$(cut -d' ' -f1 /proc/loadavg)"
    echo "$c" >>"$OUT/$case_-$name.cpu"
}
median() { sort -g "$1" | awk '{a[NR]=$1} END {print (NR % 2) ? a[(NR+1)/2] : (a[NR/2] + a[NR/2+1]) / 2}'; }
same() { # CASE: whether the two builds' outputs are the same bytes
    if [ -d "$OUT/$1-old" ]; then
        if cmp -s "$OUT/$1-old/aurora.vdb" "$OUT/$1-new/aurora.vdb"; then echo "same bytes"; else echo "differ"; fi
    elif cmp -s "$OUT/$1-old.png" "$OUT/$1-new.png"; then echo "same bytes"; else echo "differ"; fi
}

echo "# case           build run  CPU-s  (user  +  sys)  wall-s"
for case_ in bake-default bake-small render-default; do
    rm -f "$OUT/$case_-old.cpu" "$OUT/$case_-new.cpu"
    i=1
    while [ "$i" -le "$RUNS" ]; do
        run "$case_" old "$OLD" "$i"
        run "$case_" new "$NEW" "$i"
        i=$((i + 1))
    done
done
echo "load after: $(cut -d' ' -f1-3 /proc/loadavg)"
for case_ in bake-default bake-small render-default; do
    o=$(median "$OUT/$case_-old.cpu") n=$(median "$OUT/$case_-new.cpu")
    echo "median cpu $case_: old $o s, new $n s, new/old $(echo "scale=3; $n / $o" | bc); outputs $(same "$case_")"
done
