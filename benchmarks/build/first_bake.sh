#!/usr/bin/env bash
# First bake of a fresh clone, two revisions side by side: for each, a fresh
# clone (no target/) is built with `cargo build --release --locked --timings`
# and then runs `target/release/aurora bake` (the default scene), as a new
# user's `cargo run --release -- bake` does. Runs alternate A B A B ... so
# that a change of machine load falls on both.
#
#   benchmarks/build/first_bake.sh [--runs N] [--out FILE] [BASE [NEW]]
#
# BASE defaults to 9a7556f, the tree before the build-time changes, NEW to
# HEAD. N (default 2) runs of each.
# Prints wall and CPU (user + sys) seconds of the build and of the bake for
# every run, the median of each per revision, NEW/BASE ratios, the slowest
# units of each build (from cargo's timings report), and the sha256 of each
# bake's aurora.vdb (must be equal: the build settings may not change the
# output). The same text is written to benchmarks/build/DATE-Ncore-BASE-vs-NEW.txt
# (or FILE). Dependencies are downloaded by `cargo fetch` before any timing;
# the registry cache is shared, compiled artefacts are not. Run it on a quiet
# machine: other processes' load shows as wall time (loadavg is recorded).
set -euo pipefail

runs=2
out=
while [ $# -gt 0 ]; do
    case "$1" in
        --runs) runs=$2; shift 2 ;;
        --out) out=$2; shift 2 ;;
        -h|--help) sed -n '2,19p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
        --*) echo "unknown option $1" >&2; exit 2 ;;
        *) break ;;
    esac
done
top=$(git rev-parse --show-toplevel)
cd "$top"
base=${1:-9a7556f}
new=${2:-HEAD}
base_rev=$(git rev-parse --verify "$base^{commit}")
new_rev=$(git rev-parse --verify "$new^{commit}")
short() { git rev-parse --short=7 "$1"; }
date=$(date -u +%F)
ncpu=$(nproc)
if [ -z "$out" ]; then
    out="benchmarks/build/$date-${ncpu}core-$(short "$base_rev")-vs-$(short "$new_rev").txt"
fi
mkdir -p "$(dirname "$out")"

# Nothing from the caller's environment may redirect or share the build.
unset CARGO_TARGET_DIR CARGO_BUILD_TARGET_DIR RUSTC_WRAPPER CARGO_BUILD_RUSTC_WRAPPER CARGO_INCREMENTAL

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
report="$work/report.txt"
say() { printf '%s\n' "$*" | tee -a "$report"; }

# A fresh clone of a revision into $work/$2.
clone() {
    rm -rf "${work:?}/$2"
    git clone --quiet --no-checkout --no-hardlinks "$top" "$work/$2"
    git -C "$work/$2" checkout --quiet --detach "$1"
}

say "# First bake of a fresh clone: cargo build --release --locked, then aurora bake"
say "date: $(date -u +%FT%TZ)"
say "machine: $ncpu CPUs, $(grep -m1 'model name' /proc/cpuinfo 2>/dev/null | cut -d: -f2- | sed 's/^ //' || echo unknown)"
say "toolchain: $(rustc --version), $(cargo --version)"
say "A (base): $base_rev $(git log -1 --format=%s "$base_rev" | cut -c1-72)"
say "B (new):  $new_rev $(git log -1 --format=%s "$new_rev" | cut -c1-72)"
say "runs: $runs of each, alternating A B"

for tag in A B; do
    rev=$base_rev
    [ "$tag" = B ] && rev=$new_rev
    clone "$rev" "fetch-$tag"
    (cd "$work/fetch-$tag" && cargo fetch --locked --quiet)
done
say ""
say "run rev  build_wall build_cpu  bake_wall bake_cpu  total_wall  loadavg_before  vdb_sha256"

