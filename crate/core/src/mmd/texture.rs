//! MMD texture files as images the drawing side can take: PNG and JPEG pass through (the
//! browser decodes them); TGA (MMD models' usual format) and BMP (toon ramps, PMD textures,
//! sphere maps `.sph`/`.spa`), which browsers do not decode (TGA) or not in every variant (BMP),
//! are decoded here with the `image` crate (only its `tga` and `bmp` codecs) and handed on as
//! an uncompressed-filter PNG, so the rest of the engine (upload, GLB export) sees PNG only.

use thiserror::Error;

use crate::import::{MeshTexture, Sampler};

/// Why a texture file could not be used (the model still draws, with the material's colour).
#[derive(Debug, Error, Clone, PartialEq)]
pub enum TextureError {
    #[error("texture '{file}': not a PNG, JPEG, BMP or TGA image (it starts with {start:02x?})")]
    UnknownFormat { file: String, start: Vec<u8> },
    #[error("texture '{file}': the {format} image could not be decoded: {message}")]
    Decode { file: String, format: &'static str, message: String },
    #[error("texture '{file}': {width}×{height} pixels is larger than a texture may be ({max} a side)")]
    TooLarge { file: String, width: u32, height: u32, max: u32 },
}

/// The largest side accepted (WebGL2's guaranteed minimum is 2048; every GPU here has 8192).
pub const MAX_TEXTURE_SIDE: u32 = 8192;

/// MMD samples textures repeating, linearly filtered with mipmaps.
pub fn mmd_sampler() -> Sampler {
    Sampler { mag_filter: Some(9729), min_filter: Some(9987), wrap_s: 10497, wrap_t: 10497 }
}

/// The encoded image format a texture file holds, by its first bytes (TGA has no magic: any
/// other file named `.tga` is tried as TGA).
fn sniff(file: &str, bytes: &[u8]) -> Option<&'static str> {
    if bytes.starts_with(b"\x89PNG\r\n\x1a\n") {
        Some("png")
    } else if bytes.starts_with(&[0xFF, 0xD8, 0xFF]) {
        Some("jpeg")
    } else if bytes.starts_with(b"BM") {
        Some("bmp")
    } else if file.to_lowercase().ends_with(".tga") {
        Some("tga")
    } else {
        None
    }
}

/// A texture file's bytes as a [`MeshTexture`] (PNG or JPEG; TGA and BMP decoded and re-encoded
/// as PNG), sampled as MMD samples it.
pub fn mesh_texture(file: &str, bytes: &[u8]) -> Result<MeshTexture, TextureError> {
    let sampler = mmd_sampler();
    match sniff(file, bytes) {
        Some("png") => Ok(MeshTexture { mime_type: "image/png".into(), image: bytes.to_vec(), sampler }),
        Some("jpeg") => Ok(MeshTexture { mime_type: "image/jpeg".into(), image: bytes.to_vec(), sampler }),
        Some(f) => {
            let (w, h, rgba) = decode_rgba(file, f, bytes)?;
            Ok(MeshTexture { mime_type: "image/png".into(), image: encode_png(w, h, &rgba), sampler })
        }
        None => Err(TextureError::UnknownFormat { file: file.into(), start: bytes.iter().take(8).copied().collect() }),
    }
}

/// Decodes a TGA or BMP file into RGBA8 rows, top row first.
pub fn decode_rgba(file: &str, format: &'static str, bytes: &[u8]) -> Result<(u32, u32, Vec<u8>), TextureError> {
    let fmt = if format == "bmp" { image::ImageFormat::Bmp } else { image::ImageFormat::Tga };
    let err = |message: String| TextureError::Decode { file: file.into(), format, message };
    let mut reader = image::ImageReader::with_format(std::io::Cursor::new(bytes), fmt);
    let mut limits = image::Limits::default();
    limits.max_image_width = Some(MAX_TEXTURE_SIDE);
    limits.max_image_height = Some(MAX_TEXTURE_SIDE);
    reader.limits(limits);
    let img = reader.decode().map_err(|e| match e {
        image::ImageError::Limits(_) => TextureError::TooLarge { file: file.into(), width: 0, height: 0, max: MAX_TEXTURE_SIDE },
        e => err(e.to_string()),
    })?;
    let rgba = img.to_rgba8();
    let (w, h) = rgba.dimensions();
    if w == 0 || h == 0 {
        return Err(err(format!("the image is {w}×{h} pixels")));
    }
    Ok((w, h, rgba.into_raw()))
}

