#!/usr/bin/env bash
# Builds the PFD trees of the two offices (1k and 10k polygons) and every freedoom2 map with the
# default options, two scenes at a time: per scene, DIR/NAME.json (walkvis build --json) and
# DIR/NAME.time (/usr/bin/time: user s, system s, wall s, max RSS KiB). Tree files are deleted.
# usage: docs/pfd/allmaps.sh DIR   (then docs/pfd/trees.py DIR)
set -euo pipefail
[ $# -eq 1 ] || { echo "usage: $0 DIR" >&2; exit 2; }
root=$(cd "$(dirname "$0")/../.." && pwd)
export W=$root/build/release/tools/walkvis/walkvis out=$1
[ -x "$W" ] || { echo "$0: $W not built (scripts/build release)" >&2; exit 2; }
[ -x /usr/bin/time ] || { echo "$0: needs /usr/bin/time (Debian package time)" >&2; exit 2; }
mkdir -p "$out"
scenes=("gen:office?rooms=32" "gen:office?rooms=404")
for i in $(seq -w 1 32); do scenes+=("freedoom2.wad:MAP$i"); done
run() {
  local s=$1 name rc=0
  name=$(echo "$s" | tr ':?=&/' '_____')
  /usr/bin/time -f "%U %S %e %M" -o "$out/$name.time" nice -n 10 "$W" build "$s" -o "$out/$name.wvt" --json \
    >"$out/$name.json" 2>"$out/$name.err" || rc=$?
  echo "$name rc=$rc $(cat "$out/$name.time")"
  rm -f "$out/$name.wvt"
}
export -f run
printf '%s\n' "${scenes[@]}" | xargs -P "${JOBS:-2}" -I{} bash -c 'run "{}"'
