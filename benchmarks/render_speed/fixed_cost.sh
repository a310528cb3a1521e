#!/bin/sh
# The render's fixed cost: a 16x9, 1-sample render (the scene's own sky and terrain) of three bakes
# (default, seed2014, oval), by two builds side by side in one run, runs alternating OLD, NEW.
# Each run's CPU time (user + sys) and peak RSS from /usr/bin/time, and the render's own stage
# times ("times: open VDB, build, trace"); then whether the two builds' PNGs are the same bytes.
#
#   benchmarks/render_speed/fixed_cost.sh OLD_BIN NEW_BIN OUT_DIR [RUNS]
#
# The bakes are made once by OLD_BIN into OUT_DIR/bake-PRESET (reused when there), so both
# builds read the same files. RUNS (default 3) runs of each build per bake, 2 threads.
set -eu
OLD=$1 NEW=$2 OUT=$3 RUNS=${4:-3}
mkdir -p "$OUT"
for preset in default seed2014 oval; do
    [ -s "$OUT/bake-$preset/aurora.vdb" ] || "$OLD" bake -q --threads 2 --out "$OUT/bake-$preset" "$preset" >/dev/null 2>&1
done

run() { # PRESET NAME BIN RUN
    preset=$1 name=$2 bin=$3 i=$4
    log=$OUT/$preset-$name-$i.log
    /usr/bin/time -f "cpu %U %S wall %e rss %M" -o "$log.time" "$bin" render "$preset" \
        --vdb "$OUT/bake-$preset/aurora.vdb" --size 16x9 --spp 1 --threads 2 --out "$OUT/$preset-$name.png" 2>"$log"
    stages=$(sed -n 's/^times: open VDB \([0-9.]*\) s, build \([0-9.]*\) s, trace \([0-9.]*\) s$/\1 \2 \3/p' "$log")
    # shellcheck disable=SC2046
    set -- $(cat "$log.time")
    printf '%-9s %-4s %2s  %5.2f  (%4.2f + %4.2f)  %5.2f  %5.0f   %s\n' "$preset" "$name" "$i" \
        "$(echo "$2 + $3" | bc)" "$2" "$3" "$5" "$(echo "$7 / 1024" | bc)" "$stages"
}

echo "# bake      build run  CPU-s  (user + sys)   wall   peak RSS MB   open VDB, build, trace (s)"
for preset in default seed2014 oval; do
    i=1
    while [ "$i" -le "$RUNS" ]; do
        run "$preset" old "$OLD" "$i"
        run "$preset" new "$NEW" "$i"
        i=$((i + 1))
    done
    if cmp -s "$OUT/$preset-old.png" "$OUT/$preset-new.png"; then
        echo "# $preset: the two builds' images are the same bytes"
    else
        echo "# $preset: the two builds' images DIFFER"
    fi
done
