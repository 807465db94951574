//! VMD (Vocaloid Motion Data) reader: MikuMikuDance's motion file.
//!
//! A VMD holds keys, not frames: bone keys (a local translation and rotation relative to the
//! model's rest pose, with a cubic-Bézier easing per channel), morph keys, camera keys, and
//! the later optional sections (light, self-shadow, IK on/off and visibility). Frames are at
//! 30 per second; values are in MMD units as in the file (1 unit = 8 cm by MMD's convention;
//! left-handed, Y up); nothing is converted here, so what is read writes back bit-for-bit
//! ([`crate::export::vmd`]). Names are Shift-JIS (see [`super::mmd_text`]).
//!
//! This reader gives keys only; [`crate::mmd::BoneSampler`] evaluates a bone between its
//! keys (three.js-compatible Bézier easing), so there is one sampler in the engine.

use glam::{Quat, Vec3};

use super::mmd_bytes::{printable_start, CountWidth, MmdError, Reader};

/// Frames per second of every VMD.
pub const VMD_FPS: f32 = 30.0;
/// Width in bytes of a bone or morph name field.
pub const NAME_BYTES: usize = 15;
/// Bytes of one bone key, one morph key, one camera key, one light key, one self-shadow key.
pub const BONE_KEY_BYTES: usize = 111;
pub const MORPH_KEY_BYTES: usize = 23;
pub const CAMERA_KEY_BYTES: usize = 61;
pub const LIGHT_KEY_BYTES: usize = 28;
pub const SELF_SHADOW_KEY_BYTES: usize = 9;

/// The two VMD headers: "Vocaloid Motion Data file" (old, 10-byte model name) and
/// "Vocaloid Motion Data 0002" (20-byte model name).
pub const MAGIC_V1: &[u8] = b"Vocaloid Motion Data file";
pub const MAGIC_V2: &[u8] = b"Vocaloid Motion Data 0002";

/// One cubic-Bézier easing curve from (0, 0) to (127, 127) through the control points
/// (x1, y1) and (x2, y2), each 0–127 as stored. The default (20, 20, 107, 107) is linear.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct Bezier {
    pub x1: u8,
    pub y1: u8,
    pub x2: u8,
    pub y2: u8,
}

impl Bezier {
    /// MMD's default curve, a straight line: (20, 20) and (107, 107).
    pub const LINEAR: Bezier = Bezier { x1: 20, y1: 20, x2: 107, y2: 107 };
}

impl Default for Bezier {
    fn default() -> Self {
        Self::LINEAR
    }
}

/// The four curves of a bone key: translation X, Y, Z and rotation.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
pub struct BoneCurves {
    pub x: Bezier,
    pub y: Bezier,
    pub z: Bezier,
    pub rotation: Bezier,
}

impl BoneCurves {
    /// Reads the 64-byte block: its first 16 bytes hold, for channels X, Y, Z, R in turn,
    /// all x1, then all y1, then all x2, then all y2; the other 48 bytes repeat them shifted
    /// (MMD's layout) and are not needed.
    pub fn from_block(block: &[u8; 64]) -> Self {
        let ch = |c: usize| Bezier { x1: block[c], y1: block[4 + c], x2: block[8 + c], y2: block[12 + c] };
        Self { x: ch(0), y: ch(1), z: ch(2), rotation: ch(3) }
    }

    /// The 64-byte block as MMD writes it: row k (k = 0–3) is the 16-byte parameter row shifted
    /// left by k bytes, followed by 01 and zeros.
    pub fn to_block(&self) -> [u8; 64] {
        let mut row = [0u8; 16];
        for (c, b) in [self.x, self.y, self.z, self.rotation].iter().enumerate() {
            row[c] = b.x1;
            row[4 + c] = b.y1;
            row[8 + c] = b.x2;
            row[12 + c] = b.y2;
        }
        let mut out = [0u8; 64];
        for k in 0..4 {
            for j in 0..16 {
                let i = j + k;
                out[16 * k + j] = match i {
                    0..=15 => row[i],
                    16 => 1,
                    _ => 0,
                };
            }
        }
        out
    }

    fn all(&self) -> [Bezier; 4] {
        [self.x, self.y, self.z, self.rotation]
    }
}

