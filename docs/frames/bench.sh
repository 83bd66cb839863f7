#!/usr/bin/env bash
# Makes the tables of docs/frames/README.md again: bench frames on each scene with its default HFD
# tree, three times: with the frames' frustum and occlusion culling (the defaults), with frustum
# culling alone (--no-occlusion-culling), and with neither (--no-frustum-culling too).
# usage: docs/frames/bench.sh DIR [ROUNDS]   (SCENES="a b" overrides the scenes; WALKVIS=binary)
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
W=${WALKVIS:-"$root/build/release/tools/walkvis/walkvis"}  # WALKVIS=other binary, for a baseline
dir=${1:?usage: docs/frames/bench.sh DIR [ROUNDS]}
rounds=${2:-20}
doom=/usr/share/games/doom
mkdir -p "$dir"
if [[ -n "${SCENES:-}" ]]; then
  read -r -a scenes <<< "$SCENES"
else
  scenes=(gen:office "gen:office?rooms=300&furniture=6" "$doom/freedoom2.wad:MAP01" "$doom/freedoom2.wad:MAP08"
          "$doom/freedoom1.wad:E1M1")
fi
name_of() { basename "$1" | tr ':.?&=' '_____'; }
for s in "${scenes[@]}"; do
  name=$(name_of "$s")
  [[ -f "$dir/$name.wvt" ]] || "$W" build "$s" --tree hfd -o "$dir/$name.wvt" > /dev/null 2>&1
  "$W" bench frames "$dir/$name.wvt" --scene "$s" --frames 120 --rounds "$rounds" --json > "$dir/$name.json" 2>/dev/null
  "$W" bench frames "$dir/$name.wvt" --scene "$s" --frames 120 --rounds "$rounds" --no-occlusion-culling --json \
    > "$dir/$name.frustum.json" 2>/dev/null
  "$W" bench frames "$dir/$name.wvt" --scene "$s" --frames 120 --rounds "$rounds" --no-occlusion-culling \
    --no-frustum-culling --json > "$dir/$name.all.json" 2>/dev/null
done
pairs=()
for s in "${scenes[@]}"; do pairs+=("$(name_of "$s")" "$s"); done
python3 - "$dir" "${pairs[@]}" <<'PY'
import json, sys
d = sys.argv[1]
names, scenes = sys.argv[2::2], sys.argv[3::2]
print("| scene | culling | z-buffer ms (drawn) | floor ms | ideal ms (drawn) | ideal speed-up | "
      "BSP ms (drawn, occluded), of the ideal | "
      "HFD+region ms (drawn, outside, occluded) | HFD speed-up | HFD of the ideal, paired (even, odd rounds) | "
      "range over the six HFD modes, paired |")
print("|---|---|---|---|---|---|---|---|---|---|---|")
for s, name in zip(scenes, names):
    for suffix, label in (("", "frustum + occlusion"), (".frustum", "frustum"), (".all", "none")):
        j = json.load(open(f"{d}/{name}{suffix}.json"))
        modes = {m["mode"]: m for m in j["modes"]}
        z, b, h = modes["zbuffer"], modes["bsp"], modes["hfd+region"]
        hfd = [m["ideal_fraction_paired"] for m in j["modes"] if m["mode"].startswith("hfd+")]
        even, odd = h["ideal_fraction_paired_halves"]
        print(f"| {s.rsplit('/', 1)[-1]} | {label} | {z['frame_ms_median']:.3f} ({z['drawn_median']:.0f}) | "
              f"{j['floor_ms_median']:.3f} | {j['ideal_ms_median']:.3f} ({j['ideal_drawn_median']:.0f}) | "
              f"{j['ideal_speedup']:.2f} | {b['frame_ms_median']:.3f} ({b['drawn_median']:.0f}, {b['occluded_median']:.0f}), "
              f"{100 * b['ideal_fraction_paired']:.1f}% | "
              f"{h['frame_ms_median']:.3f} ({h['drawn_median']:.0f}, {h['outside_median']:.0f}, {h['occluded_median']:.0f}) | "
              f"{h['speedup_vs_zbuffer']:.2f} | {100 * h['ideal_fraction_paired']:.1f}% ({100 * even:.1f}%, {100 * odd:.1f}%) | "
              f"{100 * min(hfd):.1f}–{100 * max(hfd):.1f}% |")
PY
