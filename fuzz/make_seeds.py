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

# --- MMD: VMD motions, PMD and PMX models (issue 28) -------------------------------------------
# Tiny files written field by field from the format (no MMD asset is copied): every section,
# every skin kind and morph kind, each index size, both PMX text encodings.
def sjis(s, width):
    b = s.encode("cp932")[:width]
    return b + b"\0" * (width - len(b))

def curve_block(x1=20, y1=20, x2=107, y2=107):
    row = bytes([x1] * 4 + [y1] * 4 + [x2] * 4 + [y2] * 4)
    return b"".join((row[k:] + bytes([1]) + bytes(15))[:16] for k in range(4))

def vmd(bones, morphs, camera=0, tail=False):
    out = b"Vocaloid Motion Data 0002".ljust(30, b"\0") + sjis("初音ミク", 20)
    out += struct.pack("<I", len(bones))
    for name, frame, t, q, c in bones:
        out += sjis(name, 15) + struct.pack("<I3f4f", frame, *t, *q) + curve_block(*c)
    out += struct.pack("<I", len(morphs))
    for name, frame, w in morphs:
        out += sjis(name, 15) + struct.pack("<If", frame, w)
    if camera or tail:
        out += struct.pack("<I", camera)
        for i in range(camera):
            out += struct.pack("<If3f3f", i * 10, -45.0, 0, 10, 0, 0.1, 0.2, 0) + bytes([20, 107, 20, 107] * 6) + struct.pack("<IB", 30, 0)
    if tail:
        out += struct.pack("<I", 1) + struct.pack("<I3f3f", 0, 0.6, 0.6, 0.6, -0.5, -1, 0.5)
        out += struct.pack("<I", 1) + struct.pack("<IBf", 0, 1, 0.01)
        out += struct.pack("<I", 1) + struct.pack("<IBI", 0, 1, 2) + sjis("左足ＩＫ", 20) + b"\0" + sjis("右足ＩＫ", 20) + b"\1"
    return out

dance = [("センター", 0, (0, 0, 0), (0, 0, 0, 1), ()), ("センター", 30, (1, 2, 3), (0, 0.38268343, 0, 0.9238795), (127, 0, 0, 127)),
         ("左足ＩＫ", 15, (0.5, 1, 0), (0, 0, 0, 1), (64, 10, 100, 120)), ("右人指１先ＸＹＺ", 5, (0, 0, 0), (0, 0, 0, 1), ())]
put("import_vmd", "dance", vmd(dance, [("まばたき", 0, 0.0), ("まばたき", 10, 1.0)]))
put("import_vmd", "camera", vmd([], [], camera=3))
put("import_vmd", "all_sections", vmd(dance[:2], [("あ", 3, 0.5)], camera=1, tail=True))
put("import_vmd", "old_header", b"Vocaloid Motion Data file".ljust(30, b"\0") + sjis("miku", 10) + struct.pack("<I", 1) + sjis("頭", 15) + struct.pack("<I3f4f", 0, 0, 0, 0, 0, 0, 0, 1) + curve_block())
put("import_vmd", "truncated", vmd(dance, [])[:200])

