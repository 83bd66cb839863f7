#!/bin/bash
# HFD build time of two walkvis binaries on the same scenes, alternating, two rounds:
#   docs/hfd/ab.sh BASE_WALKVIS NEW_WALKVIS OUT_DIR
# Prints one line per build: round, binary, scene, wall s, user s, system s, then trees_seconds,
# tests, rays and bytes from `walkvis build --json`. Build BASE at the older commit in a worktree
# (scripts/build release there).
set -euo pipefail
base=$1 new=$2 out=$3
mkdir -p "$out"
summary() {
  python3 - "$1" <<'PY'
import json, sys
j = json.load(open(sys.argv[1])); t = j["trees"]
print("trees_s %.1f tests %d rays %d bytes %d" % (j["trees_seconds"], sum(x["visibility_tests"] for x in t),
      sum(x["visibility_rays"] for x in t), j["total_bytes"]))
PY
}
for round in 1 2; do
  for scene in "gen:office?rooms=300&furniture=6" "freedoom2.wad:MAP01" "freedoom2.wad:MAP10"; do
    tag=$(echo "$scene" | tr -c 'A-Za-z0-9\n' '_')
    for v in base new; do
      bin=$base; [ "$v" = new ] && bin=$new
      /usr/bin/time -f "%e %U %S" -o "$out/$tag-$v-$round.time" "$bin" build "$scene" --tree hfd \
        -o "$out/$tag-$v.wvt" --json > "$out/$tag-$v-$round.json" 2>/dev/null
      echo "$round $v $scene $(cat "$out/$tag-$v-$round.time") $(summary "$out/$tag-$v-$round.json")"
    done
  done
done