/// One bone key: the bone's local translation (MMD units, relative to its rest position) and
/// rotation (relative to its rest orientation) at `frame`.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct BoneKey {
    pub name: String,
    pub frame: u32,
    pub translation: Vec3,
    /// As stored (x, y, z, w); MMD writes unit quaternions, a reader should not count on it.
    pub rotation: Quat,
    /// The easing of the span that ends at this key.
    pub curves: BoneCurves,
}

/// One morph (facial expression) key: the morph's weight, usually 0–1.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct MorphKey {
    pub name: String,
    pub frame: u32,
    pub weight: f32,
}

/// Six camera curves, in file order: X, Y, Z (of the look-at point), rotation, distance, field
/// of view. Stored per channel as x1, x2, y1, y2.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
pub struct CameraCurves {
    pub x: Bezier,
    pub y: Bezier,
    pub z: Bezier,
    pub rotation: Bezier,
    pub distance: Bezier,
    pub fov: Bezier,
}

/// One camera key. MMD's camera orbits a look-at point: `distance` (negative: in front of it),
/// Euler `rotation_rad` (x, y, z), `fov_deg`.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CameraKey {
    pub frame: u32,
    pub distance: f32,
    pub target: Vec3,
    pub rotation_rad: Vec3,
    pub curves: CameraCurves,
    pub fov_deg: u32,
    /// The file's perspective byte: 0 means perspective on, 1 orthographic.
    pub perspective_off: bool,
}

/// One light key: colour (0–1 each) and direction.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct LightKey {
    pub frame: u32,
    pub colour: Vec3,
    pub direction: Vec3,
}

/// One self-shadow key: mode (0 off, 1 mode 1, 2 mode 2) and distance as MMD stores it.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SelfShadowKey {
    pub frame: u32,
    pub mode: u8,
    pub distance: f32,
}

/// One "property" key: the model's visibility and each named IK chain switched on or off.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PropertyKey {
    pub frame: u32,
    pub visible: bool,
    /// (IK bone name, enabled).
    pub ik: Vec<(String, bool)>,
}

/// Which header the file has.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum VmdVersion {
    /// "Vocaloid Motion Data file": model name in 10 bytes.
    V1,
    /// "Vocaloid Motion Data 0002": model name in 20 bytes.
    V2,
}

/// Everything a VMD file holds, keys in file order (not sorted).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Vmd {
    pub version: VmdVersion,
    /// The model the motion was made for (a camera/light VMD names "カメラ・照明").
    pub model_name: String,
    pub bone_keys: Vec<BoneKey>,
    pub morph_keys: Vec<MorphKey>,
    pub camera_keys: Vec<CameraKey>,
    pub light_keys: Vec<LightKey>,
    pub self_shadow_keys: Vec<SelfShadowKey>,
    pub property_keys: Vec<PropertyKey>,
}

