#!/usr/bin/env python3
"""Writes the small seed corpus of the fuzz targets (fuzz/corpus/<target>/). Every seed is made
here (no file of ../shared/data is copied): minimal BVH rigs in several shapes and units, tiny
glTF/GLB files with an animation, short envelopes with and without a pulse, and sentences in
Japanese and English. Run it again to regenerate; the fuzzer adds what it finds to the same
folders, and `./dev fuzz` keeps them."""
import json, math, os, struct

HERE = os.path.dirname(os.path.abspath(__file__))

def put(target, name, data):
    d = os.path.join(HERE, "corpus", target)
    os.makedirs(d, exist_ok=True)
    with open(os.path.join(d, name), "wb") as f:
        f.write(data if isinstance(data, bytes) else data.encode())

# --- BVH -------------------------------------------------------------------------------------
def bvh(unit, frames, root_above=False, order="Zrotation Xrotation Yrotation"):
    j = lambda name, off, kids: f"JOINT {name}\n{{\nOFFSET {off[0]*unit:g} {off[1]*unit:g} {off[2]*unit:g}\nCHANNELS 3 {order}\n{kids}}}\n"
    end = "End Site\n{\nOFFSET 0 %g 0\n}\n" % (0.1 * unit)
    leg = lambda s, x: j(f"{s}UpLeg", (0.1*x, -0.05, 0), j(f"{s}Leg", (0, -0.45, 0), j(f"{s}Foot", (0, -0.42, 0), end)))
    arm = lambda s, x: j(f"{s}Arm", (0.15*x, 0.1, 0), j(f"{s}ForeArm", (0.28*x, 0, 0), end))
    spine = j("Spine", (0, 0.2, 0), j("Neck", (0, 0.3, 0), j("Head", (0, 0.1, 0), end)) + arm("Left", 1) + arm("Right", -1))
    hips = f"{{\nOFFSET 0 {unit:g} 0\nCHANNELS 6 Xposition Yposition Zposition {order}\n{spine}{leg('Left', 1)}{leg('Right', -1)}}}\n"
    h = "HIERARCHY\n" + (f"ROOT Root\n{{\nOFFSET 0 0 0\nCHANNELS 6 Xposition Yposition Zposition {order}\nJOINT Hips\n{hips}}}\n" if root_above else f"ROOT Hips\n{hips}")
    n = h.count("CHANNELS 3") * 3 + h.count("CHANNELS 6") * 6
    rows = []
    for f in range(frames):
        r = [0.0] * n
        base = 6 if root_above else 0
        r[base] = 0.5 * unit * f / max(frames, 1)
        r[base + 1] = unit
        r[base + 4] = 20 * math.sin(f)
        rows.append(" ".join(f"{v:g}" for v in r))
    return h + f"MOTION\nFrames: {frames}\nFrame Time: 0.0333333\n" + "\n".join(rows) + "\n"

put("import_bvh", "humanoid_cm", bvh(100, 3))
put("import_bvh", "humanoid_m_xyz", bvh(1, 2, order="Xrotation Yrotation Zrotation"))
put("import_bvh", "root_above_hips", bvh(100, 2, root_above=True))
put("import_bvh", "two_joints", "HIERARCHY\nROOT hip\n{\n OFFSET 0 0 0\n CHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation Xrotation\n JOINT knee\n {\n  OFFSET 0 -40 0\n  CHANNELS 3 Xrotation Zrotation Yrotation\n  End Site\n  {\n   OFFSET 0 -40 0\n  }\n }\n}\nMOTION\nFrames: 2\nFrame Time: 0.0333333\n0 90 0 0 0 0 0 0 0\n10 90 0 0 0 0 90 0 0\n")
put("import_bvh", "truncated", bvh(100, 3)[:-30])

