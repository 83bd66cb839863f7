#!/usr/bin/env python3
"""Writes the small test models: cube.gltf (embedded base64 buffer), cube.glb and tiny.wad.

A unit cube [0,1]^3 of 12 triangles, counter-clockwise seen from outside, under a two-node tree:
node 0 translates by (10, 0, 0), its child node 1 scales by 2 and holds the mesh, so the cube
lands on [10,12] x [0,2] x [0,2]. The material's base colour is red (0xff0000).
tiny.wad is a PWAD with one Doom-format map, MAP01: a 256 x 256 room (floor 0, ceiling 128),
four one-sided linedefs listed clockwise so their right sides face in, and a player 1 start in
the middle.
Run from this folder: python3 make_models.py
"""
import base64, json, struct

V = [(0,0,0),(1,0,0),(1,1,0),(0,1,0),(0,0,1),(1,0,1),(1,1,1),(0,1,1)]
QUADS = [(0,3,2,1),(4,5,6,7),(0,1,5,4),(3,7,6,2),(0,4,7,3),(1,2,6,5)]
idx = []
for a,b,c,d in QUADS:
    idx += [a,b,c, a,c,d]
pos = b''.join(struct.pack('<3f', *v) for v in V)
ind = b''.join(struct.pack('<H', i) for i in idx)
blob = pos + ind  # 96 + 72 bytes, both 4-byte aligned

def doc(uri):
    buf = {"byteLength": len(blob)}
    if uri is not None:
        buf["uri"] = uri
    return {
        "asset": {"version": "2.0", "generator": "walkvis make_models.py"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"children": [1], "translation": [10, 0, 0]}, {"mesh": 0, "scale": [2, 2, 2]}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 0}]}],
        "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [1, 0, 0, 1]}}],
        "buffers": [buf],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": len(pos)},
                        {"buffer": 0, "byteOffset": len(pos), "byteLength": len(ind)}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 8, "type": "VEC3",
                       "min": [0, 0, 0], "max": [1, 1, 1]},
                      {"bufferView": 1, "componentType": 5123, "count": len(idx), "type": "SCALAR"}],
    }

with open('cube.gltf', 'w') as f:
    json.dump(doc("data:application/octet-stream;base64," + base64.b64encode(blob).decode()), f, indent=1)
    f.write('\n')

js = json.dumps(doc(None)).encode()
js += b' ' * ((4 - len(js) % 4) % 4)
glb = struct.pack('<I', len(js)) + b'JSON' + js + struct.pack('<I', len(blob)) + b'BIN\0' + blob
glb = b'glTF' + struct.pack('<II', 2, 12 + len(glb)) + glb
with open('cube.glb', 'wb') as f:
    f.write(glb)


def name8(n):
    return n.encode().ljust(8, b'\0')

verts = [(0, 0), (0, 256), (256, 256), (256, 0)]  # clockwise: right sides face the room
vertexes = b''.join(struct.pack('<hh', x, y) for x, y in verts)
linedefs = b''.join(struct.pack('<HHHHHHH', i, (i + 1) % 4, 1, 0, 0, i, 0xFFFF) for i in range(4))
sidedefs = b''.join(struct.pack('<hh', 0, 0) + name8('-') + name8('-') + name8('STARTAN3') + struct.pack('<H', 0)
                    for _ in range(4))
sectors = struct.pack('<hh', 0, 128) + name8('FLOOR4_8') + name8('CEIL3_5') + struct.pack('<hHH', 160, 0, 0)
things = struct.pack('<hhHHH', 128, 128, 90, 1, 7)
lumps = [('MAP01', b''), ('THINGS', things), ('LINEDEFS', linedefs), ('SIDEDEFS', sidedefs),
         ('VERTEXES', vertexes), ('SECTORS', sectors)]
data = b''
directory = b''
offset = 12
for name, body in lumps:
    directory += struct.pack('<ii', offset if body else 0, len(body)) + name8(name)
    data += body
    offset += len(body)
with open('tiny.wad', 'wb') as f:
    f.write(b'PWAD' + struct.pack('<ii', len(lumps), 12 + len(data)) + data + directory)
