#!/usr/bin/env python3
"""Per-tree and per-map tables from `walkvis build SCENE -o F --json` outputs (docs/pfd/allmaps.sh).

usage: trees.py DIR [--csv trees.csv]

Prints, per map, the trees, nodes, bytes, the area-weighted mean tests over the entropy bound and
the trees flagged optimal; then every tree whose exact mean tests (tests_area_mean) is over 1.3 x
its entropy bound, with why: `bound` where max(Huffman, cell) bound is itself over 1.3 x entropy
(no tree over these leaves meets it), `optimal` where the root search proved the tree optimal among
trees testing the BSP's lines, `open` otherwise.
"""
import csv, glob, json, os, sys
from collections import Counter

d = sys.argv[1]
out_csv = sys.argv[sys.argv.index('--csv') + 1] if '--csv' in sys.argv else None
fields = ['scene', 'level', 'cell', 'fragments', 'nodes', 'bytes', 'tests_area_mean', 'tests_mean', 'tests_max',
          'tests_entropy_bound', 'tests_huffman_bound', 'tests_cell_bound', 'tests_optimal', 'root_search_lines',
          'root_search_work_done', 'log43_N', 'stored_entries', 'entries_bound', 'build_seconds', 'region_area']
rows, over, maps = [], [], []
for f in sorted(glob.glob(os.path.join(d, '*.json'))):
    scene = os.path.basename(f)[:-5]
    j = json.load(open(f))
    trees = j['trees']
    area = sum(t['region_area'] for t in trees)
    mean = sum(t['tests_area_mean'] * t['region_area'] for t in trees) / area
    ent = sum(t['tests_entropy_bound'] * t['region_area'] for t in trees) / area
    timing = f[:-5] + '.time'  # /usr/bin/time -f '%U %S %e %M': user s of the whole build
    user = float(open(timing).read().split()[0]) if os.path.exists(timing) else float('nan')
    maps.append((scene, len(trees), sum(t['nodes'] for t in trees), j['total_bytes'] / 1e6, mean / ent,
                 sum(t['tests_optimal'] for t in trees), max(t['tests_mean'] / t['log43_N'] for t in trees),
                 j['trees_over_entries_bound'], user))
    for t in trees:
        rows.append({'scene': scene, **{k: t[k] for k in fields[1:]}})
        h, m = t['tests_entropy_bound'], t['tests_area_mean']
        if h > 0 and m > 1.3 * h:
            lb = max(t['tests_huffman_bound'], t['tests_cell_bound'])
            why = 'bound' if lb > 1.3 * h else 'optimal' if t['tests_optimal'] else 'open'
            over.append((scene, t['level'], t['cell'], t['nodes'], t['root_search_lines'], m, h, lb, m / h, why))
print('| scene | trees | nodes | MB | mean / entropy (area-weighted) | optimal trees | max tests_mean / log43 N | over entries bound | build CPU s |')
print('|---|---|---|---|---|---|---|---|---|')
for s in maps:
    print('| %s | %d | %d | %.1f | %.3f | %d | %.3f | %d | %.1f |' % s)
print()
print('| scene | level | cell | nodes | root lines | mean tests | entropy | max(Huffman, cell) | mean / entropy | why |')
print('|---|---|---|---|---|---|---|---|---|---|')
for o in over:
    print('| %s | %d | %d | %d | %d | %.3f | %.3f | %.3f | %.3f | %s |' % o)
print()
print('trees %d, flagged optimal %d, over 1.3 x entropy %d: %s' % (
    len(rows), sum(r['tests_optimal'] for r in rows), len(over), dict(Counter(o[-1] for o in over))))
if out_csv:
    with open(out_csv, 'w', newline='') as fh:
        w = csv.DictWriter(fh, fieldnames=fields)
        w.writeheader()
        w.writerows(rows)
