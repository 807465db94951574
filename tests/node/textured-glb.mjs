// Small textured, skinned GLBs made in the tests (not a test file): a 1.8 m box on a two-joint
// skeleton whose six faces each carry the whole texture (UVs 0..1), with an embedded PNG made
// here, the sampler asked for and, optionally, a KHR_texture_transform. The PNG encoder uses
// node:zlib (deflate) and the CRC-32 of the PNG spec; the GLB is laid out as the glTF 2.0
// binary container asks (4-byte aligned chunks).
import { deflateSync } from "node:zlib";

const CRC = new Int32Array(256).map((_, n) => {
  let c = n;
  for (let k = 0; k < 8; k++) c = c & 1 ? 0xedb88320 ^ (c >>> 1) : c >>> 1;
  return c;
});
function crc32(bytes) {
  let c = -1;
  for (const b of bytes) c = CRC[(c ^ b) & 0xff] ^ (c >>> 8);
  return (c ^ -1) >>> 0;
}

/** An RGB PNG of `width` × `height` whose pixel (x, y) is `color(x, y)` → [r, g, b]. */
export function png(width, height, color) {
  const raw = Buffer.alloc((width * 3 + 1) * height);
  for (let y = 0; y < height; y++) {
    raw[y * (width * 3 + 1)] = 0; // filter: none
    for (let x = 0; x < width; x++) raw.set(color(x, y), y * (width * 3 + 1) + 1 + x * 3);
  }
  const chunk = (type, body) => {
    const out = Buffer.alloc(12 + body.length);
    out.writeUInt32BE(body.length, 0);
    out.write(type, 4, "latin1");
    body.copy(out, 8);
    out.writeUInt32BE(crc32(out.subarray(4, 8 + body.length)), 8 + body.length);
    return out;
  };
  const ihdr = Buffer.alloc(13);
  ihdr.writeUInt32BE(width, 0); ihdr.writeUInt32BE(height, 4);
  ihdr[8] = 8; ihdr[9] = 2; // 8 bits, RGB
  return new Uint8Array(Buffer.concat([Buffer.from("\x89PNG\r\n\x1a\n", "latin1"), chunk("IHDR", ihdr), chunk("IDAT", deflateSync(raw)), chunk("IEND", Buffer.alloc(0))]));
}

/** Width and height from a PNG's IHDR. */
export function pngSize(bytes) {
  const dv = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  return [dv.getUint32(16), dv.getUint32(20)];
}

/** Four 32-px quadrants of a 64 × 64 image: red (top left), green (top right), blue (bottom left), yellow (bottom right). */
export const QUADRANTS = () => png(64, 64, (x, y) => (y < 32 ? (x < 32 ? [230, 20, 20] : [20, 230, 20]) : x < 32 ? [20, 20, 230] : [230, 230, 20]));

/** Black and white texels alternating, `size` × `size`: what minification without mipmaps aliases. */
export const CHECKER = (size = 512) => png(size, size, (x, y) => ((x + y) & 1 ? [255, 255, 255] : [0, 0, 0]));

/**
 * The box as a GLB. `image`: PNG bytes; `sampler`: a glTF sampler object; `transform`: a
 * KHR_texture_transform object or undefined. One animation (the root turning a little) so
 * it imports as a clip like any character.
 */
