// Byte-by-byte writers of the MMD files the browser tests make for themselves (the shared models
// have no bone morph, and no material morph but an alpha one): a PMX 2.0 model, a VMD motion and
// a 24-bit BMP image. Plain JS over Buffers, the engine's own making, no model's data; the tests
// read what they write back with three r171's MMDParser, a reader no one here wrote.
//
// PMX 2.0 as written (all little-endian; "text" is an i32 byte length then UTF-16LE):
//   "PMX " · f32 2.0 · u8 8 · u8[8] globals: encoding 0 (UTF-16LE), additional UVs, index sizes
//   vertex 2 (u16), texture 1, material 1, bone 1, morph 1, rigid body 1 (i8, −1 = none)
//   text name, name (en), comment, comment (en)
//   i32 vertices · each f32[3] position, f32[3] normal, f32[2] uv, f32[4] per additional UV,
//     u8 skin (0 BDEF1: bone; 1 BDEF2: bone, bone, f32 weight of the first), f32 edge scale
//   i32 indices · u16 each (triangles)
//   i32 textures · text path each
//   i32 materials · text name, name (en), f32[4] diffuse, f32[3] specular, f32 power,
//     f32[3] ambient, u8 flags, f32[4] edge colour, f32 edge size, texture, sphere, u8 sphere
//     mode (0 none, 1 multiply, 2 add, 3 sub-texture), u8 toon kind (0 own texture: its index;
//     1 shared: u8 0–9 for toon01–10), text memo, i32 index count
//   i32 bones · text name, name (en), f32[3] position, parent, i32 layer, u16 flags (0x1F: tail
//     is a bone index, rotatable, movable, visible, operable), tail bone (−1)
//   i32 morphs · text name, name (en), u8 panel, u8 type, i32 offsets · bone (type 2): bone,
//     f32[3] translation, f32[4] rotation (x, y, z, w); material (type 8): material (−1: all),
//     u8 operation (0 multiply, 1 add), f32[4] diffuse, f32[3] specular, f32 power, f32[3]
//     ambient, f32[4] edge colour, f32 edge size, f32[4] texture, sphere and toon tints
//   i32 display frames, i32 rigid bodies, i32 joints: 0 each
// Coordinates are MMD's file frame (left-handed, Y up, front toward −z; 1 unit ≈ 8 cm).
import { shiftJis } from "./mmd-common.mjs";

class Out {
  constructor() { this.parts = []; }
  u8(v) { const b = Buffer.alloc(1); b.writeUInt8(v); this.parts.push(b); return this; }
  i8(v) { const b = Buffer.alloc(1); b.writeInt8(v); this.parts.push(b); return this; }
  u16(v) { const b = Buffer.alloc(2); b.writeUInt16LE(v); this.parts.push(b); return this; }
  i32(v) { const b = Buffer.alloc(4); b.writeInt32LE(v); this.parts.push(b); return this; }
  u32(v) { const b = Buffer.alloc(4); b.writeUInt32LE(v); this.parts.push(b); return this; }
  f32(...vs) { for (const v of vs.flat()) { const b = Buffer.alloc(4); b.writeFloatLE(v); this.parts.push(b); } return this; }
  bytes(b) { this.parts.push(Buffer.from(b)); return this; }
  text(s) { const b = Buffer.from(s, "utf16le"); return this.i32(b.length).bytes(b); }
  /** A fixed-width field: `b` cut or zero-padded to `n` bytes. */
  fixed(b, n) { const f = Buffer.alloc(n); Buffer.from(b).copy(f, 0, 0, Math.min(n, b.length)); return this.bytes(f); }
  done() { return Buffer.concat(this.parts); }
}

/** A material morph offset's fields at "no change" for its operation (multiply: 1, add: 0), with `o`'s on top. */
export function materialOffset(material, operation, o = {}) {
  const z = operation === 0 ? 1 : 0;
  return {
    material, operation,
    diffuse: [z, z, z, z], specular: [z, z, z], power: z, ambient: [z, z, z], edgeColour: [z, z, z, z], edgeSize: z,
    texture: [z, z, z, z], sphere: [z, z, z, z], toon: [z, z, z, z],
    ...o,
  };
}

/**
 * A PMX 2.0 file of `m`: { name, comment, additionalUvs (0–4), vertices: [{ p, n, uv, auv: [[4]…],
 * bones: [b] or [b0, b1, w0], edge }], indices, textures: [path], materials: [{ name, diffuse,
 * specular, power, ambient, flags, edgeColour, edgeSize, texture, sphere, sphereMode, toon:
 * { texture } | { shared }, count }], bones: [{ name, p, parent }], morphs: [{ name, panel, type:
 * "bone" | "material", offsets }] } (bone offsets { bone, t, q }; material offsets as
 * `materialOffset` makes them).
 */
