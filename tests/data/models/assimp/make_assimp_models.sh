#!/usr/bin/env bash
# Writes the small assimp test and fuzz-seed models from ../cube.obj with `assimp export`
# (Debian's assimp-utils): the unit cube as Collada, ASCII FBX (assimp 5.2 cannot read back its
# own binary FBX), ASCII and binary PLY and STL, 3DS, and a hand-written OFF. tiny.ifc is written
# by hand (assimp has no IFC exporter): one 4 m x 0.2 m x 3 m wall in millimetres, z-up.
# Run from this folder: ./make_assimp_models.sh
set -euo pipefail
src=../cube.obj
assimp export "$src" cube.dae -fcollada >/dev/null
assimp export "$src" cube.fbx -ffbxa >/dev/null
assimp export "$src" cube.ply -fply >/dev/null
assimp export "$src" cube_binary.ply -fplyb >/dev/null
assimp export "$src" cube.stl -fstl >/dev/null
assimp export "$src" cube_binary.stl -fstlb >/dev/null
assimp export "$src" cube.3ds -f3ds >/dev/null
cat >cube.off <<'END_OFF'
OFF
8 6 0
0 0 0
1 0 0
1 1 0
0 1 0
0 0 1
1 0 1
1 1 1
0 1 1
4 0 3 2 1
4 4 5 6 7
4 0 1 5 4
4 3 7 6 2
4 0 4 7 3
4 1 2 6 5
END_OFF