/// Reads a VMD file. The sections after the bone keys are optional (older files end early):
/// a file that ends exactly before a section's count simply lacks it; one that ends inside a
/// section is refused as truncated.
pub fn read(file: &str, bytes: &[u8]) -> Result<Vmd, MmdError> {
    let mut r = Reader::new(file, bytes);
    let magic = r.bytes(30).map_err(|_| bad_magic(file, bytes))?;
    let (version, name_bytes) = if magic.starts_with(MAGIC_V2) {
        (VmdVersion::V2, 20)
    } else if magic.starts_with(MAGIC_V1) {
        (VmdVersion::V1, 10)
    } else {
        return Err(bad_magic(file, bytes));
    };
    let model_name = r.sjis(name_bytes)?;

    r.section("bone keys");
    let n = r.count(CountWidth::U32, BONE_KEY_BYTES)?;
    let mut bone_keys = Vec::with_capacity(n);
    for _ in 0..n {
        let name = r.sjis(NAME_BYTES)?;
        let frame = r.u32()?;
        let translation = r.vec3()?;
        let rotation = r.quat()?;
        let mut block = [0u8; 64];
        block.copy_from_slice(r.bytes(64)?);
        bone_keys.push(BoneKey { name, frame, translation, rotation, curves: BoneCurves::from_block(&block) });
    }

    let mut vmd = Vmd {
        version,
        model_name,
        bone_keys,
        morph_keys: Vec::new(),
        camera_keys: Vec::new(),
        light_keys: Vec::new(),
        self_shadow_keys: Vec::new(),
        property_keys: Vec::new(),
    };

    r.section("morph keys");
    if r.at_end() {
        return Ok(vmd);
    }
    let n = r.count(CountWidth::U32, MORPH_KEY_BYTES)?;
    vmd.morph_keys.reserve_exact(n);
    for _ in 0..n {
        vmd.morph_keys.push(MorphKey { name: r.sjis(NAME_BYTES)?, frame: r.u32()?, weight: r.f32()? });
    }

    r.section("camera keys");
    if r.at_end() {
        return Ok(vmd);
    }
    let n = r.count(CountWidth::U32, CAMERA_KEY_BYTES)?;
    vmd.camera_keys.reserve_exact(n);
    for _ in 0..n {
        let frame = r.u32()?;
        let distance = r.f32()?;
        let target = r.vec3()?;
        let rotation_rad = r.vec3()?;
        let b = r.bytes(24)?;
        let ch = |c: usize| Bezier { x1: b[4 * c], x2: b[4 * c + 1], y1: b[4 * c + 2], y2: b[4 * c + 3] };
        let curves = CameraCurves { x: ch(0), y: ch(1), z: ch(2), rotation: ch(3), distance: ch(4), fov: ch(5) };
        let fov_deg = r.u32()?;
        let perspective_off = r.u8()? != 0;
        vmd.camera_keys.push(CameraKey { frame, distance, target, rotation_rad, curves, fov_deg, perspective_off });
    }

    r.section("light keys");
    if r.at_end() {
        return Ok(vmd);
    }
    let n = r.count(CountWidth::U32, LIGHT_KEY_BYTES)?;
    vmd.light_keys.reserve_exact(n);
    for _ in 0..n {
        vmd.light_keys.push(LightKey { frame: r.u32()?, colour: r.vec3()?, direction: r.vec3()? });
    }

    r.section("self-shadow keys");
    if r.at_end() {
        return Ok(vmd);
    }
    let n = r.count(CountWidth::U32, SELF_SHADOW_KEY_BYTES)?;
    vmd.self_shadow_keys.reserve_exact(n);
    for _ in 0..n {
        vmd.self_shadow_keys.push(SelfShadowKey { frame: r.u32()?, mode: r.u8()?, distance: r.f32()? });
    }

    r.section("IK and visibility keys");
    if r.at_end() {
        return Ok(vmd);
    }
    // frame u32, visible u8, IK count u32: 9 bytes at least.
    let n = r.count(CountWidth::U32, 9)?;
    vmd.property_keys.reserve_exact(n);
    for _ in 0..n {
        let frame = r.u32()?;
        let visible = r.u8()? != 0;
        let m = r.count(CountWidth::U32, 21)?;
        let mut ik = Vec::with_capacity(m);
        for _ in 0..m {
            ik.push((r.sjis(20)?, r.u8()? != 0));
        }
        vmd.property_keys.push(PropertyKey { frame, visible, ik });
    }
    // Bytes after the last known section are ignored (some tools append their own data).
    Ok(vmd)
}

fn bad_magic(file: &str, bytes: &[u8]) -> MmdError {
    MmdError::BadMagic { file: file.to_string(), expected: "VMD (Vocaloid Motion Data)", found: printable_start(bytes, 30) }
}

/// One bone's keys, sorted by frame, one key per frame (where a file keys a frame twice, the
/// later key in the file wins, as in MMD).
#[derive(Clone, Debug, PartialEq)]
pub struct BoneTrack {
    pub name: String,
    pub keys: Vec<BoneKey>,
}

impl Vmd {
    /// The bone keys grouped per bone, in order of each bone's first key, each sorted by frame.
    pub fn bone_tracks(&self) -> Vec<BoneTrack> {
        let mut index: std::collections::HashMap<&str, usize> = std::collections::HashMap::new();
        let mut tracks: Vec<BoneTrack> = Vec::new();
        for k in &self.bone_keys {
            let i = *index.entry(k.name.as_str()).or_insert_with(|| {
                tracks.push(BoneTrack { name: k.name.clone(), keys: Vec::new() });
                tracks.len() - 1
            });
            tracks[i].keys.push(k.clone());
        }
        for t in &mut tracks {
            // Stable sort, then keep the last of each run of equal frames.
            t.keys.sort_by_key(|k| k.frame);
            let mut out: Vec<BoneKey> = Vec::with_capacity(t.keys.len());
            for k in t.keys.drain(..) {
                match out.last_mut() {
                    Some(prev) if prev.frame == k.frame => *prev = k,
                    _ => out.push(k),
                }
            }
            t.keys = out;
        }
        tracks
    }

