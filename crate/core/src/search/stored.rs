//! The search index in a compact, versioned binary form, so that a large library is not
//! indexed again on every visit (the app keeps it in IndexedDB, `www/project/index-store.js`).
//! It holds what building the index computed — every clip's normalised hip-origin features and
//! its per-chunk joint bounding boxes (the fast search's lower bounds) — with the ids the
//! caller gave the clips and a content key per clip. Derived data that costs one pass to make
//! (the lane layout, the shoulder-origin features) is not stored: it is built on first use, as
//! for a freshly built index.
//!
//! Content keys (XXH3-128, from `xxhash-rust`) say whether a stored index still fits the
//! library: [`clip_key`] hashes a clip's motion (name, rate, skeleton, every channel value) —
//! not its derived features, so checking costs a hash, not an index build; [`library_key`]
//! hashes the ordered clip keys with the format version and frame rate. A library that changed
//! has another key, and [`open_or_build`] rebuilds. A checksum (XXH3-128 of everything after
//! the header) catches bytes damaged in storage; a reader never panics on bad bytes, it returns
//! a [`StoredIndexError`] naming what is wrong.
//!
//! Layout (little-endian): `"ODORSIDX"`, version `u32`, reserved `u32`, checksum `u128`; then
//! fps `f32`, box chunk frames `u32`, box floats `u32`, clip count `u32`, skipped count `u32`;
//! per clip: key `u128`, id `u32`, name (`u32` length + UTF-8), fps `f32`, frames `u32`, box
//! floats `u32`, features (`frames × 63` `f32`), boxes; per skipped clip: name, reason. When the
//! running build lays its boxes out otherwise (chunk or lane sizes changed), the stored boxes
//! are dropped and built again: the features are what the result depends on.

use glam::Vec3;
use thiserror::Error;
use xxhash_rust::xxh3::{xxh3_128, Xxh3};

use crate::clip::Clip;
use crate::canon::normalize::Origin;

use super::features::{
    ClipFeatures, FeatureIndex, MotionFeatures, SkippedClip, BOX_CHUNK_FRAMES, FRAME_FLOATS,
};
use super::lanes::BOX_FLOATS;

/// Version of the binary form; a reader refuses any other.
pub const STORED_INDEX_VERSION: u32 = 1;
const MAGIC: &[u8; 8] = b"ODORSIDX";
/// Magic, version, reserved, checksum.
const HEADER_BYTES: usize = 8 + 4 + 4 + 16;
/// Folded into every content key: bump when the features of a clip are derived differently
/// (resampling, canonical joints, normalisation), so keys made by an older engine no longer match.
const FEATURES_VERSION: u32 = 1;

/// Why stored bytes could not be read back as an index.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum StoredIndexError {
    #[error("not a stored search index: it starts with {found:?}, not \"ODORSIDX\"")]
    NotAnIndex { found: String },
    #[error("stored search index has version {found}; this engine reads version {expected} (it is rebuilt)")]
    Version { found: u32, expected: u32 },
    #[error("stored search index is truncated: {needed} bytes needed at offset {at}, the data has {len}")]
    Truncated {
        at: usize,
        needed: usize,
        len: usize,
    },
    #[error("stored search index is corrupt: checksum {found:032x}, expected {expected:032x}")]
    Checksum { expected: u128, found: u128 },
    #[error("stored search index is corrupt: {what}")]
    Corrupt { what: String },
}

/// A clip's id and content key in a stored index.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct StoredClip {
    /// The caller's id for the clip (the app's library clip id).
    pub id: u32,
    /// [`clip_key`] (or [`positions_key`]) of the motion the clip was indexed from.
    pub key: u128,
}

/// An index with its clips' ids and keys: what is stored and what is read back.
#[derive(Clone, Debug)]
pub struct StoredIndex {
    pub index: FeatureIndex,
    /// One per `index.clips`, in the same order.
    pub clips: Vec<StoredClip>,
}

