#!/usr/bin/env bash
# The BSP splitting-plane knobs, each against the defaults (docs/bsp/README.md, "Knobs"): N/n,
# depth and build CPU of `walkvis bench bsp` (least-crossed) per scene and setting, one build each
# (N/n and depth are deterministic; CPU seconds are one run on a noisy machine).
# Usage: docs/bsp/knobs.sh [OUT_DIR]   (Release build: scripts/build release; SCENES=a,b for others)
set -euo pipefail
root=$(cd "$(dirname "$0")/../.." && pwd)
W=${WALKVIS:-$root/build/release/tools/walkvis/walkvis}
out=${1:-$root/out/bsp-knobs}
[ -x "$W" ] || { echo "$0: $W not built (scripts/build release)" >&2; exit 2; }
mkdir -p "$out"
wad=/usr/share/games/doom/freedoom2.wad
scenes=${SCENES:-"$wad:MAP10,$wad:MAP14,$wad:MAP26,gen:office?rooms=300&furniture=6,/usr/share/assimp/models/IFC/AC14-FZK-Haus.ifc"}
settings=(
  "default|"
  "free-first|--free-first true"
  "horizontal-weight-0.5|--horizontal-weight 0.5"
  "lookahead-max-0|--lookahead-max 0"
  "full-count-max-0|--full-count-max 0"
  "candidates-8|--candidates 8"
  "detail-extent-2|--detail-extent 2"
)
for s in "${settings[@]}"; do
  name=${s%%|*}
  read -r -a opts <<<"${s#*|}"
  echo "bench bsp: $name ${opts[*]:-}" >&2
  # bench bsp exits 1 when a scene misses its N/n target (FZK-Haus does) but still prints its JSON;
  # any other failure leaves JSON the table below cannot read, and the script stops there.
  rc=0
  "$W" bench bsp --scenes "$scenes" --runs 1 --json "${opts[@]}" >"$out/$name.json.tmp" || rc=$?
  [ "$rc" -le 1 ] || { echo "$0: bench bsp $name exited $rc" >&2; exit 2; }
  mv "$out/$name.json.tmp" "$out/$name.json"
done
python3 - "$out" "${settings[@]}" <<'PY'
import json, sys
out, settings = sys.argv[1], [s.split("|")[0] for s in sys.argv[2:]]
rows = {}
for name in settings:
    for scene in json.load(open(f"{out}/{name}.json"))["scenes"]:
        lc = next(r for r in scene["results"] if r["heuristic"] == "least-crossed")
        rows.setdefault(scene["scene"].split("/")[-1], {})[name] = lc
print("| setting | " + " | ".join(rows) + " |")
print("|---|" + "---|" * len(rows))
for name in settings:
    cells = []
    for scene, r in rows.items():
        x = r[name]
        cells.append(f"{x['ratio']:.3f}, depth {x['depth_mean']:.1f}, {x['build_cpu_seconds']:.2f} s")
    print(f"| {name} | " + " | ".join(cells) + " |")
PY
