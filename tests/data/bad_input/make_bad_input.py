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

# ---- assimp formats (scenes/assimp.cpp; seeds in ../models/assimp/)
tiny_ifc = open("../models/assimp/tiny.ifc", "rb").read()
cube_fbx = open("../models/assimp/cube.fbx", "rb").read()
cube_dae = open("../models/assimp/cube.dae", "rb").read()
# assimp 5.2's IFC reader crashes (SIGSEGV) on a cut-off file or a reference to an undefined
# entity: scenes/assimp.cpp refuses both first.
case("truncated.ifc", tiny_ifc[:700], "truncated.ifc: IFC DATA section does not end (no ENDSEC;): the file is truncated")
case("ifc_dangling_reference.ifc", b"\n".join(l for l in tiny_ifc.split(b"\n") if not l.startswith(b"#22=")),
     "ifc_dangling_reference.ifc: IFC entity #21 refers to #22, which the file does not define")
# An entity of a type name assimp does not know, referenced by another: assimp 5.2 dereferences
# null (found by fuzz_assimp); the import runs in a child process first and this is what it says.
case("ifc_unknown_entity.ifc", tiny_ifc.replace(b"IFCSHAPEREPRESENTATION(", b"IFCSHAPEREPRERENTATION("),
     "ifc_unknown_entity.ifc: assimp crashed reading it (signal 11")
case("not_ifc.ifc", "this is not an IFC file\n", "not_ifc.ifc: assimp: (line 1) expected magic token: ISO-10303-21")
case("empty.ifc", "", "empty.ifc: empty file")
# assimp 5.2's FBX parser leaks what it parsed when an ASCII FBX ends early (LeakSanitizer
# reports it inside libassimp, suppressed in tests/lsan.supp).
case("truncated.fbx", cube_fbx[:3000], "truncated.fbx: assimp: FBX-Parser")
case("binary_garbage.fbx", b"Kaydara FBX Binary  \x00\x1a\x00" + bytes((i * 151 + 7) % 256 for i in range(512)),
     "binary_garbage.fbx: assimp: FBX-")
case("garbage.dae", bytes((i * 151 + 7) % 256 for i in range(512)), "garbage.dae: assimp: Unable to read file, malformed XML")
case("truncated.dae", cube_dae[:4000], "truncated.dae: assimp: Unable to read file, malformed XML")
case("no_faces.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
     "end_header\n0 0 0\n1 0 0\n0 1 0\n", "no_faces.ply: no triangles (assimp: Validation failed: Mesh  contains no faces)")
case("lines_only.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n2 0 1\n", "lines_only.off: no triangles (assimp: No meshes remaining)")
# Collada node graphs that assimp 5.2 itself cannot survive (stack overflow, exponential
# expansion): refused by a scan before assimp sees them.
dae_head = ('<?xml version="1.0" encoding="utf-8"?>\n'
            '<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">\n'
            ' <asset><unit name="meter" meter="1"/><up_axis>Y_UP</up_axis></asset>\n'
            ' <library_geometries><geometry id="tri"><mesh>\n'
            '  <source id="p"><float_array id="pa" count="9">0 0 0 1 0 0 0 1 0</float_array><technique_common>'
            '<accessor source="#pa" count="3" stride="3"><param name="X" type="float"/><param name="Y" type="float"/>'
            '<param name="Z" type="float"/></accessor></technique_common></source>\n'
            '  <vertices id="v"><input semantic="POSITION" source="#p"/></vertices>\n'
            '  <triangles count="1"><input semantic="VERTEX" source="#v" offset="0"/><p>0 1 2</p></triangles>\n'
            ' </mesh></geometry></library_geometries>\n')
dae_tail = ' <scene><instance_visual_scene url="#scene"/></scene>\n</COLLADA>\n'
case("collada_instance_cycle.dae", dae_head +
     ' <library_nodes><node id="loop"><instance_node url="#loop"/><instance_geometry url="#tri"/></node></library_nodes>\n'
     ' <library_visual_scenes><visual_scene id="scene"><node id="top"><instance_node url="#loop"/></node>'
     '</visual_scene></library_visual_scenes>\n' + dae_tail,
     "collada_instance_cycle.dae: Collada node instances form a cycle")
case("collada_instance_explosion.dae", dae_head + ' <library_nodes>\n' +
     '<node id="n0"><instance_geometry url="#tri"/></node>\n' +
     ''.join('<node id="n%d"><instance_node url="#n%d"/><instance_node url="#n%d"/></node>\n' % (i, i - 1, i - 1)
             for i in range(1, 40)) +
     ' </library_nodes>\n <library_visual_scenes><visual_scene id="scene"><node id="top"><instance_node url="#n39"/>'
     '</node></visual_scene></library_visual_scenes>\n' + dae_tail,
     "collada_instance_explosion.dae: Collada node instances expand to more than")
case("collada_deep_nodes.dae", dae_head + ' <library_visual_scenes><visual_scene id="scene">\n' +
     ''.join('<node id="d%d">' % i for i in range(400)) + '<instance_geometry url="#tri"/>' + '</node>' * 400 +
     '\n </visual_scene></library_visual_scenes>\n' + dae_tail,
     "collada_deep_nodes.dae: Collada nodes nested deeper than 256 levels")

for name in os.listdir("."):
    if name.endswith(".py") or name.endswith(".md"):
        continue
    os.remove(name)
for name, (content, expected) in sorted(CASES.items()):
    open(name, "wb").write(content)
    open(name + ".expected", "w").write(expected + "\n")
print(len(CASES), "cases")