impl StoredIndex {
    /// [`library_key`] of the clips, in order.
    pub fn library_key(&self) -> u128 {
        library_key(self.index.fps, self.clips.iter().map(|c| c.key))
    }
}

/// Content key of a clip as the index would see it: its name, frame rate, skeleton and every
/// rotation and translation value, bit for bit.
pub fn clip_key(name: &str, clip: &Clip) -> u128 {
    let mut h = KeyHasher::new(b"clip");
    h.str(name);
    h.f32s(&[clip.fps]);
    h.u32(clip.skeleton.joints.len() as u32);
    for j in &clip.skeleton.joints {
        h.str(&j.name);
        h.u32(j.parent.map_or(u32::MAX, |p| p as u32));
        h.f32s(&j.rest_offset.to_array());
        h.f32s(&j.rest_rotation.to_array());
        h.u32(j.end_site as u32);
    }
    h.u32(clip.rotations.len() as u32);
    h.floats(clip.rotations.iter().flat_map(|q| q.to_array()));
    for t in &clip.translations {
        h.u32(t.joint as u32);
        h.u32(t.values.len() as u32);
        h.floats(t.values.iter().flat_map(|v| v.to_array()));
    }
    h.finish()
}

/// Content key of a clip given as canonical world positions (`SearchIndex.addFeatures`).
pub fn positions_key(name: &str, positions: &[Vec3]) -> u128 {
    let mut h = KeyHasher::new(b"positions");
    h.str(name);
    h.floats(positions.iter().flat_map(|v| v.to_array()));
    h.finish()
}

/// Key of a whole library: the format version, the index's frame rate and the ordered clip keys.
pub fn library_key(fps: f32, clip_keys: impl IntoIterator<Item = u128>) -> u128 {
    let mut h = KeyHasher::new(b"library");
    h.u32(STORED_INDEX_VERSION);
    h.f32s(&[fps]);
    for k in clip_keys {
        h.0.update(&k.to_le_bytes());
    }
    h.finish()
}

/// Streams values into XXH3-128 in blocks (one `update` per value would be slow).
struct KeyHasher(Xxh3, Vec<u8>);

impl KeyHasher {
    fn new(kind: &[u8]) -> KeyHasher {
        let mut h = Xxh3::new();
        h.update(kind);
        h.update(&FEATURES_VERSION.to_le_bytes());
        KeyHasher(h, Vec::with_capacity(1 << 16))
    }
    fn u32(&mut self, v: u32) {
        self.0.update(&v.to_le_bytes());
    }
    fn str(&mut self, s: &str) {
        self.u32(s.len() as u32);
        self.0.update(s.as_bytes());
    }
    fn f32s(&mut self, v: &[f32]) {
        self.floats(v.iter().copied());
    }
    fn floats(&mut self, v: impl Iterator<Item = f32>) {
        for x in v {
            self.1.extend_from_slice(&x.to_le_bytes());
            if self.1.len() >= 1 << 16 {
                self.0.update(&self.1);
                self.1.clear();
            }
        }
        self.0.update(&self.1);
        self.1.clear();
    }
    fn finish(self) -> u128 {
        self.0.digest128()
    }
}

