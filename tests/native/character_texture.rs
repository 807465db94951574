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