def pmx(version=2.0, utf8=False, sizes=(2, 1, 1, 2, 1, 1), auv=0):
    vi, ti, mi, bi, mo, ri = sizes
    enc = "utf-8" if utf8 else "utf-16-le"
    text = lambda s: struct.pack("<i", len(s.encode(enc))) + s.encode(enc)
    idx = lambda v, n: struct.pack({1: "<b", 2: "<h", 4: "<i"}[n], v)
    vidx = lambda v: struct.pack({1: "<B", 2: "<H", 4: "<i"}[vi], v)
    out = b"PMX " + struct.pack("<f", version) + bytes([8, 1 if utf8 else 0, auv, vi, ti, mi, bi, mo, ri])
    out += text("テスト") + text("test") + text("コメント") + text("comment")
    # Four vertices on three bones: BDEF1, BDEF2, BDEF4 (QDEF in 2.1), SDEF.
    verts = [(0, 0, 0), (0, 10, 0), (1, 10, 0), (0, 20, 0)]
    out += struct.pack("<i", len(verts))
    for i, p in enumerate(verts):
        out += struct.pack("<3f3f2f", *p, 0, 0, -1, 0.5, 0.5) + struct.pack("<4f", 0, 0, 0, 0) * auv
        kind = [0, 1, 4 if version >= 2.1 else 2, 3][i]
        out += bytes([kind])
        if kind == 0: out += idx(0, bi)
        elif kind == 1: out += idx(0, bi) + idx(1, bi) + struct.pack("<f", 0.25)
        elif kind in (2, 4): out += idx(0, bi) + idx(1, bi) + idx(2, bi) + idx(-1, bi) + struct.pack("<4f", 0.5, 0.25, 0.25, 0)
        else: out += idx(1, bi) + idx(2, bi) + struct.pack("<f", 0.5) + struct.pack("<9f", 0, 10, 0, 0, 12, 0, 0, 8, 0)
        out += struct.pack("<f", 1.0)
    out += struct.pack("<i", 6) + b"".join(vidx(v) for v in (0, 1, 2, 1, 3, 2))
    out += struct.pack("<i", 2) + text("tex\\Body.png") + text("toon_own.bmp")
    out += struct.pack("<i", 2)
    for m in range(2):
        out += text(f"材質{m}") + text(f"mat{m}") + struct.pack("<4f3ff3f", 1, 1, 1, 1, 0, 0, 0, 5, 0.5, 0.5, 0.5) + bytes([0x13])
        out += struct.pack("<4ff", 0, 0, 0, 1, 1.0) + idx(0, ti) + idx(-1, ti) + bytes([0])
        out += (bytes([1, m]) if m == 0 else bytes([0]) + idx(1, ti)) + text("") + struct.pack("<i", 3)
    # Bones: センター, 左足 (grant from センター, fixed axis, local axes), 左足ＩＫ (IK on 左足 with a limit).
    out += struct.pack("<i", 3)
    out += text("センター") + text("center") + struct.pack("<3f", 0, 8, 0) + idx(-1, bi) + struct.pack("<iH", 0, 0x001E | 0x0001) + idx(1, bi)
    out += text("左足") + text("leg_L") + struct.pack("<3f", 1, 10, 0) + idx(0, bi) + struct.pack("<iH", 0, 0x001A | 0x0100 | 0x0400 | 0x0800)
    out += struct.pack("<3f", 0, -1, 0) + idx(0, bi) + struct.pack("<f", 0.5) + struct.pack("<3f", 1, 0, 0) + struct.pack("<6f", 1, 0, 0, 0, 0, 1)
    out += text("左足ＩＫ") + text("leg IK_L") + struct.pack("<3f", 1, 0, 0) + idx(0, bi) + struct.pack("<iH", 1, 0x003E)
    out += struct.pack("<3f", 0, 0, 1) + idx(1, bi) + struct.pack("<if", 40, 2.0) + struct.pack("<i", 1) + idx(1, bi) + bytes([1]) + struct.pack("<6f", -3.14, 0, 0, -0.01, 0, 0)
    # Morphs: vertex, bone, UV, material, group (and 2.1's flip and impulse).
    morphs = [(1, struct.pack("<i", 1) + vidx(3) + struct.pack("<3f", 0, 1, 0)),
              (2, struct.pack("<i", 1) + idx(2, bi) + struct.pack("<3f4f", 0, 1, 0, 0, 0, 0, 1)),
              (3, struct.pack("<i", 1) + vidx(0) + struct.pack("<4f", 0.1, 0, 0, 0)),
              (8, struct.pack("<i", 1) + idx(-1, mi) + bytes([0]) + struct.pack("<28f", *([1.0] * 28))),
              (0, struct.pack("<i", 2) + idx(0, mo) + struct.pack("<f", 1) + idx(1, mo) + struct.pack("<f", 0.5))]
    if version >= 2.1:
        morphs += [(9, struct.pack("<i", 1) + idx(0, mo) + struct.pack("<f", 1)), (10, struct.pack("<i", 1) + idx(0, ri) + bytes([1]) + struct.pack("<6f", 0, 1, 0, 0, 0, 0))]
    out += struct.pack("<i", len(morphs))
    for k, (kind, body) in enumerate(morphs):
        out += text(f"モーフ{k}") + text(f"morph{k}") + bytes([k % 5, kind]) + body
    out += struct.pack("<i", 2)
    out += text("Root") + text("Root") + bytes([1]) + struct.pack("<i", 1) + bytes([0]) + idx(0, bi)
    out += text("表情") + text("Exp") + bytes([1]) + struct.pack("<i", 1) + bytes([1]) + idx(0, mo)
    out += struct.pack("<i", 2)
    for k in range(2):
        out += text(f"剛体{k}") + text(f"rigid{k}") + idx(k, bi) + bytes([k]) + struct.pack("<H", 0xFFFE) + bytes([k])
        out += struct.pack("<3f3f3f5f", 1, 2, 0, 0, 10 + k, 0, 0, 0, 0, 1, 0.5, 0.5, 0, 0.5) + bytes([k])
    out += struct.pack("<i", 1) + text("ジョイント") + text("joint") + bytes([0]) + idx(0, ri) + idx(1, ri) + struct.pack("<24f", *([0.0] * 24))
    if version >= 2.1:
        out += struct.pack("<i", 1) + text("ソフト") + text("soft") + bytes([0]) + idx(0, mi) + bytes([0]) + struct.pack("<H", 0) + bytes([0])
        out += struct.pack("<iiffi", 2, 0, 1.0, 0.05, 0) + struct.pack("<12f", *([0.0] * 12)) + struct.pack("<6f", *([0.0] * 6)) + struct.pack("<4i", 1, 1, 1, 1) + struct.pack("<3f", 1, 1, 1)
        out += struct.pack("<i", 1) + idx(0, ri) + vidx(0) + bytes([0]) + struct.pack("<i", 1) + vidx(1)
    return out

