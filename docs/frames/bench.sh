#!/usr/bin/env bash
# Frame times against their floor and the ideal (docs/frames/README.md): builds the HFD trees of
# the office and three Freedoom maps into DIR, then runs `walkvis bench frames` on each and prints
# one table per scene. Usage: docs/frames/bench.sh DIR [ROUNDS]. Run it on an idle machine.
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
W="$root/build/release/tools/walkvis/walkvis"
dir=${1:?usage: docs/frames/bench.sh DIR [ROUNDS]}
rounds=${2:-5}
doom=/usr/share/games/doom
mkdir -p "$dir"
scenes=(gen:office "$doom/freedoom2.wad:MAP01" "$doom/freedoom2.wad:MAP08" "$doom/freedoom1.wad:E1M1")
for s in "${scenes[@]}"; do
  name=$(basename "$s" | tr ':.' '__')
  [[ -f "$dir/$name.wvt" ]] || "$W" build "$s" --tree hfd -o "$dir/$name.wvt" > /dev/null 2>&1
  "$W" bench frames "$dir/$name.wvt" --scene "$s" --frames 120 --rounds "$rounds" --json > "$dir/$name.json" 2>/dev/null
done
python3 - "$dir" "${scenes[@]}" <<'PY'
import json, sys
d = sys.argv[1]
for s in sys.argv[2:]:
    name = s.rsplit('/', 1)[-1].replace(':', '_').replace('.', '_')
    j = json.load(open(f"{d}/{name}.json"))
    print(f"\n{s}: {j['scene_polygons']} fragments, {j['frames']} frames x {j['rounds']} rounds; "
          f"floor {j['floor_ms_median']:.3f} ms, ideal {j['ideal_ms_median']:.3f} ms drawing "
          f"{j['ideal_drawn_median']:.0f} ({j['ideal_speedup']:.2f}x the z-buffer)")
    print("| mode | frame ms | round spread | drawn | speed-up | of the ideal | pixels off |")
    print("|---|---|---|---|---|---|---|")
    for m in j["modes"]:
        print(f"| {m['mode']} | {m['frame_ms_median']:.3f} | {100 * m['frame_ms_round_spread']:.0f}% | "
              f"{m['drawn_median']:.0f} | {m['speedup_vs_zbuffer']:.2f} | {100 * m['ideal_fraction']:.0f}% | "
              f"{m['pixels_differing_from_zbuffer']} |")
PY
