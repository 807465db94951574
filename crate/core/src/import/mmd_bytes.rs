//! The little-endian byte cursor and the one error type shared by the MikuMikuDance readers
//! (VMD motions, PMD and PMX models).
//!
//! Every read names the section it is in, so a truncated or garbled file is refused with the
//! file, the section and the byte offset where it went wrong; every declared count is checked
//! against the bytes left *before* anything is allocated for it (a 40-byte file claiming four
//! billion vertices is refused, not attempted). No input makes these readers panic.

use glam::{Quat, Vec2, Vec3, Vec4};
use thiserror::Error;

use super::mmd_text;

/// Why an MMD file (VMD, PMD, PMX) could not be read, or a VMD not written, with the file and
/// the offending values.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum MmdError {
    #[error("{file}: not a {expected} file (it starts with {found:?})")]
    BadMagic { file: String, expected: &'static str, found: String },
    #[error("{file}: {format} version {version} is not supported (supported: {supported})")]
    BadVersion { file: String, format: &'static str, version: String, supported: &'static str },
    #[error("{file}: truncated in {section} at byte {offset}: {needed} bytes needed, {available} left")]
    Truncated { file: String, section: String, offset: usize, needed: usize, available: usize },
    #[error(
        "{file}: {section} at byte {offset} declares {count} entries of at least {min_entry_bytes} bytes each, \
         but only {available} bytes are left"
    )]
    CountTooLarge { file: String, section: String, offset: usize, count: i64, min_entry_bytes: usize, available: usize },
    #[error("{file}: {section} at byte {offset}: {what} is {value} (allowed: {allowed})")]
    BadValue { file: String, section: String, offset: usize, what: &'static str, value: i64, allowed: &'static str },
    #[error("{file}: {section} {entry}: {what} {index} is out of range (there are {count})")]
    IndexOutOfRange { file: String, section: &'static str, entry: usize, what: &'static str, index: i64, count: usize },
    #[error("{file}: {what} '{name}' cannot be written in Shift-JIS (character {character:?})")]
    NotShiftJis { file: String, what: &'static str, name: String, character: char },
    #[error("{file}: {what} is {value}, more than a VMD can hold (at most {limit})")]
    TooMany { file: String, what: &'static str, value: usize, limit: u64 },
    #[error("{file}: {what} of key {key} ('{name}', frame {frame}) is not finite")]
    NotFinite { file: String, what: &'static str, key: usize, name: String, frame: u32 },
    #[error("{file}: Bézier control value {value} of key {key} ('{name}', frame {frame}) is outside 0–127")]
    BadCurve { file: String, key: usize, name: String, frame: u32, value: u8 },
}

impl MmdError {
    /// The file the error is about.
    pub fn file(&self) -> &str {
        match self {
            MmdError::BadMagic { file, .. }
            | MmdError::BadVersion { file, .. }
            | MmdError::Truncated { file, .. }
            | MmdError::CountTooLarge { file, .. }
            | MmdError::BadValue { file, .. }
            | MmdError::IndexOutOfRange { file, .. }
            | MmdError::NotShiftJis { file, .. }
            | MmdError::TooMany { file, .. }
            | MmdError::NotFinite { file, .. }
            | MmdError::BadCurve { file, .. } => file,
        }
    }

    /// A short machine-readable kind, stable for the JS API.
    pub fn kind(&self) -> &'static str {
        match self {
            MmdError::BadMagic { .. } => "mmd-bad-magic",
            MmdError::BadVersion { .. } => "mmd-bad-version",
            MmdError::Truncated { .. } => "mmd-truncated",
            MmdError::CountTooLarge { .. } => "mmd-count-too-large",
            MmdError::BadValue { .. } => "mmd-bad-value",
            MmdError::IndexOutOfRange { .. } => "mmd-index-out-of-range",
            MmdError::NotShiftJis { .. } => "mmd-not-shift-jis",
            MmdError::TooMany { .. } => "mmd-too-many",
            MmdError::NotFinite { .. } => "mmd-not-finite",
            MmdError::BadCurve { .. } => "mmd-bad-curve",
        }
    }
}

/// The first bytes of a file as a person reads them, for [`MmdError::BadMagic`].
pub(crate) fn printable_start(bytes: &[u8], n: usize) -> String {
    bytes.iter().take(n).map(|&b| if b.is_ascii_graphic() || b == b' ' { b as char } else { '.' }).collect()
}

/// Text encoding of a PMX file's strings (header global 0).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum TextEncoding {
    Utf16Le,
    Utf8,
}