/// The index in its binary form. `clips` gives each indexed clip's id and key, in order.
/// (Borrowed, not a [`StoredIndex`]: a large index is not copied to be written.)
///
/// # Panics
/// When `clips` and `index.clips` differ in length (a caller's bug, not bad input).
pub fn encode_index(index: &FeatureIndex, clips: &[StoredClip]) -> Vec<u8> {
    assert_eq!(
        index.clips.len(),
        clips.len(),
        "one StoredClip per indexed clip"
    );
    let floats: usize = index
        .clips
        .iter()
        .map(|c| c.frame_count() * FRAME_FLOATS + c.chunk_boxes(Origin::Hips).len())
        .sum();
    let mut out = Vec::with_capacity(HEADER_BYTES + 20 + floats * 4 + index.clips.len() * 64);
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&STORED_INDEX_VERSION.to_le_bytes());
    out.extend_from_slice(&0u32.to_le_bytes());
    out.extend_from_slice(&0u128.to_le_bytes()); // checksum, filled in below
    let put_u32 = |out: &mut Vec<u8>, v: usize| out.extend_from_slice(&(v as u32).to_le_bytes());
    let put_str = |out: &mut Vec<u8>, s: &str| {
        out.extend_from_slice(&(s.len() as u32).to_le_bytes());
        out.extend_from_slice(s.as_bytes());
    };
    // Sized first and filled in place: the loop then compiles to plain stores (pushing byte
    // by byte was most of the time for hundreds of megabytes).
    let put_f32s = |out: &mut Vec<u8>, v: &[f32]| {
        let at = out.len();
        out.resize(at + v.len() * 4, 0);
        for (d, x) in out[at..].chunks_exact_mut(4).zip(v) {
            d.copy_from_slice(&x.to_le_bytes());
        }
    };
    put_f32s(&mut out, &[index.fps]);
    put_u32(&mut out, BOX_CHUNK_FRAMES);
    put_u32(&mut out, BOX_FLOATS);
    put_u32(&mut out, index.clips.len());
    put_u32(&mut out, index.skipped.len());
    for (c, s) in index.clips.iter().zip(clips) {
        out.extend_from_slice(&s.key.to_le_bytes());
        out.extend_from_slice(&s.id.to_le_bytes());
        put_str(&mut out, &c.name);
        put_f32s(&mut out, &[c.fps]);
        put_u32(&mut out, c.frame_count());
        let boxes = c.chunk_boxes(Origin::Hips);
        put_u32(&mut out, boxes.len());
        put_f32s(&mut out, &c.features(Origin::Hips).data);
        put_f32s(&mut out, boxes);
    }
    for s in &index.skipped {
        put_str(&mut out, &s.name);
        put_str(&mut out, &s.reason);
    }
    let sum = xxh3_128(&out[HEADER_BYTES..]);
    out[16..32].copy_from_slice(&sum.to_le_bytes());
    out
}

/// Reads bytes written by [`encode_index`] back. The version is checked first, then the
/// checksum, then every length against the data.
pub fn decode_index(bytes: &[u8]) -> Result<StoredIndex, StoredIndexError> {
    let mut r = Reader { bytes, at: 0 };
    let magic = r.take(8)?;
    if magic != MAGIC {
        return Err(StoredIndexError::NotAnIndex {
            found: String::from_utf8_lossy(magic).into_owned(),
        });
    }
    let version = r.u32()?;
    if version != STORED_INDEX_VERSION {
        return Err(StoredIndexError::Version {
            found: version,
            expected: STORED_INDEX_VERSION,
        });
    }
    let _reserved = r.u32()?;
    let expected = u128::from_le_bytes(r.take(16)?.try_into().expect("16 bytes"));
    let found = xxh3_128(&bytes[HEADER_BYTES..]);
    if found != expected {
        return Err(StoredIndexError::Checksum { expected, found });
    }
    let corrupt = |what: String| StoredIndexError::Corrupt { what };
    let fps = r.f32()?;
    let (chunk_frames, box_floats) = (r.u32()? as usize, r.u32()? as usize);
    // Boxes laid out as this build lays them out are kept; otherwise they are built again.
    let same_layout = chunk_frames == BOX_CHUNK_FRAMES && box_floats == BOX_FLOATS;
    let (clip_count, skipped_count) = (r.u32()? as usize, r.u32()? as usize);
    let mut index = FeatureIndex::with_fps(fps);
    if index.fps != fps {
        return Err(corrupt(format!(
            "frame rate {fps} is not a positive number"
        )));
    }
    let mut clips = Vec::new();
    for n in 0..clip_count {
        let key = u128::from_le_bytes(r.take(16)?.try_into().expect("16 bytes"));
        let id = r.u32()?;
        let name = r.string()?;
        let clip_fps = r.f32()?;
        let frames = r.u32()? as usize;
        let boxes_len = r.u32()? as usize;
        if frames == 0 {
            return Err(corrupt(format!("clip {n} (\"{name}\") has no frames")));
        }
        if same_layout && boxes_len != frames.div_ceil(BOX_CHUNK_FRAMES) * BOX_FLOATS {
            return Err(corrupt(format!(
                "clip {n} (\"{name}\"): {boxes_len} box values for {frames} frames"
            )));
        }
        let data = r.f32s(
            frames
                .checked_mul(FRAME_FLOATS)
                .ok_or_else(|| corrupt(format!("clip {n}: {frames} frames")))?,
        )?;
        let boxes = r.f32s(boxes_len)?;
        let hips = MotionFeatures {
            origin: Origin::Hips,
            data,
        };
        let features = if same_layout {
            ClipFeatures::with_hip_boxes(name, clip_fps, hips, boxes)
        } else {
            ClipFeatures::new(name, clip_fps, hips)
        };
        index.add_features(features);
        clips.push(StoredClip { id, key });
    }
    for _ in 0..skipped_count {
        let name = r.string()?;
        let reason = r.string()?;
        index.skipped.push(SkippedClip { name, reason });
    }
    if r.at != bytes.len() {
        return Err(corrupt(format!(
            "{} bytes follow the last clip",
            bytes.len() - r.at
        )));
    }
    Ok(StoredIndex { index, clips })
}

