#!/usr/bin/env bash
# Builds the HFD tree of every freedoom2 map with the default options, one map at a time (each
# build uses both threads): per map, DIR/MAPnn.json (walkvis build --tree hfd --json) and
# DIR/MAPnn.time (/usr/bin/time: user s, system s, wall s, max RSS KiB). Tree files are deleted.
# Further arguments go to walkvis build (e.g. --no-fuse-occluders). MAPS="01 02 …" picks maps;
# TIMEOUT=S stops a map's build after S seconds (rc=124; allmaps.py then skips it; default none).
# usage: docs/hfd/allmaps.sh DIR [build options]   (then docs/hfd/allmaps.py DIR)
set -euo pipefail
[ $# -ge 1 ] || { echo "usage: $0 DIR [build options]" >&2; exit 2; }
root=$(cd "$(dirname "$0")/../.." && pwd)
W=$root/build/release/tools/walkvis/walkvis
out=$1
shift
[ -x "$W" ] || { echo "$0: $W not built (scripts/build release)" >&2; exit 2; }
[ -x /usr/bin/time ] || { echo "$0: needs /usr/bin/time (Debian package time)" >&2; exit 2; }
mkdir -p "$out"
for i in ${MAPS:-$(seq -w 1 32)}; do
  rc=0
  /usr/bin/time -f "%U %S %e %M" -o "$out/MAP$i.time" timeout "${TIMEOUT:-0}" "$W" build "freedoom2.wad:MAP$i" --tree hfd "$@" \
    -o "$out/MAP$i.wvt" --json >"$out/MAP$i.json" 2>"$out/MAP$i.err" || rc=$?
  echo "MAP$i rc=$rc $(cat "$out/MAP$i.time")"
  rm -f "$out/MAP$i.wvt"
done