/// A bounds-checked little-endian reader over one file's bytes.
pub(crate) struct Reader<'a> {
    bytes: &'a [u8],
    pos: usize,
    file: &'a str,
    section: &'static str,
}

impl<'a> Reader<'a> {
    pub(crate) fn new(file: &'a str, bytes: &'a [u8]) -> Self {
        Self { bytes, pos: 0, file, section: "header" }
    }

    /// Names the section the following reads belong to (for errors).
    pub(crate) fn section(&mut self, section: &'static str) {
        self.section = section;
    }

    pub(crate) fn pos(&self) -> usize {
        self.pos
    }

    pub(crate) fn remaining(&self) -> usize {
        self.bytes.len() - self.pos
    }

    pub(crate) fn at_end(&self) -> bool {
        self.pos >= self.bytes.len()
    }

    pub(crate) fn truncated(&self, needed: usize) -> MmdError {
        MmdError::Truncated {
            file: self.file.to_string(),
            section: self.section.to_string(),
            offset: self.pos,
            needed,
            available: self.remaining(),
        }
    }

    pub(crate) fn bad_value(&self, offset: usize, what: &'static str, value: i64, allowed: &'static str) -> MmdError {
        MmdError::BadValue { file: self.file.to_string(), section: self.section.to_string(), offset, what, value, allowed }
    }

