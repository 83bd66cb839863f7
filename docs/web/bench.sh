#!/usr/bin/env bash
# docs/web/bench.sh [WORK_DIR] [RUNS]: the figures of docs/web/README.md. Builds the HFD trees of
# the office, freedoom2 MAP01 and FZK-Haus into WORK_DIR (default /tmp/walkvis-web-bench; trees
# already there are kept: FZK-Haus's takes about 12 minutes on 2 cores), exports each deflated
# and raw (--raw), and opens each export RUNS times (default 5) with ?bench in headless Chromium
# (docs/web/bench.js), from file:// (walkvis-data.js) and from a local static server (python3
# -m http.server: walkvis.bin). Prints one JSON line per page open, then tables of medians.
# Needs a Release build (scripts/build release).
set -euo pipefail
root="$(cd "$(dirname "$0")/../.." && pwd)"
walkvis="$root/build/release/tools/walkvis/walkvis"
work="${1:-/tmp/walkvis-web-bench}"
runs="${2:-5}"
query='bench=20&reps=5&size=640x480'
mkdir -p "$work"
port=8765
python3 -m http.server "$port" --bind 127.0.0.1 --directory "$work" > "$work/server.log" 2>&1 &
server=$!
trap 'kill $server' EXIT
declare -A scenes=(
  [office]='gen:office?rooms=12&seed=4'
  [map01]='/usr/share/games/doom/freedoom2.wad:MAP01'
  [fzk]='/usr/share/assimp/models/IFC/AC14-FZK-Haus.ifc'
)
for name in office map01 fzk; do
  scene="${scenes[$name]}"
  [ -f "$work/$name.hfd" ] || "$walkvis" build "$scene" --tree hfd --threads 2 -o "$work/$name.hfd" > "$work/$name.build.txt"
  "$walkvis" export "$work/$name.hfd" --scene "$scene" --web "$work/${name}_web" > "$work/$name.export.txt" 2>&1
  "$walkvis" export "$work/$name.hfd" --scene "$scene" --web "$work/${name}_raw" --raw > "$work/$name.raw.txt" 2>&1
done
# One browser opens every page, the variants alternating so that drift in the machine's speed
# falls on all alike; first one page not counted (the browser's first page starts its renderer).
urls=("file://$work/office_web/index.html?frame=0")
for name in office map01 fzk; do
  for _ in $(seq "$runs"); do
    for variant in web raw; do
      urls+=("file://$work/${name}_$variant/index.html?$query" "http://127.0.0.1:$port/${name}_$variant/index.html?$query")
    done
  done
done
node "$root/docs/web/bench.js" "${urls[@]}" | tail -n +2 > "$work/bench.jsonl"
python3 - "$work" <<'EOF'
import json, os, statistics, sys
work = sys.argv[1]
rows = {}
for line in open(os.path.join(work, 'bench.jsonl')):
    r = json.loads(line)
    src, _, rest = r['url'].partition('://')
    folder = rest.split('/')[-2]  # NAME_web or NAME_raw
    scene, _, variant = folder.rpartition('_')
    rows.setdefault((scene, variant, src), []).append(r['page'])
med = statistics.median
print("Load (medians, ms from the navigation's start): page.js started, bytes in hand, walkvis.bin read and checked (load),")
print("the view cells of the bench keys in (cells).")
print('| scene | export | from | bytes read | page.js | bytes | load | parse | cells |')
print('|---|---|---|---|---|---|---|---|---|')
for (scene, variant, src), pages in rows.items():
    d = os.path.join(work, scene + '_' + variant)
    f, ext = ('walkvis-data.js', '.js') if src == 'file' else ('walkvis.bin', '.bin')
    cells = (pages[0].get('cells_loaded') or '').split(',')
    read = os.path.getsize(os.path.join(d, f)) + sum(os.path.getsize(os.path.join(d, 'cells', k + ext)) for k in cells if k)
    m = lambda key: med(p[key] for p in pages)
    print('| {} | {} | {} | {:,} B ({} and {} cells) | {:.0f} | {:.0f} | {:.0f} | {:.0f} | {:.0f} |'.format(
        scene, variant, src, read, f, len([k for k in cells if k]), m('script_ms'), m('bytes_ms'), m('load_ms'),
        m('parse_ms'), m('cells_ms')))
print()
print('Frames (medians over all opens; 640x480, 20 tour keys x 5 repetitions per open).')
print('| scene | fragments | floor | z-buffer | BSP | HFD (order + GL calls + wait) | HFD order (mean) | BSP order (mean) | drawn | HFD speed-up over the z-buffer |')
print('|---|---|---|---|---|---|---|---|---|---|')
scenes = {}
for (scene, variant, src), pages in rows.items():
    scenes.setdefault(scene, []).extend(pages)
for scene, pages in scenes.items():
    m = lambda mode, key='frame_ms_median': med(p['bench']['modes'][mode][key] for p in pages)
    b = pages[0]['bench']
    print('| {} | {:,} | {:.1f} ms | {:.1f} ms | {:.1f} ms | {:.1f} ms ({:.1f} + {:.1f} + {:.1f}) | {:.0f} µs | {:.0f} µs | {:.0f} | {:.1f}× |'.format(
        scene, b['fragments'], m('floor'), m('zbuffer'), m('bsp'), m('hfd'), m('hfd', 'order_ms_median'),
        m('hfd', 'submit_ms_median'), m('hfd', 'wait_ms_median'), m('hfd', 'order_us_mean'), m('bsp', 'order_us_mean'),
        b['modes']['hfd']['drawn_mean'], m('zbuffer') / m('hfd')))
EOF
