"""Writes torus.gltf: a torus of 32 x 12 quads (768 triangles, genus 1) with smooth
normals, tangents, texture coordinates, vertex colours and a seam in u and v, lit by an
emissive quad. With --animated, torus-animated.gltf: the same torus skinned to two joints
(JOINTS_0, WEIGHTS_0), with a morph target that swells it, and an animation of 1 s that
turns the second joint and the morph weight. tests/data/draco/README.md says how the
Draco fixtures are made from them."""
import base64, json, math, struct, sys

animated = "--animated" in sys.argv
args = [a for a in sys.argv[1:] if a != "--animated"]

R, r, NU, NV = 1.0, 0.35, 32, 12
pos, nrm, tan, uv, col, idx = [], [], [], [], [], []
joints, weights, swell = [], [], []
for i in range(NU + 1):
    u = 2 * math.pi * i / NU
    for j in range(NV + 1):
        v = 2 * math.pi * j / NV
        c = R + r * math.cos(v)
        pos += [c * math.cos(u), r * math.sin(v), c * math.sin(u)]
        nrm += [math.cos(v) * math.cos(u), math.sin(v), math.cos(v) * math.sin(u)]
        tan += [-math.sin(u), 0.0, math.cos(u), 1.0]
        uv += [i / NU, j / NV]
        col += [0.5 + 0.5 * math.cos(u), 0.5 + 0.5 * math.sin(v), 0.3, 1.0]
        # Skin: the half with x > 0 follows joint 1, blending over a band.
        w1 = min(1.0, max(0.0, 0.5 + c * math.cos(u)))
        joints += [0, 1, 0, 0]
        weights += [1.0 - w1, w1, 0.0, 0.0]
        # Morph target: a swelling of the tube along its normal.
        swell += [0.15 * math.cos(v) * math.cos(u), 0.15 * math.sin(v), 0.15 * math.cos(v) * math.sin(u)]
for i in range(NU):
    for j in range(NV):
        a, b = i * (NV + 1) + j, (i + 1) * (NV + 1) + j
        idx += [a, a + 1, b, b, a + 1, b + 1]
n = len(pos) // 3
lamp = [-0.5, 1.5, -0.5, 0.5, 1.5, -0.5, 0.5, 1.5, 0.5, -0.5, 1.5, 0.5]
lamp_idx = [0, 1, 2, 0, 2, 3]

blob, views, accessors = b"", [], []
def add(data, fmt, type_, comp, count, extra=None):
    global blob
    while len(blob) % 4:
        blob += b"\0"
    raw = struct.pack("<%d%s" % (len(data), fmt), *data)
    views.append({"buffer": 0, "byteOffset": len(blob), "byteLength": len(raw)})
    blob += raw
    acc = {"bufferView": len(views) - 1, "componentType": comp, "count": count, "type": type_}
    acc.update(extra or {})
    accessors.append(acc)
    return len(accessors) - 1

def bounds(data, k):
    return {"min": [min(data[c::k]) for c in range(k)], "max": [max(data[c::k]) for c in range(k)]}

P = add(pos, "f", "VEC3", 5126, n, bounds(pos, 3))
N = add(nrm, "f", "VEC3", 5126, n)
T = add(tan, "f", "VEC4", 5126, n)
UV = add(uv, "f", "VEC2", 5126, n)
C = add(col, "f", "VEC4", 5126, n)
I = add(idx, "H", "SCALAR", 5123, len(idx))
LP = add(lamp, "f", "VEC3", 5126, 4, bounds(lamp, 3))
LI = add(lamp_idx, "H", "SCALAR", 5123, 6)
gltf = {
    "asset": {"version": "2.0", "generator": "lanterna tests/data/draco/make_torus.py"},
    "scene": 0,
    "scenes": [{"nodes": [0, 1, 2]}],
    "nodes": [
        {"mesh": 0, "rotation": [0.2588, 0.0, 0.0, 0.9659]},
        {"mesh": 1},
        {"camera": 0, "translation": [0.0, 1.2, 3.5], "rotation": [-0.1305, 0.0, 0.0, 0.9914]},
    ],
    "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.01}}],
    "meshes": [
        {"primitives": [{"attributes": {"POSITION": P, "NORMAL": N, "TANGENT": T, "TEXCOORD_0": UV, "COLOR_0": C}, "indices": I, "material": 0}]},
        {"primitives": [{"attributes": {"POSITION": LP}, "indices": LI, "material": 1}]},
    ],
    "materials": [
        {"pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.8, 0.8, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.6}},
        {"emissiveFactor": [1.0, 1.0, 1.0], "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 4.0}}},
    ],
    "extensionsUsed": ["KHR_materials_emissive_strength"],
    "accessors": accessors,
    "bufferViews": views,
    "buffers": [{"byteLength": len(blob), "uri": "data:application/octet-stream;base64," + base64.b64encode(blob).decode()}],
}
if animated:
    J = add(joints, "B", "VEC4", 5121, n)
    W = add(weights, "f", "VEC4", 5126, n)
    S = add(swell, "f", "VEC3", 5126, n, bounds(swell, 3))
    IBM = add([1.0, 0, 0, 0, 0, 1.0, 0, 0, 0, 0, 1.0, 0, 0, 0, 0, 1.0] * 2, "f", "MAT4", 5126, 2)
    times = [0.0, 0.5, 1.0]
    T0 = add(times, "f", "SCALAR", 5126, 3, {"min": [0.0], "max": [1.0]})
    half = math.sin(0.35)
    R1 = add([0, 0, 0, 1, 0, 0, half, math.cos(0.35), 0, 0, 0, 1], "f", "VEC4", 5126, 3)
    MW = add([0.0, 1.0, 0.25], "f", "SCALAR", 5126, 3)
    prim = gltf["meshes"][0]["primitives"][0]
    prim["attributes"].update({"JOINTS_0": J, "WEIGHTS_0": W})
    prim["targets"] = [{"POSITION": S}]
    gltf["meshes"][0]["weights"] = [0.0]
    # The torus node becomes the skinned mesh's node; joints 3 and 4 (4 a child of 3).
    gltf["nodes"][0] = {"mesh": 0, "skin": 0}
    gltf["nodes"] += [
        {"rotation": [0.2588, 0.0, 0.0, 0.9659], "children": [4]},
        {"translation": [0.0, 0.0, 0.0]},
    ]
    gltf["scenes"][0]["nodes"] += [3]
    gltf["skins"] = [{"joints": [3, 4], "inverseBindMatrices": IBM}]
    gltf["animations"] = [{
        "samplers": [{"input": T0, "output": R1}, {"input": T0, "output": MW}],
        "channels": [
            {"sampler": 0, "target": {"node": 4, "path": "rotation"}},
            {"sampler": 1, "target": {"node": 0, "path": "weights"}},
        ],
    }]
    gltf["buffers"][0] = {"byteLength": len(blob), "uri": "data:application/octet-stream;base64," + base64.b64encode(blob).decode()}
json.dump(gltf, open(args[0] if args else "torus.gltf", "w"))
