//! Names in MikuMikuDance files: Shift-JIS (cp932) in fixed-width NUL-terminated fields (VMD,
//! PMD), UTF-16LE or UTF-8 in PMX.
//!
//! Shift-JIS goes through `encoding_rs` (the crate Firefox uses; its `SHIFT_JIS` is the WHATWG
//! encoding, which is Windows code page 932 with the NEC and IBM extensions, exactly what MMD
//! writes, e.g. ① or ㈱ in model names). Hand-written tables would be thousands of lines to get
//! wrong, and `encoding_rs` is already in the dependency tree (symphonia uses it).
//!
//! A fixed field holds the name up to its first NUL; the bytes after it are garbage MMD left
//! (often 0xFD) and are ignored. MMD cuts names that do not fit byte-wise, possibly through a
//! two-byte character, so a VMD's 15-byte bone name may be a prefix of the model's 20-byte
//! name: [`vmd_name_matches`] compares the way MMD does, and the cut byte is kept (see
//! [`CUT_LEAD_BYTE_BASE`]) so such a name writes back as it was.

use encoding_rs::SHIFT_JIS;

/// Where a field ends with the first byte of a two-byte character MMD cut off (0x81–0x9F,
/// 0xE0–0xFC), the decoded name ends with this character plus that byte: U+10FF81–U+10FFFC in
/// Unicode's private-use plane 16, which no Shift-JIS text decodes to (cp932's user-defined
/// characters land in U+E000–U+E757). [`encode_sjis`] writes it back as the byte, so a VMD
/// that names a bone by a cut name reads and writes back byte for byte.
pub const CUT_LEAD_BYTE_BASE: u32 = 0x10_FF00;

fn is_lead_byte(b: u8) -> bool {
    matches!(b, 0x81..=0x9F | 0xE0..=0xFC)
}

/// Decodes a fixed-width Shift-JIS field up to its first NUL. A two-byte character cut off at
/// the end becomes the marker described at [`CUT_LEAD_BYTE_BASE`]; other bytes that are not
/// valid cp932 become U+FFFD.
pub fn decode_sjis_field(field: &[u8]) -> String {
    let end = field.iter().position(|&b| b == 0).unwrap_or(field.len());
    let field = &field[..end];
    let mut i = 0;
    let mut cut = None;
    while i < field.len() {
        if is_lead_byte(field[i]) {
            if i + 1 == field.len() {
                cut = Some(field[i]);
            }
            i += 2;
        } else {
            i += 1;
        }
    }
    match cut {
        Some(b) => {
            let (text, _, _) = SHIFT_JIS.decode(&field[..field.len() - 1]);
            let mut s = text.into_owned();
            s.extend(char::from_u32(CUT_LEAD_BYTE_BASE + u32::from(b)));
            s
        }
        None => SHIFT_JIS.decode(field).0.into_owned(),
    }
}

/// Encodes a name into Shift-JIS (a cut-character marker, see [`CUT_LEAD_BYTE_BASE`], as its
/// byte). `Err(c)`: the first character Shift-JIS cannot hold.
pub fn encode_sjis(name: &str) -> Result<Vec<u8>, char> {
    let cut_byte = |c: char| {
        let v = u32::from(c).wrapping_sub(CUT_LEAD_BYTE_BASE);
        u8::try_from(v).ok().filter(|&b| is_lead_byte(b))
    };
    if name.chars().any(|c| cut_byte(c).is_some()) {
        let mut out = Vec::new();
        for c in name.chars() {
            match cut_byte(c) {
                Some(b) => out.push(b),
                None => out.extend(encode_sjis(c.encode_utf8(&mut [0u8; 4]))?),
            }
        }
        return Ok(out);
    }
    let (bytes, _, had_errors) = SHIFT_JIS.encode(name);
    if had_errors {
        // Find the culprit, character by character, to name it.
        for c in name.chars() {
            let mut buf = [0u8; 4];
            let (_, _, bad) = SHIFT_JIS.encode(c.encode_utf8(&mut buf));
            if bad {
                return Err(c);
            }
        }
        return Err('\u{FFFD}');
    }
    Ok(bytes.into_owned())
}