/// A bounds-checked little-endian cursor.
struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize) -> Result<&'a [u8], StoredIndexError> {
        let end = self.at.checked_add(n).filter(|&e| e <= self.bytes.len());
        let end = end.ok_or(StoredIndexError::Truncated {
            at: self.at,
            needed: n,
            len: self.bytes.len(),
        })?;
        let s = &self.bytes[self.at..end];
        self.at = end;
        Ok(s)
    }
    fn u32(&mut self) -> Result<u32, StoredIndexError> {
        Ok(u32::from_le_bytes(
            self.take(4)?.try_into().expect("4 bytes"),
        ))
    }
    fn f32(&mut self) -> Result<f32, StoredIndexError> {
        Ok(f32::from_le_bytes(
            self.take(4)?.try_into().expect("4 bytes"),
        ))
    }
    fn string(&mut self) -> Result<String, StoredIndexError> {
        let n = self.u32()? as usize;
        let at = self.at;
        String::from_utf8(self.take(n)?.to_vec()).map_err(|_| StoredIndexError::Corrupt {
            what: format!("the text at offset {at} is not UTF-8"),
        })
    }
    fn f32s(&mut self, n: usize) -> Result<Vec<f32>, StoredIndexError> {
        let b = self.take(n.checked_mul(4).ok_or(StoredIndexError::Truncated {
            at: self.at,
            needed: usize::MAX,
            len: self.bytes.len(),
        })?)?;
        Ok(b.chunks_exact(4)
            .map(|c| f32::from_le_bytes(c.try_into().expect("4 bytes")))
            .collect())
    }
}

/// Where an index handed out by [`open_or_build`] came from.
#[derive(Clone, Debug, PartialEq)]
pub enum Opened {
    /// Read from the stored bytes.
    Stored,
    /// Built again, and why: nothing stored, a stored index of another library (stale), or
    /// stored bytes that could not be read.
    Rebuilt { why: String },
}