    pub(crate) fn bytes(&mut self, n: usize) -> Result<&'a [u8], MmdError> {
        if n > self.remaining() {
            return Err(self.truncated(n));
        }
        let s = &self.bytes[self.pos..self.pos + n];
        self.pos += n;
        Ok(s)
    }

    pub(crate) fn skip(&mut self, n: usize) -> Result<(), MmdError> {
        self.bytes(n).map(|_| ())
    }

    fn array<const N: usize>(&mut self) -> Result<[u8; N], MmdError> {
        let mut a = [0u8; N];
        a.copy_from_slice(self.bytes(N)?);
        Ok(a)
    }

    pub(crate) fn u8(&mut self) -> Result<u8, MmdError> {
        Ok(self.array::<1>()?[0])
    }
    pub(crate) fn i8(&mut self) -> Result<i8, MmdError> {
        Ok(i8::from_le_bytes(self.array()?))
    }
    pub(crate) fn u16(&mut self) -> Result<u16, MmdError> {
        Ok(u16::from_le_bytes(self.array()?))
    }
    pub(crate) fn i16(&mut self) -> Result<i16, MmdError> {
        Ok(i16::from_le_bytes(self.array()?))
    }
    pub(crate) fn u32(&mut self) -> Result<u32, MmdError> {
        Ok(u32::from_le_bytes(self.array()?))
    }
    pub(crate) fn i32(&mut self) -> Result<i32, MmdError> {
        Ok(i32::from_le_bytes(self.array()?))
    }
    pub(crate) fn f32(&mut self) -> Result<f32, MmdError> {
        Ok(f32::from_le_bytes(self.array()?))
    }
    pub(crate) fn vec2(&mut self) -> Result<Vec2, MmdError> {
        Ok(Vec2::new(self.f32()?, self.f32()?))
    }
    /// A joint record's eight-vector tail, the same in PMD and PMX: position, rotation,
    /// translation min/max, rotation min/max, spring translation/rotation. The head (names,
    /// kind, the two rigid bodies) differs per format and is read by the caller.
    pub(crate) fn joint_tail(&mut self, name: String, name_en: String, kind: u8, rigid_a: usize, rigid_b: usize) -> Result<super::mmd_model::MmdJoint, MmdError> {
        Ok(super::mmd_model::MmdJoint {
            name,
            name_en,
            kind,
            rigid_a,
            rigid_b,
            position: self.vec3()?,
            rotation_rad: self.vec3()?,
            translation_min: self.vec3()?,
            translation_max: self.vec3()?,
            rotation_min_rad: self.vec3()?,
            rotation_max_rad: self.vec3()?,
            spring_translation: self.vec3()?,
            spring_rotation: self.vec3()?,
        })
    }

    pub(crate) fn vec3(&mut self) -> Result<Vec3, MmdError> {
        Ok(Vec3::new(self.f32()?, self.f32()?, self.f32()?))
    }
    pub(crate) fn vec4(&mut self) -> Result<Vec4, MmdError> {
        Ok(Vec4::new(self.f32()?, self.f32()?, self.f32()?, self.f32()?))
    }
    /// A quaternion stored x, y, z, w (as MMD stores them), as read (not normalised).
    pub(crate) fn quat(&mut self) -> Result<Quat, MmdError> {
        Ok(Quat::from_xyzw(self.f32()?, self.f32()?, self.f32()?, self.f32()?))
    }

    /// A fixed-width Shift-JIS (cp932) field: up to the first NUL, the rest ignored.
    pub(crate) fn sjis(&mut self, width: usize) -> Result<String, MmdError> {
        Ok(mmd_text::decode_sjis_field(self.bytes(width)?))
    }

    /// A PMX text: an i32 byte length, then that many bytes in the file's encoding.
    pub(crate) fn pmx_text(&mut self, encoding: TextEncoding) -> Result<String, MmdError> {
        let at = self.pos;
        let len = self.i32()?;
        if len < 0 {
            return Err(self.bad_value(at, "text length", i64::from(len), "0 or more bytes"));
        }
        let b = self.bytes(len as usize)?;
        Ok(match encoding {
            TextEncoding::Utf16Le => mmd_text::decode_utf16le(b),
            TextEncoding::Utf8 => String::from_utf8_lossy(b).into_owned(),
        })
    }

    /// Reads a count of entries (`u32`, `i32` or `u16` as the format says) and checks that
    /// `count × min_entry_bytes` fits in the bytes left, so nothing is allocated for a count
    /// the file cannot hold.
    pub(crate) fn count(&mut self, width: CountWidth, min_entry_bytes: usize) -> Result<usize, MmdError> {
        let at = self.pos;
        let count: i64 = match width {
            CountWidth::U8 => i64::from(self.u8()?),
            CountWidth::U16 => i64::from(self.u16()?),
            CountWidth::U32 => i64::from(self.u32()?),
            CountWidth::I32 => i64::from(self.i32()?),
        };
        if count < 0 {
            return Err(self.bad_value(at, "entry count", count, "0 or more"));
        }
        let fits = (count as u64).checked_mul(min_entry_bytes as u64).is_some_and(|n| n <= self.remaining() as u64);
        if !fits {
            return Err(MmdError::CountTooLarge {
                file: self.file.to_string(),
                section: self.section.to_string(),
                offset: at,
                count,
                min_entry_bytes,
                available: self.remaining(),
            });
        }
        Ok(count as usize)
    }
}

/// How a section's entry count is stored.
#[derive(Clone, Copy, Debug)]
pub(crate) enum CountWidth {
    U8,
    U16,
    U32,
    I32,
}

/// Checks an optional index (−1 and other negatives read as "none" where the format allows it)
/// against the number of entries it points into.
pub(crate) fn check_index(
    file: &str,
    section: &'static str,
    entry: usize,
    what: &'static str,
    index: i64,
    count: usize,
) -> Result<usize, MmdError> {
    if index < 0 || index as u64 >= count as u64 {
        return Err(MmdError::IndexOutOfRange { file: file.to_string(), section, entry, what, index, count });
    }
    Ok(index as usize)
}

/// An index that may be −1 ("none"): `None` for −1, else checked like [`check_index`].
pub(crate) fn check_optional_index(
    file: &str,
    section: &'static str,
    entry: usize,
    what: &'static str,
    index: i64,
    count: usize,
) -> Result<Option<usize>, MmdError> {
    if index == -1 {
        return Ok(None);
    }
    check_index(file, section, entry, what, index, count).map(Some)
}