/// The Shift-JIS bytes of `name` cut to at most `width` bytes the way MMD cuts them: byte-wise,
/// even through a two-byte character. MMD finds a model's bone for a VMD key by comparing the
/// model name's first `width` bytes with the field, so a cleaner cut at a character boundary
/// would name no bone in MMD.
pub fn encode_sjis_field(name: &str, width: usize) -> Result<Vec<u8>, char> {
    let mut b = encode_sjis(name)?;
    b.truncate(width);
    Ok(b)
}

/// Decodes UTF-16LE (PMX text); an odd trailing byte and unpaired surrogates become U+FFFD.
pub fn decode_utf16le(bytes: &[u8]) -> String {
    let units = bytes.chunks_exact(2).map(|c| u16::from_le_bytes([c[0], c[1]]));
    let mut s: String = char::decode_utf16(units).map(|r| r.unwrap_or('\u{FFFD}')).collect();
    if bytes.len() % 2 == 1 {
        s.push('\u{FFFD}');
    }
    s
}

/// Whether a name read from a VMD field of `width` bytes (15 for bones and morphs) names the
/// model's `model_name`: equal, or equal to the model's name cut to `width` Shift-JIS bytes as
/// MMD cuts it (byte-wise: a cut two-byte character decodes to the same marker on both sides).
pub fn vmd_name_matches(vmd_name: &str, model_name: &str, width: usize) -> bool {
    if vmd_name == model_name {
        return true;
    }
    let (bytes, _, _) = SHIFT_JIS.encode(model_name);
    bytes.len() > width && decode_sjis_field(&bytes[..width]) == vmd_name
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decodes_up_to_the_nul_and_ignores_garbage_after_it() {
        // センター, NUL, then MMD's 0xFD filler (from a real VMD's first key).
        let field = [0x83, 0x5a, 0x83, 0x93, 0x83, 0x5e, 0x81, 0x5b, 0x00, 0xfd, 0xfd, 0xfd, 0xfd, 0xfd, 0xfd];
        assert_eq!(decode_sjis_field(&field), "センター");
        // No NUL: the whole field is the name.
        assert_eq!(decode_sjis_field(b"abc"), "abc");
    }

    #[test]
    fn cp932_extensions_round_trip() {
        for name in ["左足ＩＫ", "①", "㈱", "上半身2", "ｾﾝﾀｰ"] {
            let b = encode_sjis(name).unwrap();
            assert_eq!(decode_sjis_field(&b), name);
        }
        assert_eq!(encode_sjis("a😀"), Err('😀'));
    }

    #[test]
    fn field_encoding_cuts_byte_wise_as_mmd_does() {
        // 8 two-byte characters = 16 bytes; a 15-byte field keeps 7 and a half.
        let b = encode_sjis_field("あいうえおかきく", 15).unwrap();
        assert_eq!(b.len(), 15);
        assert!(vmd_name_matches(&decode_sjis_field(&b), "あいうえおかきく", 15));
        assert_eq!(encode_sjis_field("センター", 15).unwrap().len(), 8);
    }

    #[test]
    fn vmd_names_match_byte_cut_model_names() {
        let model = "右人指１先ＸＹＺ"; // 16 bytes in Shift-JIS
        let bytes = encode_sjis(model).unwrap();
        let cut = decode_sjis_field(&bytes[..15]);
        assert_eq!(cut.chars().last(), char::from_u32(CUT_LEAD_BYTE_BASE + u32::from(bytes[14])));
        // It writes back as the same 15 bytes.
        assert_eq!(encode_sjis(&cut).unwrap(), &bytes[..15]);
        assert!(vmd_name_matches(&cut, model, 15));
        assert!(vmd_name_matches(model, model, 15));
        assert!(!vmd_name_matches("右人指１", model, 15));
    }

    #[test]
    fn utf16_decoding_is_lossy_not_failing() {
        assert_eq!(decode_utf16le(&[0x42, 0x30]), "あ");
        assert_eq!(decode_utf16le(&[0x00, 0xD8]), "\u{FFFD}");
        assert_eq!(decode_utf16le(&[0x41, 0x00, 0x42]), "A\u{FFFD}");
    }
}
