#!/usr/bin/env bash
# Sampled against conservative HFD trees (issue table of docs/hfd/README.md, "Sampled and
# conservative"): per scene, builds `--tree hfd` in both modes one after the other (each build uses
# both threads), then `walkvis stats` on each tree with enough views per level for at least EYES
# eyes (default 4,000) at --res 64. Writes DIR/NAME.MODE.{json,time,stats.json}; trees are kept as
# DIR/NAME.MODE.wvt until the stats ran. WALKVIS=path picks the binary (default the Release build);
# SCENES="name=scene …" picks scenes (default below); PHASE=build|stats|all (default all).
# usage: docs/hfd/modes.sh DIR   (then docs/hfd/modes.py DIR)
set -euo pipefail
[ $# -ge 1 ] || { echo "usage: $0 DIR" >&2; exit 2; }
root=$(cd "$(dirname "$0")/../.." && pwd)
W=${WALKVIS:-$root/build/release/tools/walkvis/walkvis}
out=$1
[ -x "$W" ] || { echo "$0: $W not built (scripts/build release)" >&2; exit 2; }
[ -x /usr/bin/time ] || { echo "$0: needs /usr/bin/time (Debian package time)" >&2; exit 2; }
d2=freedoom2.wad d1=/usr/share/games/doom/freedoom1.wad
default_scenes="MAP01=$d2:MAP01 MAP02=$d2:MAP02 MAP04=$d2:MAP04 MAP05=$d2:MAP05 MAP06=$d2:MAP06
MAP07=$d2:MAP07 MAP08=$d2:MAP08 MAP09=$d2:MAP09 E1M1=$d1:E1M1 E1M2=$d1:E1M2 E1M3=$d1:E1M3
office10k=gen:office?rooms=300&furniture=6"
mkdir -p "$out"
for entry in ${SCENES:-$default_scenes}; do
  name=${entry%%=*} scene=${entry#*=}
  for mode in sampled conservative; do
    base=$out/$name.$mode
    if [ "${PHASE:-all}" != stats ]; then
      rc=0
      /usr/bin/time -f "%U %S %e %M" -o "$base.time" "$W" build "$scene" --tree hfd --visibility "$mode" \
        -o "$base.wvt" --json >"$base.json" 2>"$base.err" || rc=$?
      echo "$name $mode build rc=$rc $(cat "$base.time")"
    fi
    if [ "${PHASE:-all}" != build ] && [ -f "$base.wvt" ]; then
      levels=$(python3 -c "import json,sys; print(len({t['level'] for t in json.load(open(sys.argv[1]))['trees']}))" "$base.json")
      views=$(( (${EYES:-4000} + levels - 1) / levels ))
      [ "$views" -ge 100 ] || views=100
      rc=0
      "$W" stats "$base.wvt" --views "$views" --res 64 --json >"$base.stats.json" 2>/dev/null || rc=$?
      echo "$name $mode stats rc=$rc views=$views"
    fi
  done
done
