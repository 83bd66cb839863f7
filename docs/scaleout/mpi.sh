#!/usr/bin/env bash
# The speed of `walkvis build` under `mpirun -n K` against one process, one thread per rank, in the
# same run: REPS alternating builds each, medians of the trees' seconds (the distributed part,
# the build JSON's trees_seconds) and of the whole command's wall time, their ratios, and whether
# every file is byte-identical to the first one-process build's.
# Usage: docs/scaleout/mpi.sh [SCENE] [RANKS] [REPS] [build options...]
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
walkvis="$root/build/release/tools/walkvis/walkvis"
scene=${1:-/usr/share/games/doom/freedoom2.wad:MAP01}
ranks=${2:-2}
reps=${3:-3}
shift $(( $# < 3 ? $# : 3 ))
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
run() {  # run NAME LAUNCHER...: one build, appends "trees wall" to $tmp/NAME
  local name=$1
  shift
  local t0 t1
  t0=$(date +%s.%N)
  "$@" "$walkvis" build "$scene" --tree hfd --threads 1 -o "$tmp/$name.wvt" --json "${extra[@]}" 2>/dev/null > "$tmp/$name.json"
  t1=$(date +%s.%N)
  python3 -c "import json,sys; print(json.load(open(sys.argv[1]))['trees_seconds'], float(sys.argv[3]) - float(sys.argv[2]))" \
    "$tmp/$name.json" "$t0" "$t1" >> "$tmp/$name.times"
  if [ ! -e "$tmp/ref.wvt" ]; then
    cp "$tmp/$name.wvt" "$tmp/ref.wvt"
  elif ! cmp -s "$tmp/$name.wvt" "$tmp/ref.wvt"; then
    echo "DIFFERENT BYTES: $name" >&2
    differ=1
  fi
}
extra=("$@")
differ=0
for ((i = 0; i < reps; ++i)); do
  run alone env
  run mpi mpirun --oversubscribe -n "$ranks"
done
python3 - "$tmp" "$scene" "$ranks" "$reps" <<'PY'
import statistics, sys
tmp, scene, ranks, reps = sys.argv[1:]
t = {n: [tuple(map(float, l.split())) for l in open(f"{tmp}/{n}.times")] for n in ("alone", "mpi")}
med = {n: (statistics.median(x[0] for x in v), statistics.median(x[1] for x in v)) for n, v in t.items()}
print(f"{scene}: {reps} builds each, medians")
print(f"  one process      trees {med['alone'][0]:.2f} s, whole command {med['alone'][1]:.2f} s")
print(f"  mpirun -n {ranks}      trees {med['mpi'][0]:.2f} s, whole command {med['mpi'][1]:.2f} s")
print(f"  speed-up         trees {med['alone'][0] / med['mpi'][0]:.2f}x, whole command {med['alone'][1] / med['mpi'][1]:.2f}x")
PY
[ "$differ" = 0 ] && echo "  all $((2 * reps)) tree files byte-identical"
exit "$differ"
