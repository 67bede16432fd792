#!/usr/bin/env python3
"""Seeds for the scene-format fuzzers (scripts/fuzz.sh): a small file of each format, into
SEEDS/ply, SEEDS/gltf, SEEDS/pbrt and SEEDS/ray_file. A quad in PLY ascii and both binary byte orders; a glTF
with a node hierarchy, a camera and a material as .gltf (buffer as a data URI) and as .glb; a
pbrt-v4 scene with each directive the loader reads."""
import base64, json, struct, sys
from pathlib import Path

seeds = Path(sys.argv[1])
quad = [(0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0)]

def ply(fmt, endian):
    head = (f"ply\nformat {fmt} 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
            "element face 1\nproperty list uchar int vertex_indices\nend_header\n").encode()
    if fmt == "ascii":
        return head + b"".join(f"{x} {y} {z}\n".encode() for x, y, z in quad) + b"4 0 1 2 3\n"
    body = b"".join(struct.pack(endian + "3f", *p) for p in quad) + struct.pack(endian + "B4i", 4, 0, 1, 2, 3)
    return head + body

(seeds / "ply/quad-ascii.ply").write_bytes(ply("ascii", ""))
(seeds / "ply/quad-le.ply").write_bytes(ply("binary_little_endian", "<"))
(seeds / "ply/quad-be.ply").write_bytes(ply("binary_big_endian", ">"))

binary = b"".join(struct.pack("<3f", *p) for p in quad) + struct.pack("<6H", 0, 1, 2, 0, 2, 3)
doc = {
    "asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0, 2]}],
    "nodes": [{"translation": [1, 0, 0], "children": [1]}, {"mesh": 0, "rotation": [0, 0.7071068, 0, 0.7071068]},
              {"camera": 0, "matrix": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 4, 1]}],
    "cameras": [{"type": "perspective", "perspective": {"yfov": 0.7, "znear": 0.1}}],
    "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.2, 0.2, 1]}}],
    "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 0}]}],
    "buffers": [{"byteLength": len(binary)}],
    "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 48}, {"buffer": 0, "byteOffset": 48, "byteLength": 12}],
    "accessors": [{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 0]},
                  {"bufferView": 1, "componentType": 5123, "count": 6, "type": "SCALAR"}],
}
text = dict(doc, buffers=[{"byteLength": len(binary),
                           "uri": "data:application/octet-stream;base64," + base64.b64encode(binary).decode()}])
(seeds / "gltf/quad.gltf").write_text(json.dumps(text))
js = json.dumps(doc).encode()
js += b" " * (-len(js) % 4)
data = binary + b"\0" * (-len(binary) % 4)
glb = struct.pack("<4sII", b"glTF", 2, 12 + 8 + len(js) + 8 + len(data)) + struct.pack("<II", len(js), 0x4E4F534A) + js
glb += struct.pack("<II", len(data), 0x004E4942) + data
(seeds / "gltf/quad.glb").write_bytes(glb)

(seeds / "pbrt/scene.pbrt").write_text("""Film "rgb" "integer xresolution" [64] "integer yresolution" [48]
LookAt 0 1 6  0 1 0  0 1 0
Camera "perspective" "float fov" [40]
WorldBegin
LightSource "infinite" "rgb L" [0.2 0.3 0.4]
AttributeBegin
  AreaLightSource "diffuse" "rgb L" [4 4 4]
  Translate 0 3 0
  Rotate 30 0 1 0
  Shape "trianglemesh" "point3 P" [-0.5 0 -0.5  0.5 0 -0.5  0.5 0 0.5  -0.5 0 0.5] "integer indices" [0 1 2 0 2 3]
AttributeEnd
LightSource "point" "point3 from" [1 2 3] "rgb I" [5 5 5]
MakeNamedMaterial "red" "string type" "diffuse" "rgb reflectance" [0.8 0.1 0.1]
NamedMaterial "red"
CoordinateSystem "here"
Transform [1 0 0 0  0 1 0 0  0 0 1 0  0 0 0 1]
ConcatTransform [2 0 0 0  0 2 0 0  0 0 2 0  0 0 0 1]
CoordSysTransform "here"
Shape "sphere" "float radius" 1
ObjectBegin "tri"
  Shape "trianglemesh" "point3 P" [0 0 0 1 0 0 0 1 0]
ObjectEnd
AttributeBegin
  Scale 2 2 2
  ObjectInstance "tri"
AttributeEnd
""")

# Ray batch files (docs/rays-format.md): two rays without hits, and two shadow rays with hits.
def rays_file(flags, name, hits):
    rays = [(0, 0, 0, 0, 0, 1, 0, 1e30), (1, 2, 3, -0.5, 0.5, 0.7071, 1e-4, 10)]
    out = b"RSRAYS\r\n" + struct.pack("<IIQ", 1, flags, len(rays)) + bytes(range(32))
    out += struct.pack("<II", len(name), len(b"raysort rays")) + name + b"raysort rays"
    out += b"".join(struct.pack("<8f", *r) for r in rays)
    return out + (b"".join(struct.pack("<fI", t, tri) for t, tri in hits) if flags & 1 else b"")

(seeds / "ray_file").mkdir(parents=True, exist_ok=True)
(seeds / "ray_file/primary.rays").write_bytes(rays_file(0, b"primary", []))
(seeds / "ray_file/shadow0-hits.rays").write_bytes(rays_file(3, b"shadow0", [(2.5, 7), (10, 0xFFFFFFFF)]))
