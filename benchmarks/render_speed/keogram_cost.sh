#!/bin/sh
# A keogram's cost per frame: `aurora keogram` of a baked sequence by two builds side by side in
# one run, runs alternating OLD, NEW; CPU time (user + sys), wall and peak RSS from /usr/bin/time;
# then whether the two builds' keograms (EXR, PNG, CSV) are the same bytes.
#
#   benchmarks/render_speed/keogram_cost.sh OLD_BIN NEW_BIN SEQ_DIR FRAMES OUT_DIR [RUNS]
#
# SEQ_DIR is a sequence baked with its line grid, e.g.
#   aurora bake default --frames 1-3 --set 'grid.lines=["5577"]' --out SEQ_DIR
# FRAMES its frames in range syntax (1-3); RUNS (default 3) runs of each build, 2 threads.
set -eu
OLD=$1 NEW=$2 SEQ=$3 FRAMES=$4 OUT=$5 RUNS=${6:-3}
mkdir -p "$OUT"
echo "# build run  CPU-s  (user + sys)   wall   peak RSS MB"
i=1
while [ "$i" -le "$RUNS" ]; do
    for name in old new; do
        if [ "$name" = old ]; then bin=$OLD; else bin=$NEW; fi
        /usr/bin/time -f "%U %S %e %M" -o "$OUT/$name-$i.time" "$bin" keogram default --vdb "$SEQ" --frame "$FRAMES" \
            --out "$OUT/k-$name.exr" --threads 2 >/dev/null 2>&1
        # shellcheck disable=SC2046
        set -- $(cat "$OUT/$name-$i.time")
        printf '%-4s %2s  %5.2f  (%4.2f + %4.2f)  %5.2f  %5.0f\n' "$name" "$i" "$(echo "$1 + $2" | bc)" "$1" "$2" "$3" "$(echo "$4 / 1024" | bc)"
    done
    i=$((i + 1))
done
for ext in exr png csv; do
    if cmp -s "$OUT/k-old.$ext" "$OUT/k-new.$ext"; then echo "# the two builds' .$ext are the same bytes"; else echo "# the two builds' .$ext DIFFER"; fi
done