export function writePmx(m) {
  const o = new Out();
  o.bytes("PMX ").f32(2.0).u8(8).u8(0).u8(m.additionalUvs ?? 0).u8(2).u8(1).u8(1).u8(1).u8(1).u8(1);
  o.text(m.name).text(m.name).text(m.comment ?? "").text(m.comment ?? "");
  o.i32(m.vertices.length);
  for (const v of m.vertices) {
    o.f32(v.p, v.n, v.uv);
    for (let k = 0; k < (m.additionalUvs ?? 0); k++) o.f32(v.auv?.[k] ?? [0, 0, 0, 0]);
    if (v.bones.length === 1) o.u8(0).i8(v.bones[0]);
    else o.u8(1).i8(v.bones[0]).i8(v.bones[1]).f32(v.bones[2]);
    o.f32(v.edge ?? 1);
  }
  o.i32(m.indices.length);
  for (const i of m.indices) o.u16(i);
  o.i32(m.textures.length);
  for (const t of m.textures) o.text(t);
  o.i32(m.materials.length);
  for (const x of m.materials) {
    o.text(x.name).text(x.name).f32(x.diffuse, x.specular, x.power, x.ambient).u8(x.flags).f32(x.edgeColour, x.edgeSize);
    o.i8(x.texture ?? -1).i8(x.sphere ?? -1).u8(x.sphereMode ?? 0);
    if (x.toon?.texture != null) o.u8(0).i8(x.toon.texture);
    else o.u8(1).u8(x.toon?.shared ?? 0);
    o.text("").i32(x.count);
  }
  o.i32(m.bones.length);
  for (const b of m.bones) o.text(b.name).text(b.name).f32(b.p).i8(b.parent ?? -1).i32(0).u16(0x1f).i8(-1);
  o.i32(m.morphs.length);
  for (const x of m.morphs) {
    o.text(x.name).text(x.name).u8(x.panel ?? 4).u8({ bone: 2, material: 8 }[x.type]).i32(x.offsets.length);
    for (const e of x.offsets) {
      if (x.type === "bone") o.i8(e.bone).f32(e.t, e.q);
      else o.i8(e.material).u8(e.operation).f32(e.diffuse, e.specular, e.power, e.ambient, e.edgeColour, e.edgeSize, e.texture, e.sphere, e.toon);
    }
  }
  return o.i32(0).i32(0).i32(0).done();
}

/** MMD's linear interpolation block of a bone key (64 bytes: the 16-byte row X/Y/Z/R × x1 y1 x2 y2, then three copies each shifted by one, as MMD writes them). */
function linearCurves() {
  const row = [20, 20, 20, 20, 20, 20, 20, 20, 107, 107, 107, 107, 107, 107, 107, 107];
  const out = [];
  for (let k = 0; k < 4; k++) out.push(...row.slice(k), ...Array(k).fill(0));
  return out;
}

/**
 * A VMD ("Vocaloid Motion Data 0002") of `v`: { model, bones: [{ name, frame, p, q }], morphs:
 * [{ name, frame, weight }] }, names in Shift-JIS cut to MMD's 20 (model) and 15 bytes; no
 * camera, light or self-shadow keys.
 */
export function writeVmd(v) {
  const o = new Out();
  o.fixed(Buffer.from("Vocaloid Motion Data 0002"), 30).fixed(shiftJis(v.model), 20);
  o.u32(v.bones.length);
  for (const k of v.bones) o.fixed(shiftJis(k.name), 15).u32(k.frame).f32(k.p ?? [0, 0, 0], k.q ?? [0, 0, 0, 1]).bytes(linearCurves());
  o.u32(v.morphs.length);
  for (const k of v.morphs) o.fixed(shiftJis(k.name), 15).u32(k.frame).f32(k.weight);
  return o.u32(0).u32(0).u32(0).done();
}

/** A 24-bit uncompressed BMP of `w` × `h` pixels, `rgb(x, y)` → [r, g, b] (y = 0 the top row; rows stored bottom-up, padded to 4 bytes). */
export function writeBmp(w, h, rgb) {
  const stride = (3 * w + 3) & ~3;
  const o = new Out();
  o.bytes("BM").u32(54 + stride * h).u32(0).u32(54);
  o.u32(40).i32(w).i32(h).u16(1).u16(24).u32(0).u32(stride * h).i32(2835).i32(2835).u32(0).u32(0);
  for (let y = h - 1; y >= 0; y--) {
    const row = Buffer.alloc(stride);
    for (let x = 0; x < w; x++) { const [r, g, b] = rgb(x, y); row[3 * x] = b; row[3 * x + 1] = g; row[3 * x + 2] = r; }
    o.bytes(row);
  }
  return o.done();
}
