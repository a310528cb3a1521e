#!/usr/bin/env bash
# The chemistry's cost on the default bake: two binaries (the simple line
# model's, OLD, and the chemistry's, NEW) bake the default scene in turns,
# REPEATS times each, in one run: benchmarks/bake/cost.sh on the `default`
# preset (each run's user, sys and wall time and peak memory, then the
# medians and the NEW / OLD ratio of the CPU time).
# Usage: benchmarks/chemistry/cost.sh OLD_BIN NEW_BIN [REPEATS]
set -euo pipefail
[ $# -ge 2 ] || { echo "usage: $0 OLD_BIN NEW_BIN [REPEATS]" >&2; exit 2; }
exec "$(dirname "$0")/../bake/cost.sh" "$1" "$2" default "${3:-3}"