/// The stored index when it is the library's (its [`StoredIndex::library_key`] equals
/// `expected_key`) and readable; otherwise `build()`'s, with the reason.
pub fn open_or_build<E>(
    stored: Option<&[u8]>,
    expected_key: u128,
    build: impl FnOnce() -> Result<StoredIndex, E>,
) -> Result<(StoredIndex, Opened), E> {
    let why = match stored.map(decode_index) {
        None => "no index stored".to_string(),
        Some(Err(e)) => e.to_string(),
        Some(Ok(s)) => {
            let key = s.library_key();
            if key == expected_key {
                return Ok((s, Opened::Stored));
            }
            format!("stale: the stored index is of library {key:032x}, this library is {expected_key:032x}")
        }
    };
    Ok((build()?, Opened::Rebuilt { why }))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::canon::builtin::demo_clip;
    use crate::canon::humanoid::HumanoidMap;

    fn demo_index() -> StoredIndex {
        let clip = demo_clip();
        let map = HumanoidMap::from_skeleton(&clip.skeleton);
        let mut index = FeatureIndex::new();
        index.add_features(ClipFeatures::from_clip("demo", &clip, &map));
        index.skipped.push(SkippedClip {
            name: "fox".into(),
            reason: "not humanoid".into(),
        });
        StoredIndex {
            index,
            clips: vec![StoredClip {
                id: 7,
                key: clip_key("demo", &clip),
            }],
        }
    }

    #[test]
    fn bytes_read_back_exactly() {
        let s = demo_index();
        let bytes = encode_index(&s.index, &s.clips);
        let back = decode_index(&bytes).expect("reads back");
        assert_eq!(back.clips, s.clips);
        assert_eq!(back.index.skipped, s.index.skipped);
        let (a, b) = (&s.index.clips[0], &back.index.clips[0]);
        assert_eq!(a.features(Origin::Hips), b.features(Origin::Hips));
        assert_eq!(a.chunk_boxes(Origin::Hips), b.chunk_boxes(Origin::Hips));
        assert_eq!((a.name.as_str(), a.fps), (b.name.as_str(), b.fps));
        assert_eq!(
            encode_index(&back.index, &back.clips),
            bytes,
            "encoding is deterministic"
        );
    }

    #[test]
    fn every_damage_is_a_typed_error() {
        let bytes = {
            let d = demo_index();
            encode_index(&d.index, &d.clips)
        };
        // Every truncation is an error, never a panic.
        for n in (0..bytes.len()).step_by(97).chain([bytes.len() - 1]) {
            assert!(
                decode_index(&bytes[..n]).is_err(),
                "truncated to {n} bytes was read"
            );
        }
        let mut v = bytes.clone();
        v[8] = 2;
        assert_eq!(
            decode_index(&v).unwrap_err(),
            StoredIndexError::Version {
                found: 2,
                expected: STORED_INDEX_VERSION
            }
        );
        let mut v = bytes.clone();
        v[0] = b'X';
        assert!(matches!(
            decode_index(&v),
            Err(StoredIndexError::NotAnIndex { .. })
        ));
        for at in [HEADER_BYTES + 3, bytes.len() / 2, bytes.len() - 5] {
            let mut v = bytes.clone();
            v[at] ^= 0x10;
            assert!(
                matches!(decode_index(&v), Err(StoredIndexError::Checksum { .. })),
                "a flipped bit at {at} went unnoticed"
            );
        }
    }

    #[test]
    fn keys_follow_content() {
        let clip = demo_clip();
        let mut changed = clip.clone();
        changed.rotations[5] = changed.rotations[5] * glam::Quat::from_rotation_y(1e-3);
        assert_eq!(clip_key("demo", &clip), clip_key("demo", &clip.clone()));
        assert_ne!(clip_key("demo", &clip), clip_key("demo", &changed));
        assert_ne!(clip_key("demo", &clip), clip_key("demo2", &clip));
        let (a, b) = (clip_key("a", &clip), clip_key("b", &clip));
        assert_ne!(
            library_key(60.0, [a, b]),
            library_key(60.0, [b, a]),
            "order is part of the library"
        );
        assert_ne!(library_key(60.0, [a]), library_key(30.0, [a]));
    }
}
