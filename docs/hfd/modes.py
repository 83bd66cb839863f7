#!/usr/bin/env python3
"""Tables of docs/hfd/modes.sh: per scene and mode, eyes, eyes with a miss, pixel error ratio, worst
eye, rejection, build wall and CPU seconds and tree bytes; then per scene the conservative mode
against the sampled one (rejection ratio, CPU ratio). usage: docs/hfd/modes.py DIR"""
import json
import pathlib
import sys


def load(out, name, mode):
    base = out / f"{name}.{mode}"
    try:
        build = json.loads(pathlib.Path(f"{base}.json").read_text())
        stats = json.loads(pathlib.Path(f"{base}.stats.json").read_text())
    except (FileNotFoundError, json.JSONDecodeError):
        return None
    user, system, wall, _ = pathlib.Path(f"{base}.time").read_text().split()[:4]
    o = stats["overall"]
    return {"fragments": build["fragments"], "eyes": o["eyes"], "miss": o["eyes_with_miss"],
            "missed_eyes": o["eyes"] - o["missed_histogram"]["0"], "pixel": o["pixel_error_ratio"],
            "worst": o["pixel_error_ratio_max"], "rejection": o["rejection_ratio"], "wall": float(wall),
            "cpu": float(user) + float(system), "bytes": build["total_bytes"],
            "proved": build.get("visibility_proved_hidden", 0), "kept": build.get("visibility_kept_unproven", 0)}


def main():
    if len(sys.argv) != 2:
        print(__doc__.strip().splitlines()[-1], file=sys.stderr)
        return 2
    out = pathlib.Path(sys.argv[1])
    names = sorted({p.name.split(".")[0] for p in out.glob("*.sampled.json")})
    rows = {}
    print("| scene | mode | fragments | eyes | eyes with a miss | pixel error ratio | worst eye | rejection |"
          " wall s | CPU s | tree bytes |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for name in names:
        for mode in ("sampled", "conservative"):
            r = load(out, name, mode)
            if r is None:
                print(f"{name} {mode}: no finished build and stats", file=sys.stderr)
                continue
            rows[name, mode] = r
            print(f"| {name} | {mode} | {r['fragments']:,} | {r['eyes']:,} | {100 * r['miss']:.2f}% ({r['missed_eyes']}) |"
                  f" {r['pixel']:.2e} | {r['worst']:.2e} | {100 * r['rejection']:.2f}% | {r['wall']:.1f} |"
                  f" {r['cpu']:.1f} | {r['bytes']:,} |")
    print()
    print("| scene | rejection, conservative / sampled | CPU s, conservative / sampled | bytes, conservative / sampled |")
    print("|---|---|---|---|")
    for name in names:
        s, c = rows.get((name, "sampled")), rows.get((name, "conservative"))
        if s and c:
            print(f"| {name} | {c['rejection'] / s['rejection']:.4f} | {c['cpu'] / s['cpu']:.2f} |"
                  f" {c['bytes'] / s['bytes']:.3f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
