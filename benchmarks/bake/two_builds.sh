# Sourced by the two-build benchmarks (cost.sh, stages.sh): reads OLD_BIN
# NEW_BIN SCENE [N] into OLD, NEW, SCENE and N (N defaulting to
# $DEFAULT_N), checks for GNU time ($TIME), makes a scratch folder $T
# removed on exit, and prints the header every data file starts with: the
# builds, the scene, the CPU model and the load.
[ $# -ge 3 ] || { echo "usage: $0 OLD_BIN NEW_BIN SCENE [N]" >&2; exit 2; }
OLD=$1
NEW=$2
SCENE=$3
N=${4:-$DEFAULT_N}
TIME=/usr/bin/time
[ -x "$TIME" ] || { echo "needs GNU time at $TIME" >&2; exit 1; }
T=$(mktemp -d)
trap 'rm -rf "$T"' EXIT
echo "old: $OLD"
echo "new: $NEW"
echo "scene: $SCENE, $N runs each${RUNS_AT:+ $RUNS_AT}, alternating"
echo "cpu: $(lscpu | sed -n 's/^Model name: *//p' | head -n 1), nproc $(nproc), load before: $(cut -d' ' -f1-3 /proc/loadavg)"
