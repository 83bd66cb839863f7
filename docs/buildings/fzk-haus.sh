#!/usr/bin/env bash
# The whole pipeline on the KIT FZK-Haus IFC model (Debian package assimp-testmodels): load and
# levels (with plan PNGs), the BSP, an HFD tree, order validation, rejection statistics, frames
# from inside and frame times. Writes into DIR: info.json, plan/level-K.png, bench-bsp.json,
# hfd.json (+ hfd.time: user s, system s, wall s, max RSS KiB), validate-bsp.json,
# validate-hfd.json, stats.json, frames/ (render), bench-frames.json. The tree file is deleted.
# usage: docs/buildings/fzk-haus.sh DIR [HFD_SAMPLES]   (default samples 4,2,16 and view cells
# planned for 1 GiB trees). The HFD tree covers the areas of at least 40 m2 (the garden): trees of
# the rooms take hours on two cores (README.md). FULL=1 builds every level.
set -euo pipefail
[ $# -ge 1 ] || { echo "usage: $0 DIR [R,P,REFINE]" >&2; exit 2; }
root=$(cd "$(dirname "$0")/../.." && pwd)
W=$root/build/release/tools/walkvis/walkvis out=$1 samples=${2:-4,2,16}
F=/usr/share/assimp/models/IFC/AC14-FZK-Haus.ifc
[ -x "$W" ] || { echo "$0: $W not built (scripts/build release)" >&2; exit 2; }
[ -f "$F" ] || { echo "$0: $F missing (apt-get install assimp-testmodels)" >&2; exit 2; }
[ -x /usr/bin/time ] || { echo "$0: needs /usr/bin/time (Debian package time)" >&2; exit 2; }
mkdir -p "$out"
step() { echo "$(date +%T) $*" >&2; }
step info; "$W" info "$F" --json --plan "$out/plan" >"$out/info.json"
step "bench bsp"; "$W" bench bsp --scenes "$F" --runs 1 --json >"$out/bench-bsp.json"
step "build --tree hfd --samples $samples"
/usr/bin/time -f "%U %S %e %M" -o "$out/hfd.time" "$W" build "$F" -o "$out/fzk.wvt" --tree hfd --samples "$samples" \
  --cell-memory 1G --max-memory 4G $([ "${FULL:-0}" = 1 ] || echo --min-level-area 40) --json >"$out/hfd.json" 2>"$out/hfd.err"
min_area=(); [ "${FULL:-0}" = 1 ] || min_area=(--min-level-area 40)
step "validate --order bsp"; "$W" validate "$F" --order bsp --views 100 --size 64 --zbits 24 --json >"$out/validate-bsp.json"
step "validate --order hfd"; "$W" validate "$out/fzk.wvt" --order hfd --views 100 --size 64 --zbits none --json \
  >"$out/validate-hfd.json"
step stats; "$W" stats "$out/fzk.wvt" --views 50 --res 64 --json >"$out/stats.json"
# Views from inside: the kitchen and the spiral stair, the living room, the attic under the roof.
printf 'time,x,y,z,yaw,pitch\n0,2.0,1.7,-1.2,-0.9,-0.05\n1,6.5,1.7,-4.5,2.4,-0.05\n2,6.0,4.4,-5.0,1.2,-0.05\n' \
  >"$out/inside.csv"
step render; "$W" render "$out/fzk.wvt" --scene "$F" "${min_area[@]}" --path "$out/inside.csv" --frames 3 --size 640x400 --out "$out/frames"
step "bench frames"; "$W" bench frames "$out/fzk.wvt" --scene "$F" "${min_area[@]}" --frames 60 --json >"$out/bench-frames.json"
rm -f "$out/fzk.wvt"
step done
