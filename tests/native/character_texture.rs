//! Base-colour textures of imported characters (what the viewer samples): the Fox's PNG is
//! kept as the file holds it, with its sampler and the UV set its material names; an
//! untextured character (Xbot) has none; a broken or outside image is left out with a warning
//! and the part keeps its base colour.

use odori_core::import::{import_bytes, ImportOptions};
use odori_tests::read;

/// Width and height from a PNG's IHDR chunk.
fn png_size(png: &[u8]) -> (u32, u32) {
    assert!(png.starts_with(b"\x89PNG\r\n\x1a\n"), "not a PNG");
    assert_eq!(&png[12..16], b"IHDR");
    let be = |o: usize| u32::from_be_bytes([png[o], png[o + 1], png[o + 2], png[o + 3]]);
    (be(16), be(20))
}

#[test]
fn fox_keeps_its_base_colour_texture_sampler_and_uvs() {
    let rel = "gltf/Fox.glb";
    let im = import_bytes(rel, &read(rel), &ImportOptions::default()).unwrap();
    let mesh = im.mesh.as_ref().expect("the Fox has a skinned mesh");
    assert_eq!(mesh.textures.len(), 1, "one texture");
    let t = &mesh.textures[0];
    assert_eq!(t.mime_type, "image/png");
    assert_eq!(png_size(&t.image), (1024, 1024));
    // The file's sampler: linear magnification, linear-mipmap-linear minification, repeat.
    assert_eq!((t.sampler.mag_filter, t.sampler.min_filter, t.sampler.wrap_s, t.sampler.wrap_t), (Some(9729), Some(9987), 10497, 10497));
    for p in &mesh.parts {
        assert_eq!(p.texture, Some(0));
        assert_eq!(p.uvs.len(), p.positions.len(), "one UV per vertex");
        // The Fox's UVs lie on its atlas.
        assert!(p.uvs.iter().flatten().all(|v| (-0.01..=1.01).contains(v)), "UVs outside the atlas");
        let spread = p.uvs.iter().fold((f32::MAX, f32::MIN), |(lo, hi), uv| (lo.min(uv[0]), hi.max(uv[0])));
        assert!(spread.1 - spread.0 > 0.5, "UVs cover the atlas: {spread:?}");
    }
    assert!(!im.warnings.iter().any(|w| w.contains("texture")), "{:?}", im.warnings);
}

#[test]
fn untextured_character_has_no_texture() {
    let rel = "gltf/Xbot.glb";
    let im = import_bytes(rel, &read(rel), &ImportOptions::default()).unwrap();
    let mesh = im.mesh.as_ref().expect("Xbot has a skinned mesh");
    assert!(mesh.textures.is_empty());
    assert!(mesh.parts.iter().all(|p| p.texture.is_none() && p.uvs.is_empty()));
}

#[test]
fn an_image_that_is_not_png_or_jpeg_is_left_out_with_a_warning() {
    // The Fox with its PNG's signature broken: the import still succeeds, the part keeps its
    // base colour, and the warning names the texture.
    let mut bytes = read("gltf/Fox.glb");
    let at = bytes.windows(8).position(|w| w == b"\x89PNG\r\n\x1a\n").expect("the Fox holds a PNG");
    bytes[at + 1] = b'X';
    let im = import_bytes("Fox.glb", &bytes, &ImportOptions::default()).unwrap();
    let mesh = im.mesh.as_ref().unwrap();
    assert!(mesh.textures.is_empty());
    assert!(mesh.parts.iter().all(|p| p.texture.is_none()));
    assert!(im.warnings.iter().any(|w| w.contains("texture 0") && w.contains("not drawn")), "{:?}", im.warnings);
}

// ---- Export with textures (spec §M): what the GLB writer keeps of a textured character ----

use odori_core::export::gltf::{glb, GlbOptions};
use odori_core::import::{SkinnedMesh, UvTransform};

/// The JSON chunk of a GLB and its binary chunk.
fn split_glb(bytes: &[u8]) -> (serde_json::Value, Vec<u8>) {
    assert_eq!(&bytes[0..4], b"glTF");
    let json_len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    let json: serde_json::Value = serde_json::from_slice(&bytes[20..20 + json_len]).unwrap();
    let at = 20 + json_len;
    let bin_len = u32::from_le_bytes(bytes[at..at + 4].try_into().unwrap()) as usize;
    (json, bytes[at + 8..at + 8 + bin_len].to_vec())
}

/// A GLB from a JSON document and a binary chunk (both padded to 4 bytes, as the format asks).
fn join_glb(json: &serde_json::Value, bin: &[u8]) -> Vec<u8> {
    let mut text = serde_json::to_vec(json).unwrap();
    while text.len() % 4 != 0 {
        text.push(b' ');
    }
    let mut bin = bin.to_vec();
    while bin.len() % 4 != 0 {
        bin.push(0);
    }
    let mut out = Vec::new();
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&((12 + 8 + text.len() + 8 + bin.len()) as u32).to_le_bytes());
    out.extend_from_slice(&(text.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&text);
    out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(&bin);
    out
}

/// The Fox (its first clip and its textured mesh) as imported.
fn fox() -> (odori_core::Clip, SkinnedMesh) {
    let rel = "gltf/Fox.glb";
    let im = import_bytes(rel, &read(rel), &ImportOptions::default()).unwrap();
    (im.clips[0].clone(), im.mesh.expect("the Fox has a mesh"))
}

fn reimport(bytes: &[u8], fps: f32) -> SkinnedMesh {
    let back = import_bytes("export.glb", bytes, &ImportOptions { gltf_fps: fps, ..Default::default() }).unwrap();
    assert!(!back.warnings.iter().any(|w| w.contains("texture")), "{:?}", back.warnings);
    back.mesh.expect("the export holds the mesh")
}