/// RGBA8 rows as a PNG (8-bit RGBA, filter 0 on every row, zlib at a fast level).
pub fn encode_png(width: u32, height: u32, rgba: &[u8]) -> Vec<u8> {
    use std::io::Write;
    let row = width as usize * 4;
    let mut raw = Vec::with_capacity((row + 1) * height as usize);
    for r in rgba.chunks_exact(row.max(1)).take(height as usize) {
        raw.push(0);
        raw.extend_from_slice(r);
    }
    let mut z = flate2::write::ZlibEncoder::new(Vec::new(), flate2::Compression::fast());
    // Writing into a Vec cannot fail.
    let _ = z.write_all(&raw);
    let idat = z.finish().unwrap_or_default();
    let mut out = b"\x89PNG\r\n\x1a\n".to_vec();
    let mut ihdr = Vec::with_capacity(13);
    ihdr.extend_from_slice(&width.to_be_bytes());
    ihdr.extend_from_slice(&height.to_be_bytes());
    ihdr.extend_from_slice(&[8, 6, 0, 0, 0]);
    chunk(&mut out, b"IHDR", &ihdr);
    chunk(&mut out, b"IDAT", &idat);
    chunk(&mut out, b"IEND", &[]);
    out
}

fn chunk(out: &mut Vec<u8>, kind: &[u8; 4], data: &[u8]) {
    out.extend_from_slice(&(data.len() as u32).to_be_bytes());
    out.extend_from_slice(kind);
    out.extend_from_slice(data);
    let mut crc = flate2::Crc::new();
    crc.update(kind);
    crc.update(data);
    out.extend_from_slice(&crc.sum().to_be_bytes());
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 2×2 24-bit BMP (bottom-up rows, BGR, rows padded to 4 bytes), written by hand.
    fn bmp_2x2() -> Vec<u8> {
        let pixels: [[u8; 3]; 4] = [[0, 0, 255], [0, 255, 0], [255, 0, 0], [255, 255, 255]]; // BGR: red, green (bottom row); blue, white (top)
        let mut data = Vec::new();
        for row in pixels.chunks(2) {
            for p in row {
                data.extend_from_slice(p);
            }
            data.extend_from_slice(&[0, 0]);
        }
        let mut f = b"BM".to_vec();
        f.extend_from_slice(&((54 + data.len()) as u32).to_le_bytes());
        f.extend_from_slice(&[0; 4]);
        f.extend_from_slice(&54u32.to_le_bytes());
        f.extend_from_slice(&40u32.to_le_bytes());
        f.extend_from_slice(&2i32.to_le_bytes());
        f.extend_from_slice(&2i32.to_le_bytes());
        f.extend_from_slice(&1u16.to_le_bytes());
        f.extend_from_slice(&24u16.to_le_bytes());
        f.extend_from_slice(&[0; 24]);
        f.extend_from_slice(&data);
        f
    }

    #[test]
    fn bmp_decodes_top_row_first() {
        let (w, h, rgba) = decode_rgba("t.bmp", "bmp", &bmp_2x2()).unwrap();
        assert_eq!((w, h), (2, 2));
        assert_eq!(&rgba[0..8], &[0, 0, 255, 255, 255, 255, 255, 255], "top row: blue, white");
        assert_eq!(&rgba[8..16], &[255, 0, 0, 255, 0, 255, 0, 255], "bottom row: red, green");
    }

    #[test]
    fn rle_tga_with_alpha_decodes() {
        // Type 10 (RLE true colour), 3×1, 32 bits, top-left origin (descriptor 0x28): one run of
        // three BGRA pixels.
        let mut f = vec![0, 0, 10, 0, 0, 0, 0, 0, 0, 0, 0, 0];
        f.extend_from_slice(&3u16.to_le_bytes());
        f.extend_from_slice(&1u16.to_le_bytes());
        f.extend_from_slice(&[32, 0x28]);
        f.extend_from_slice(&[0x82, 10, 20, 30, 128]);
        let t = mesh_texture("a.TGA", &f).unwrap();
        assert_eq!(t.mime_type, "image/png");
        let (_, _, rgba) = decode_rgba("a.tga", "tga", &f).unwrap();
        assert_eq!(rgba, [30, 20, 10, 128].repeat(3));
    }

    #[test]
    fn bad_files_are_typed_errors() {
        assert!(matches!(mesh_texture("x.dds", b"DDS \0\0\0"), Err(TextureError::UnknownFormat { .. })));
        assert!(matches!(mesh_texture("x.bmp", b"BM\x10"), Err(TextureError::Decode { format: "bmp", .. })));
        assert!(matches!(mesh_texture("x.tga", &[0, 0, 2]), Err(TextureError::Decode { format: "tga", .. })));
    }

    #[test]
    fn png_passes_through_and_encoded_png_has_valid_chunks() {
        let png = encode_png(2, 1, &[1, 2, 3, 4, 5, 6, 7, 8]);
        let t = mesh_texture("p.png", &png).unwrap();
        assert_eq!(t.image, png);
        // IHDR's CRC over "IHDR" + data, as any PNG reader checks it.
        assert_eq!(&png[12..16], b"IHDR");
        let crc = u32::from_be_bytes(png[29..33].try_into().unwrap());
        let mut c = flate2::Crc::new();
        c.update(&png[12..29]);
        assert_eq!(crc, c.sum());
    }
}