put("import_pmx", "pmx20_utf16.pmx", pmx())
put("import_pmx", "pmx21_utf8_wide_indices.pmx", pmx(2.1, utf8=True, sizes=(4, 4, 4, 4, 4, 4), auv=2))
put("import_pmx", "pmx21_byte_indices.pmx", pmx(2.1, sizes=(1, 1, 1, 1, 1, 1), auv=1))
put("import_pmx", "pmx_truncated.pmx", pmx()[:300])

def pmd():
    out = b"Pmd" + struct.pack("<f", 1.0) + sjis("テスト", 20) + sjis("コメント", 256)
    verts = [(0, 0, 0), (0, 10, 0), (1, 10, 0)]
    out += struct.pack("<I", 3) + b"".join(struct.pack("<3f3f2fHHBB", *p, 0, 0, -1, 0.5, 0.5, 0, 1, 100 - 50 * (i % 2), i % 2) for i, p in enumerate(verts))
    out += struct.pack("<I", 3) + struct.pack("<3H", 0, 1, 2)
    out += struct.pack("<I", 1) + struct.pack("<3fff3f3fBBI", 1, 1, 1, 1, 5, 0, 0, 0, 0.5, 0.5, 0.5, 0, 1, 3) + sjis("body.bmp*shine.sph", 20)
    bones = [("センター", 0xFFFF, 1, 1, 0, (0, 8, 0)), ("左ひざ", 0, 2, 0, 0, (1, 5, 0)), ("左足首", 1, 0, 6, 0, (1, 1, 0)),
             ("左足ＩＫ", 0, 0, 2, 0, (1, 0, 0)), ("左目", 0, 0, 5, 0, (0, 15, 0)), ("左腕捩連", 0, 0, 9, 50, (2, 12, 0))]
    out += struct.pack("<H", len(bones)) + b"".join(sjis(n, 20) + struct.pack("<HHBH3f", p, t, k, ik, *pos) for n, p, t, k, ik, pos in bones)
    out += struct.pack("<H", 1) + struct.pack("<HHBHf", 3, 2, 1, 40, 0.5) + struct.pack("<H", 1)
    out += struct.pack("<H", 2) + sjis("base", 20) + struct.pack("<IB", 2, 0) + struct.pack("<I3f", 1, 0, 10, 0) + struct.pack("<I3f", 2, 1, 10, 0)
    out += sjis("まばたき", 20) + struct.pack("<IB", 1, 2) + struct.pack("<I3f", 1, 0, -0.5, 0)
    out += bytes([1]) + struct.pack("<H", 1) + bytes([1]) + sjis("足\n", 50) + struct.pack("<I", 1) + struct.pack("<HB", 1, 1)
    out += bytes([1]) + sjis("test", 20) + sjis("comment", 256) + b"".join(sjis(f"bone{i}", 20) for i in range(len(bones))) + sjis("blink", 20) + sjis("Legs", 50)
    out += b"".join(sjis(f"toon{i + 1:02}.bmp" if i else "own_toon.bmp", 100) for i in range(10))
    out += struct.pack("<I", 1) + sjis("頭", 20) + struct.pack("<HBHB", 0, 0, 0xFFFF, 0) + struct.pack("<3f3f3f5fB", 1, 0, 0, 0, 2, 0, 0, 0, 0, 1, 0.5, 0.5, 0, 0.5, 0)
    out += struct.pack("<I", 1) + sjis("j", 20) + struct.pack("<II", 0, 0) + struct.pack("<24f", *([0.0] * 24))
    return out

put("import_pmx", "pmd10.pmd", pmd())
put("import_pmx", "pmd_no_extensions.pmd", pmd()[:pmd().index(bytes([1]) + sjis("test", 20))])

# --- MMD file sets (import_files): zips of the seeds above, as the MMD dialog gives them --------
import io, zipfile

def zipped(entries):
    b = io.BytesIO()
    with zipfile.ZipFile(b, "w", zipfile.ZIP_DEFLATED) as f:
        for name, data in entries:
            f.writestr(zipfile.ZipInfo(name, date_time=(2026, 1, 1, 0, 0, 0)), data, zipfile.ZIP_DEFLATED)
    return b.getvalue()

put("import_files", "model_and_dance.zip", zipped([("m/model.pmd", pmd()), ("m/dance.vmd", vmd(dance, []))]))
put("import_files", "pmx_backslash.zip", zipped([("M\\Model.PMX", pmx()), ("m\\tex.png", b"\x89PNG")]))
put("import_files", "truncated_vmd.zip", zipped([("cut.vmd", vmd(dance, [])[:200])]))
put("import_files", "lone.vmd", vmd(dance, [("まばたき", 0, 0.0), ("まばたき", 10, 1.0)]))
