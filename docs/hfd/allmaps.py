#!/usr/bin/env python3
"""Table of the HFD builds of docs/hfd/allmaps.sh: per map, fragments, view cells, tree seconds,
bytes, rays, tests proved hidden; then the totals. usage: docs/hfd/allmaps.py DIR [--csv FILE]"""
import csv
import json
import pathlib
import sys

def main():
    args = sys.argv[1:]
    if not args:
        print(__doc__.strip().splitlines()[-1], file=sys.stderr)
        return 2
    out = pathlib.Path(args[0])
    csv_path = args[args.index("--csv") + 1] if "--csv" in args else None
    rows = []
    for path in sorted(out.glob("MAP*.json")):
        try:
            j = json.loads(path.read_text())
        except json.JSONDecodeError:
            print(f"{path}: not a finished build (see {path.with_suffix('.err')})", file=sys.stderr)
            continue
        user, system, wall, rss = path.with_suffix(".time").read_text().split()[:4]
        rows.append({
            "map": path.stem, "fragments": j["fragments"], "view_cells": j["view_cells"],
            "trees_seconds": j["trees_seconds"], "wall_seconds": float(wall), "cpu_seconds": float(user) + float(system),
            "bytes": j["total_bytes"], "tests": j["visibility_tests"], "rays": j["visibility_rays"],
            "proved_hidden": j.get("visibility_proved_hidden", 0), "rays_per_second": j["rays_per_second"],
            "max_rss_kib": int(rss)})
    if not rows:
        print(f"{out}: no finished builds", file=sys.stderr)
        return 2
    print("| map | fragments | cells | tree s | wall s | CPU s | bytes | tests | rays | proved hidden |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['map']} | {r['fragments']:,} | {r['view_cells']} | {r['trees_seconds']:.1f} | {r['wall_seconds']:.1f} |"
              f" {r['cpu_seconds']:.1f} | {r['bytes']:,} | {r['tests']:,} | {r['rays']:,} | {r['proved_hidden']:,} |")
    tot = lambda k: sum(r[k] for r in rows)
    print(f"| all {len(rows)} | {tot('fragments'):,} | {tot('view_cells')} | {tot('trees_seconds'):.1f} |"
          f" {tot('wall_seconds'):.1f} | {tot('cpu_seconds'):.1f} | {tot('bytes'):,} | {tot('tests'):,} | {tot('rays'):,} |"
          f" {tot('proved_hidden'):,} |")
    worst = max(rows, key=lambda r: r["wall_seconds"])
    print(f"slowest: {worst['map']} {worst['wall_seconds']:.1f} s wall")
    if csv_path:
        with open(csv_path, "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
            w.writeheader()
            w.writerows(rows)
    return 0

if __name__ == "__main__":
    sys.exit(main())