    /// The last keyed frame of any bone or morph key (0 for a motion without keys).
    pub fn last_frame(&self) -> u32 {
        let b = self.bone_keys.iter().map(|k| k.frame).max().unwrap_or(0);
        let m = self.morph_keys.iter().map(|k| k.frame).max().unwrap_or(0);
        b.max(m)
    }

    /// Every curve control value is within 0–127 (what MMD writes; other tools sometimes write
    /// more, which the sampler tolerates).
    pub fn curves_in_range(&self) -> bool {
        self.bone_keys.iter().all(|k| k.curves.all().iter().all(|b| b.x1 <= 127 && b.y1 <= 127 && b.x2 <= 127 && b.y2 <= 127))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn curve_block_round_trips_and_reads_row_zero() {
        let c = BoneCurves {
            x: Bezier { x1: 1, y1: 2, x2: 3, y2: 4 },
            y: Bezier { x1: 5, y1: 6, x2: 7, y2: 8 },
            z: Bezier { x1: 9, y1: 10, x2: 11, y2: 12 },
            rotation: Bezier { x1: 13, y1: 14, x2: 15, y2: 16 },
        };
        let b = c.to_block();
        assert_eq!(&b[..16], &[1, 5, 9, 13, 2, 6, 10, 14, 3, 7, 11, 15, 4, 8, 12, 16]);
        assert_eq!(&b[16..32], &[5, 9, 13, 2, 6, 10, 14, 3, 7, 11, 15, 4, 8, 12, 16, 1]);
        assert_eq!(&b[60..], &[16, 1, 0, 0]);
        assert_eq!(BoneCurves::from_block(&b), c);
    }

    fn key(frame: u32, t: Vec3, q: Quat, curves: BoneCurves) -> BoneKey {
        BoneKey { name: "センター".into(), frame, translation: t, rotation: q, curves }
    }

    #[test]
    fn duplicate_frames_keep_the_later_key() {
        let mut v = Vmd {
            version: VmdVersion::V2,
            model_name: String::new(),
            bone_keys: vec![],
            morph_keys: vec![],
            camera_keys: vec![],
            light_keys: vec![],
            self_shadow_keys: vec![],
            property_keys: vec![],
        };
        v.bone_keys.push(key(5, Vec3::X, Quat::IDENTITY, BoneCurves::default()));
        v.bone_keys.push(key(0, Vec3::ZERO, Quat::IDENTITY, BoneCurves::default()));
        v.bone_keys.push(key(5, Vec3::Y, Quat::IDENTITY, BoneCurves::default()));
        let tr = v.bone_tracks();
        assert_eq!(tr.len(), 1);
        assert_eq!(tr[0].keys.iter().map(|k| k.frame).collect::<Vec<_>>(), vec![0, 5]);
        assert_eq!(tr[0].keys[1].translation, Vec3::Y);
    }

    #[test]
    fn short_and_wrong_headers_are_typed_errors() {
        assert!(matches!(read("a.vmd", b""), Err(MmdError::BadMagic { .. })));
        assert!(matches!(read("a.vmd", b"Vocaloid Motion Data 0002"), Err(MmdError::BadMagic { .. })));
        let mut b = MAGIC_V2.to_vec();
        b.resize(50, 0);
        b.extend_from_slice(&u32::MAX.to_le_bytes());
        match read("a.vmd", &b) {
            Err(MmdError::CountTooLarge { section, count, .. }) => {
                assert_eq!(section, "bone keys");
                assert_eq!(count, i64::from(u32::MAX));
            }
            other => panic!("{other:?}"),
        }
        // No bone count at all: truncated in the bone keys.
        let b = &b[..50];
        assert!(matches!(read("a.vmd", b), Err(MmdError::Truncated { offset: 50, .. })));
    }
}