TIMEFORMAT='%R %U %S'
for i in $(seq 1 "$runs"); do
    for tag in A B; do
        rev=$base_rev
        [ "$tag" = B ] && rev=$new_rev
        d="$work/run-$tag"
        clone "$rev" "run-$tag"
        load=$(cut -d' ' -f1-3 /proc/loadavg)
        bt=$( { time (cd "$d" && cargo build --release --locked --offline --timings >"$work/build-$tag-$i.log" 2>&1); } 2>&1 ) || {
            echo "build of $tag failed:" >&2; tail -n 30 "$work/build-$tag-$i.log" >&2; exit 1; }
        kt=$( { time (cd "$d" && ./target/release/aurora bake >"$work/bake-$tag-$i.log" 2>&1); } 2>&1 ) || {
            echo "bake of $tag failed:" >&2; tail -n 30 "$work/bake-$tag-$i.log" >&2; exit 1; }
        sha=$(sha256sum "$d/aurora-out/aurora.vdb" | cut -d' ' -f1)
        read -r bw bu bs <<<"$bt"
        read -r kw ku ks <<<"$kt"
        line=$(awk -v i="$i" -v t="$tag" -v bw="$bw" -v bu="$bu" -v bs="$bs" -v kw="$kw" -v ku="$ku" -v ks="$ks" \
            'BEGIN { printf "%3d %-4s %10.1f %9.1f %10.2f %8.2f %11.1f", i, t, bw, bu + bs, kw, ku + ks, bw + kw }')
        say "$line  $load  $sha"
        echo "$tag $bw $(awk -v u="$bu" -v s="$bs" 'BEGIN{print u+s}') $kw $(awk -v u="$ku" -v s="$ks" 'BEGIN{print u+s}') $sha" >>"$work/rows"
        # The slowest units of this build, from cargo's timings report.
        html=$(ls "$d"/target/cargo-timings/cargo-timing-*.html 2>/dev/null | head -n 1 || true)
        if [ -n "$html" ] && command -v python3 >/dev/null; then
            python3 - "$html" >"$work/units-$tag-$i.txt" <<'PY' || true
import json, re, sys
text = open(sys.argv[1]).read()
m = re.search(r'const UNIT_DATA = (\[.*?\]);\n', text, re.S)
units = json.loads(m.group(1)) if m else []
for u in sorted(units, key=lambda u: -u['duration'])[:12]:
    kind = u.get('target', '').strip() or 'lib'
    print(f"    {u['duration']:6.1f} s  {u['name']} {u['version']} {kind}")
PY
        fi
        rm -rf "$d"
    done
done

say ""
say "medians (s)        build_wall build_cpu  bake_wall bake_cpu  total_wall"
med() { sort -n | awk '{ a[NR] = $1 } END { if (NR % 2) print a[(NR + 1) / 2]; else print (a[NR / 2] + a[NR / 2 + 1]) / 2 }'; }
declare -A M
for tag in A B; do
    for col in 2 3 4 5; do
        M[$tag$col]=$(awk -v t="$tag" -v c="$col" '$1 == t { print $c }' "$work/rows" | med)
    done
    M[${tag}t]=$(awk -v t="$tag" '$1 == t { print $2 + $4 }' "$work/rows" | med)
    say "$(awk -v t="$tag" -v a="${M[${tag}2]}" -v b="${M[${tag}3]}" -v c="${M[${tag}4]}" -v d="${M[${tag}5]}" -v e="${M[${tag}t]}" \
        'BEGIN { printf "%-18s %10.1f %9.1f %10.2f %8.2f %11.1f", t, a, b, c, d, e }')"
done
say "$(awk -v a="${M[A2]}" -v b="${M[B2]}" -v c="${M[A3]}" -v d="${M[B3]}" -v e="${M[A4]}" -v f="${M[B4]}" -v g="${M[A5]}" -v h="${M[B5]}" -v x="${M[At]}" -v y="${M[Bt]}" \
    'BEGIN { printf "%-18s %10.3f %9.3f %10.3f %8.3f %11.3f", "B/A", b / a, d / c, f / e, h / g, y / x }')"
shas=$(awk '{ print $6 }' "$work/rows" | sort -u | wc -l)
if [ "$shas" = 1 ]; then
    say "aurora.vdb: identical in every run"
else
    say "aurora.vdb: DIFFERS between runs ($shas distinct hashes)"
fi
say ""
say "slowest units of each build (cargo --timings; units compile in parallel, so these overlap):"
for f in "$work"/units-*.txt; do
    [ -e "$f" ] || continue
    n=$(basename "$f" .txt)
    say "  ${n#units-}:"
    while IFS= read -r l; do say "$l"; done <"$f"
done
cp "$report" "$out"
echo "written: $out"
[ "$shas" = 1 ]