# --- glTF / GLB ------------------------------------------------------------------------------
def key_bytes(end):
    b = struct.pack("<2f", 0.0, end)
    b += struct.pack("<4f", 0, 0, 0, 1) + struct.pack("<4f", 0, 0, 0.70710677, 0.70710677)
    return b

def gltf_json(bin_len, extra_nodes=False, interp="LINEAR"):
    nodes = [{"name": "Hips", "children": [1]}, {"name": "Spine", "translation": [0, 0.5, 0], "scale": [0.01, 0.01, 0.01]}]
    if extra_nodes:
        nodes = [{"name": "Armature", "children": [1], "scale": [0.01, 0.01, 0.01]}, {"name": "Hips", "children": [2], "translation": [0, 100, 0]}, {"name": "Spine", "translation": [0, 10, 0]}]
    return {
        "asset": {"version": "2.0"}, "nodes": nodes, "scenes": [{"nodes": [0]}], "scene": 0,
        "buffers": [{"byteLength": bin_len}],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 8}, {"buffer": 0, "byteOffset": 8, "byteLength": 32}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 2, "type": "SCALAR", "min": [0], "max": [1]},
                      {"bufferView": 1, "componentType": 5126, "count": 2, "type": "VEC4"}],
        "animations": [{"name": "turn", "channels": [{"sampler": 0, "target": {"node": len(nodes) - 1, "path": "rotation"}}],
                        "samplers": [{"input": 0, "output": 1, "interpolation": interp}]}],
    }

def glb(doc, binary):
    j = json.dumps(doc, separators=(",", ":")).encode()
    j += b" " * (-len(j) % 4)
    binary += b"\0" * (-len(binary) % 4)
    total = 12 + 8 + len(j) + 8 + len(binary)
    return b"glTF" + struct.pack("<II", 2, total) + struct.pack("<I", len(j)) + b"JSON" + j + struct.pack("<I", len(binary)) + b"BIN\0" + binary

import base64
put("import_gltf", "one_second.glb", glb(gltf_json(40), key_bytes(1.0)))
put("import_gltf", "armature_above.glb", glb(gltf_json(40, extra_nodes=True), key_bytes(2.0)))
put("import_gltf", "step.glb", glb(gltf_json(40, interp="STEP"), key_bytes(0.5)))
doc = gltf_json(40)
doc["buffers"][0]["uri"] = "data:application/octet-stream;base64," + base64.b64encode(key_bytes(1.0)).decode()
put("import_gltf", "embedded.gltf", json.dumps(doc))

# --- envelopes ---------------------------------------------------------------------------------
def envelope(hop_byte, bands, frames, bpm, hop):
    out = bytes([hop_byte, (bands - 1) % 4])
    vals = []
    for b in range(bands):
        for n in range(frames):
            t = n * hop
            beat = (t * bpm / 60.0) % 1.0
            v = 0.02 + (0.5 * math.exp(-beat * 60 / bpm / 0.05) if bpm else 0.0)
            vals.append(int(min(v, 1.0) * 65000))
    return out + b"".join(struct.pack("<H", v) for v in vals)

hop_byte = round((0.01 - 0.005) / 0.045 * 255)
hop = 0.005 + 0.045 * hop_byte / 255
put("music_envelope", "pulse_120_one_band", envelope(hop_byte, 1, 600, 120, hop))
put("music_envelope", "pulse_90_four_bands", envelope(hop_byte, 4, 400, 90, hop))
put("music_envelope", "flat", envelope(hop_byte, 1, 500, 0, hop))

# --- text ----------------------------------------------------------------------------------------
for i, s in enumerate(["太郎は走って，ボールを蹴る．そして喜ぶ．", "歩きながら右手を振る", "Taro runs, then kicks the ball. Then he rejoices.",
                       "Clap while jumping.", "走る。99999秒後に座る。", "走る。-5秒後に座る。", "While walking, wave the left hand and nod.",
                       "ガッツポーズする。しばらくしてからお辞儀する。"]):
    put("text_parse", f"sentence_{i}", s)