#[test]
fn fox_exports_its_image_sampler_and_uvs() {
    let (clip, mesh) = fox();
    let bytes = glb(&clip.skeleton, &[&clip], &GlbOptions { mesh: Some(&mesh) }).unwrap();
    let (json, bin) = split_glb(&bytes);
    // The image sits in the binary chunk through a buffer view, with its MIME type.
    let image = &json["images"][0];
    assert_eq!(image["mimeType"], "image/png");
    assert!(image.get("uri").is_none());
    let view = &json["bufferViews"][image["bufferView"].as_u64().unwrap() as usize];
    let (off, len) = (view["byteOffset"].as_u64().unwrap() as usize, view["byteLength"].as_u64().unwrap() as usize);
    assert_eq!(&bin[off..off + len], mesh.textures[0].image.as_slice(), "the PNG is written byte for byte");
    assert!(view.get("target").is_none(), "an image's buffer view has no target");
    assert_eq!((json["samplers"][0]["magFilter"].as_u64(), json["samplers"][0]["minFilter"].as_u64()), (Some(9729), Some(9987)));
    let info = &json["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"];
    assert_eq!(info["index"], 0);
    assert!(json["meshes"][0]["primitives"][0]["attributes"].get("TEXCOORD_0").is_some());
    assert!(json.get("extensionsUsed").is_none(), "no transform, no extension");

    // And back: the same image, sampler and UVs on every part.
    let back = reimport(&bytes, clip.fps);
    assert_eq!(back.textures, mesh.textures);
    assert_eq!(back.parts.len(), mesh.parts.len());
    for (a, b) in mesh.parts.iter().zip(&back.parts) {
        assert_eq!(b.texture, Some(0));
        assert_eq!(a.uvs, b.uvs, "UVs are written as f32, exactly");
        assert_eq!(b.uv_transform, None);
    }
}

#[test]
fn a_texture_transform_is_written_with_its_extension_and_read_back() {
    let (clip, mut mesh) = fox();
    let t = UvTransform { offset: [0.25, -0.5], rotation_rad: 0.3, scale: [0.5, 2.0] };
    for p in &mut mesh.parts {
        p.uv_transform = Some(t);
    }
    let bytes = glb(&clip.skeleton, &[&clip], &GlbOptions { mesh: Some(&mesh) }).unwrap();
    let (json, _) = split_glb(&bytes);
    assert_eq!(json["extensionsUsed"], serde_json::json!(["KHR_texture_transform"]));
    let ext = &json["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["extensions"]["KHR_texture_transform"];
    assert_eq!(ext["offset"], serde_json::json!([0.25, -0.5]));
    assert_eq!(ext["scale"], serde_json::json!([0.5, 2.0]));
    assert!((ext["rotation"].as_f64().unwrap() - 0.3).abs() < 1e-6);
    assert_eq!(ext["texCoord"], 0, "the one UV set written");
    let back = reimport(&bytes, clip.fps);
    assert!(back.parts.iter().all(|p| p.uv_transform == Some(t)), "{:?}", back.parts[0].uv_transform);
}

#[test]
fn the_transform_tex_coord_override_picks_the_uv_set() {
    // An exported Fox edited so the true UVs are TEXCOORD_1 and TEXCOORD_0 holds other numbers
    // (the positions' first two components): only a reader that honours the transform's
    // texCoord gets the Fox's UVs back.
    let (clip, mesh) = fox();
    let bytes = glb(&clip.skeleton, &[&clip], &GlbOptions { mesh: Some(&mesh) }).unwrap();
    let (mut json, bin) = split_glb(&bytes);
    let attrs = json["meshes"][0]["primitives"][0]["attributes"].clone();
    let pos = &json["accessors"][attrs["POSITION"].as_u64().unwrap() as usize];
    let decoy = serde_json::json!({ "bufferView": pos["bufferView"], "componentType": 5126, "count": pos["count"], "type": "VEC2" });
    let accessors = json["accessors"].as_array_mut().unwrap();
    accessors.push(decoy);
    let decoy_index = accessors.len() - 1;
    let a = &mut json["meshes"][0]["primitives"][0]["attributes"];
    a["TEXCOORD_1"] = attrs["TEXCOORD_0"].clone();
    a["TEXCOORD_0"] = serde_json::json!(decoy_index);
    json["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"]["extensions"] = serde_json::json!({ "KHR_texture_transform": { "texCoord": 1 } });
    json["extensionsUsed"] = serde_json::json!(["KHR_texture_transform"]);
    let back = reimport(&join_glb(&json, &bin), clip.fps);
    assert_eq!(back.parts[0].uvs, mesh.parts[0].uvs, "the override's set is read");
    assert_eq!(back.parts[0].uv_transform, Some(UvTransform::default()), "an identity transform");
}

#[test]
fn uv_transform_is_scale_then_rotation_then_offset() {
    // Scale (0.5, 2), a quarter turn, offset (0.1, 0.2): (1, 1) → (0.5, 2) → (2, -0.5) → (2.1, -0.3).
    let t = UvTransform { offset: [0.1, 0.2], rotation_rad: std::f32::consts::FRAC_PI_2, scale: [0.5, 2.0] };
    let [u, v] = t.apply([1.0, 1.0]);
    assert!((u - 2.1).abs() < 1e-6 && (v + 0.3).abs() < 1e-6, "({u}, {v})");
    assert_eq!(UvTransform::default().apply([0.3, 0.7]), [0.3, 0.7]);
}
