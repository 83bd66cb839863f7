#!/usr/bin/env python3
"""Writes the bad-input corpus: for each bad file NAME.EXT, NAME.EXT.expected holds a substring that
`walkvis info NAME.EXT` (run in this folder) must print on stderr. A NAME.spec file holds a scene
argument to pass instead of a file. tests/test_bad_input.cpp runs them all.
Run from this folder: python3 make_bad_input.py (reads ../models/ for the binary cases).
"""
import json, os

CASES = {}

def case(name, content, expected):
    CASES[name] = (content.encode() if isinstance(content, str) else content, expected)

quad = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
# ---- scene arguments (.spec: the argument itself)
case("missing.spec", "does_not_exist.obj", "does_not_exist.obj: cannot open")
case("missing_map.spec", "../models/tiny.wad:MAP99", "MAP99")
case("wad_without_map_name.spec", "../models/tiny.wad", "MAP01")
case("bad_generator_param.spec", "gen:office?rooms=-3", "rooms")
case("unknown_generator.spec", "gen:nosuchthing", "nosuchthing")
case("unknown_generator_param.spec", "gen:office?colour=red", "colour")
case("generator_param_not_key_value.spec", "gen:office?rooms", "rooms")
case("unknown_extension.xyz", "hello\n", "unknown scene format '.xyz'")
# ---- OBJ
case("truncated.obj", "# cut off while writing\nv 0 0 0\nv 1 0 0\nv 1 1", "truncated.obj:4: vertex needs 3 coordinates")
case("non_numeric.obj", "v 0 0 0\nv 1 0 0\nv 1 abc 0\nf 1 2 3\n", "non_numeric.obj:3: bad number 'abc'")
case("index_out_of_range.obj", quad + "f 1 2 9\n", "index_out_of_range.obj:5: face index 9 out of range (4 vertices)")
case("negative_index_out_of_range.obj", quad + "f -1 -2 -5\n",
     "negative_index_out_of_range.obj:5: face index -5 out of range (4 vertices so far)")
case("zero_index.obj", quad + "f 0 1 2\n", "zero_index.obj:5: face index 0")
case("nan.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n", "nan.obj:2: non-finite number 'nan'")
case("inf.obj", "v 0 0 0\nv 1 0 0\nv 0 inf 0\nf 1 2 3\n", "inf.obj:3: non-finite number 'inf'")
case("overflow.obj", "v 0 0 0\nv 1e400 0 0\nv 0 1 0\nf 1 2 3\n", "overflow.obj:2: number '1e400' is out of range")
case("two_vertex_face.obj", quad + "f 1 2\n", "two_vertex_face.obj:5: face with 2 vertices")
case("empty.obj", "", "empty.obj: no faces")
case("no_faces.obj", quad, "no_faces.obj: no faces")
case("all_degenerate.obj", quad + "f 1 1 2\nf 1 2 1\nv 2 0 0\nf 1 2 5\n", "empty scene")
case("binary_garbage.obj", bytes((i * 151 + 7) % 256 for i in range(512)), "binary_garbage.obj")

# ---- glTF
cube = json.load(open("../models/cube.gltf"))
def gltf(name, edit, expected):
    doc = json.loads(json.dumps(cube))
    edit(doc)
    case(name, json.dumps(doc, indent=1) + "\n", expected)

case("malformed_json.gltf", '{"asset": {"version": "2.0"}, "scenes": [\n', "malformed_json.gltf: malformed glTF")
case("not_json.gltf", "this is not json\n", "not_json.gltf: malformed glTF")
gltf("accessor_out_of_range.gltf", lambda d: d["accessors"][0].update(count=9),
     "accessor_out_of_range.gltf: mesh 0 primitive 0: accessor 0 (offset 0, 9 elements")
gltf("gltf_index_out_of_range.gltf", lambda d: d["accessors"][0].update(count=6), "index 6 out of range (6 vertices)")
gltf("gltf_node_cycle.gltf", lambda d: d["nodes"][1].update(children=[0]), "node 0 is reached twice")
gltf("gltf_buffer_view_out_of_range.gltf", lambda d: d["bufferViews"][1].update(byteLength=1000),
     "out of range of its buffer")
gltf("gltf_no_version.gltf", lambda d: d.pop("asset"), "malformed glTF")
gltf("gltf_external_buffer_missing.gltf", lambda d: d["buffers"][0].update(uri="no_such_buffer.bin"),
     "no_such_buffer.bin")
case("gltf_deep_nesting.gltf", '{"asset": {"version": "2.0"}, "extras": ' + "[" * 1000 + "]" * 1000 + "}\n",
     "gltf_deep_nesting.gltf: malformed glTF: JSON nested deeper than")
glb = open("../models/cube.glb", "rb").read()
case("truncated.glb", glb[:100], "truncated.glb: truncated GLB (header says 908 bytes, file has 100)")
case("truncated_header.glb", glb[:7], "truncated_header.glb: truncated GLB header")
case("bad_magic.glb", b"GLTF" + glb[4:], "bad_magic.glb: not a GLB file (bad magic)")
case("bad_json_chunk_length.glb", glb[:12] + b"\xff\xff\x00\x00" + glb[16:], "bad_json_chunk_length.glb: malformed glTF")

# ---- WAD
wad = open("../models/tiny.wad", "rb").read()
case("truncated.wad", wad[:8], "truncated.wad: truncated WAD header")
case("truncated_directory.wad", wad[:200], "truncated_directory.wad: truncated WAD directory")
case("bad_magic.wad", b"XWAD" + wad[4:], "bad_magic.wad: not a WAD file (bad magic)")

for name in os.listdir("."):
    if name.endswith(".py") or name.endswith(".md"):
        continue
    os.remove(name)
for name, (content, expected) in sorted(CASES.items()):
    open(name, "wb").write(content)
    open(name + ".expected", "w").write(expected + "\n")
print(len(CASES), "cases")