export function texturedBox({ image, sampler = { magFilter: 9729, minFilter: 9987 }, transform, height = 1.8, half = 0.3 }) {
  const P = [], N = [], UV = [], I = [];
  // Each face: corner positions (counter-clockwise seen from outside), its normal.
  const faces = [
    [[1, 0, 0], [[half, 0, half], [half, 0, -half], [half, height, -half], [half, height, half]]],
    [[-1, 0, 0], [[-half, 0, -half], [-half, 0, half], [-half, height, half], [-half, height, -half]]],
    [[0, 0, 1], [[-half, 0, half], [half, 0, half], [half, height, half], [-half, height, half]]],
    [[0, 0, -1], [[half, 0, -half], [-half, 0, -half], [-half, height, -half], [half, height, -half]]],
    [[0, 1, 0], [[-half, height, half], [half, height, half], [half, height, -half], [-half, height, -half]]],
    [[0, -1, 0], [[-half, 0, -half], [half, 0, -half], [half, 0, half], [-half, 0, half]]],
  ];
  for (const [n, corners] of faces) {
    const base = P.length / 3;
    // UV v runs down the image: the face's bottom edge samples v = 1.
    [[0, 1], [1, 1], [1, 0], [0, 0]].forEach((uv, k) => { P.push(...corners[k]); N.push(...n); UV.push(...uv); });
    I.push(base, base + 1, base + 2, base, base + 2, base + 3);
  }
  const nv = P.length / 3;
  const times = [0, 0.5, 1];
  const s = Math.sin(0.05), c = Math.cos(0.05);
  const rotations = [0, 0, 0, 1, 0, s, 0, c, 0, 0, 0, 1];
  const ibm = [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, -height, 0, 1];
  const parts = [
    ["positions", new Float32Array(P), 34962],
    ["normals", new Float32Array(N), 34962],
    ["uvs", new Float32Array(UV), 34962],
    ["joints", new Uint16Array(nv * 4), 34962],
    ["weights", new Float32Array(nv * 4).map((_, i) => (i % 4 === 0 ? 1 : 0)), 34962],
    ["indices", new Uint16Array(I), 34963],
    ["ibm", new Float32Array(ibm)],
    ["times", new Float32Array(times)],
    ["rotations", new Float32Array(rotations)],
    ["image", image],
  ];
  const chunks = [], bufferViews = [], view = {};
  let length = 0;
  for (const [name, arr, target] of parts) {
    const bytes = new Uint8Array(arr.buffer, arr.byteOffset, arr.byteLength);
    bufferViews.push({ buffer: 0, byteOffset: length, byteLength: bytes.length, ...(target ? { target } : {}) });
    view[name] = bufferViews.length - 1;
    chunks.push(bytes);
    length += bytes.length;
    const pad = (4 - (length % 4)) % 4;
    if (pad) { chunks.push(new Uint8Array(pad)); length += pad; }
  }
  const bin = new Uint8Array(length);
  let at = 0;
  for (const ch of chunks) { bin.set(ch, at); at += ch.length; }
  const min = [0, 1, 2].map((k) => Math.min(...P.filter((_, i) => i % 3 === k)));
  const max = [0, 1, 2].map((k) => Math.max(...P.filter((_, i) => i % 3 === k)));
  const json = {
    asset: { version: "2.0", generator: "Odori tests (textured-glb.mjs)" },
    ...(transform ? { extensionsUsed: ["KHR_texture_transform"] } : {}),
    scene: 0,
    scenes: [{ nodes: [0, 2] }],
    nodes: [
      { name: "root", children: [1] },
      { name: "top", translation: [0, height, 0] },
      { name: "box", mesh: 0, skin: 0 },
    ],
    skins: [{ joints: [0, 1], inverseBindMatrices: 6, skeleton: 0 }],
    meshes: [{ name: "box", primitives: [{ attributes: { POSITION: 0, NORMAL: 1, TEXCOORD_0: 2, JOINTS_0: 3, WEIGHTS_0: 4 }, indices: 5, material: 0 }] }],
    materials: [{ name: "box", pbrMetallicRoughness: { baseColorTexture: { index: 0, ...(transform ? { extensions: { KHR_texture_transform: transform } } : {}) }, metallicFactor: 0, roughnessFactor: 1 } }],
    textures: [{ sampler: 0, source: 0 }],
    samplers: [sampler],
    images: [{ bufferView: view.image, mimeType: "image/png" }],
    accessors: [
      { bufferView: view.positions, componentType: 5126, count: nv, type: "VEC3", min, max },
      { bufferView: view.normals, componentType: 5126, count: nv, type: "VEC3" },
      { bufferView: view.uvs, componentType: 5126, count: nv, type: "VEC2" },
      { bufferView: view.joints, componentType: 5123, count: nv, type: "VEC4" },
      { bufferView: view.weights, componentType: 5126, count: nv, type: "VEC4" },
      { bufferView: view.indices, componentType: 5123, count: I.length, type: "SCALAR" },
      { bufferView: view.ibm, componentType: 5126, count: 2, type: "MAT4" },
      { bufferView: view.times, componentType: 5126, count: times.length, type: "SCALAR", min: [0], max: [1] },
      { bufferView: view.rotations, componentType: 5126, count: times.length, type: "VEC4" },
    ],
    animations: [{ name: "sway", samplers: [{ input: 7, output: 8, interpolation: "LINEAR" }], channels: [{ sampler: 0, target: { node: 0, path: "rotation" } }] }],
    bufferViews,
    buffers: [{ byteLength: bin.length }],
  };
  let text = new TextEncoder().encode(JSON.stringify(json));
  const jsonPad = (4 - (text.length % 4)) % 4;
  const total = 12 + 8 + text.length + jsonPad + 8 + bin.length;
  const out = new Uint8Array(total);
  const dv = new DataView(out.buffer);
  dv.setUint32(0, 0x46546c67, true); dv.setUint32(4, 2, true); dv.setUint32(8, total, true);
  dv.setUint32(12, text.length + jsonPad, true); dv.setUint32(16, 0x4e4f534a, true);
  out.set(text, 20); out.fill(0x20, 20 + text.length, 20 + text.length + jsonPad);
  const b = 20 + text.length + jsonPad;
  dv.setUint32(b, bin.length, true); dv.setUint32(b + 4, 0x004e4942, true);
  out.set(bin, b + 8);
  return out;
}
