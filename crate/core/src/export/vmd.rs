//! VMD writer: a [`Vmd`] back to MikuMikuDance's motion file ("Vocaloid Motion Data 0002").
//!
//! Writes every section the reader reads (bone keys with their 64-byte interpolation blocks
//! in MMD's layout, morph keys, and camera, light, self-shadow and IK/visibility keys when
//! there are any), values as given, in MMD units (nothing converted), names in Shift-JIS cut
//! byte-wise to their fields as MMD cuts them (see [`mmd_text::encode_sjis_field`]). Reading the
//! written file gives back every key exactly: names, frames, values and curves.
//!
//! The camera, light and self-shadow counts are always written (zero when empty), as MMD does.
//!
//! A name the reader got from a field MMD cut through a two-byte character writes back as the
//! same bytes (see [`mmd_text::CUT_LEAD_BYTE_BASE`]). Refused with a typed [`MmdError`]: a name
//! Shift-JIS cannot hold (emoji, U+FFFD), a value that is not finite, a curve control value
//! above 127, more keys than a u32 counts.

use crate::import::mmd_bytes::MmdError;
use crate::import::mmd_text;
use crate::import::vmd::{Bezier, Vmd, BONE_KEY_BYTES, MAGIC_V2, MORPH_KEY_BYTES, NAME_BYTES};

fn name_field(out: &mut Vec<u8>, file: &str, what: &'static str, name: &str, width: usize) -> Result<(), MmdError> {
    let b = mmd_text::encode_sjis_field(name, width).map_err(|character| MmdError::NotShiftJis {
        file: file.to_string(),
        what,
        name: name.to_string(),
        character,
    })?;
    out.extend_from_slice(&b);
    out.resize(out.len() + (width - b.len()), 0);
    Ok(())
}

fn count(out: &mut Vec<u8>, file: &str, what: &'static str, n: usize) -> Result<(), MmdError> {
    let n32 = u32::try_from(n).map_err(|_| MmdError::TooMany { file: file.to_string(), what, value: n, limit: u64::from(u32::MAX) })?;
    out.extend_from_slice(&n32.to_le_bytes());
    Ok(())
}

fn floats(out: &mut Vec<u8>, values: &[f32]) {
    for v in values {
        out.extend_from_slice(&v.to_le_bytes());
    }
}

fn check_curve(file: &str, key: usize, name: &str, frame: u32, b: &Bezier) -> Result<(), MmdError> {
    for value in [b.x1, b.y1, b.x2, b.y2] {
        if value > 127 {
            return Err(MmdError::BadCurve { file: file.to_string(), key, name: name.to_string(), frame, value });
        }
    }
    Ok(())
}

/// Writes `vmd` as a VMD file. `file` names the output in errors.
pub fn write(file: &str, vmd: &Vmd) -> Result<Vec<u8>, MmdError> {
    let mut out = Vec::with_capacity(54 + vmd.bone_keys.len() * BONE_KEY_BYTES + 4 + vmd.morph_keys.len() * MORPH_KEY_BYTES + 16);
    out.extend_from_slice(MAGIC_V2);
    out.resize(30, 0);
    name_field(&mut out, file, "model name", &vmd.model_name, 20)?;

    count(&mut out, file, "the number of bone keys", vmd.bone_keys.len())?;
    for (i, k) in vmd.bone_keys.iter().enumerate() {
        if !(k.translation.is_finite() && k.rotation.is_finite()) {
            let what = if k.translation.is_finite() { "rotation" } else { "translation" };
            return Err(MmdError::NotFinite { file: file.to_string(), what, key: i, name: k.name.clone(), frame: k.frame });
        }
        for b in [k.curves.x, k.curves.y, k.curves.z, k.curves.rotation] {
            check_curve(file, i, &k.name, k.frame, &b)?;
        }
        name_field(&mut out, file, "bone name", &k.name, NAME_BYTES)?;
        out.extend_from_slice(&k.frame.to_le_bytes());
        floats(&mut out, &k.translation.to_array());
        floats(&mut out, &k.rotation.to_array());
        out.extend_from_slice(&k.curves.to_block());
    }

    count(&mut out, file, "the number of morph keys", vmd.morph_keys.len())?;
    for (i, k) in vmd.morph_keys.iter().enumerate() {
        if !k.weight.is_finite() {
            return Err(MmdError::NotFinite { file: file.to_string(), what: "morph weight", key: i, name: k.name.clone(), frame: k.frame });
        }
        name_field(&mut out, file, "morph name", &k.name, NAME_BYTES)?;
        out.extend_from_slice(&k.frame.to_le_bytes());
        floats(&mut out, &[k.weight]);
    }

    // The camera, light and self-shadow counts are always written, as MMD writes them (three.js's
    // parser reads the camera count unconditionally and fails on a file that ends before it);
    // the IK/visibility section only when it has keys.
    count(&mut out, file, "the number of camera keys", vmd.camera_keys.len())?;
    for (i, k) in vmd.camera_keys.iter().enumerate() {
        if !(k.distance.is_finite() && k.target.is_finite() && k.rotation_rad.is_finite()) {
            return Err(MmdError::NotFinite { file: file.to_string(), what: "camera value", key: i, name: "camera".into(), frame: k.frame });
        }
        out.extend_from_slice(&k.frame.to_le_bytes());
        floats(&mut out, &[k.distance]);
        floats(&mut out, &k.target.to_array());
        floats(&mut out, &k.rotation_rad.to_array());
        let c = &k.curves;
        for b in [c.x, c.y, c.z, c.rotation, c.distance, c.fov] {
            check_curve(file, i, "camera", k.frame, &b)?;
            out.extend_from_slice(&[b.x1, b.x2, b.y1, b.y2]);
        }
        out.extend_from_slice(&k.fov_deg.to_le_bytes());
        out.push(u8::from(k.perspective_off));
    }
    count(&mut out, file, "the number of light keys", vmd.light_keys.len())?;
    for (i, k) in vmd.light_keys.iter().enumerate() {
        if !(k.colour.is_finite() && k.direction.is_finite()) {
            return Err(MmdError::NotFinite { file: file.to_string(), what: "light value", key: i, name: "light".into(), frame: k.frame });
        }
        out.extend_from_slice(&k.frame.to_le_bytes());
        floats(&mut out, &k.colour.to_array());
        floats(&mut out, &k.direction.to_array());
    }
    count(&mut out, file, "the number of self-shadow keys", vmd.self_shadow_keys.len())?;
    for (i, k) in vmd.self_shadow_keys.iter().enumerate() {
        if !k.distance.is_finite() {
            return Err(MmdError::NotFinite { file: file.to_string(), what: "self-shadow distance", key: i, name: "self-shadow".into(), frame: k.frame });
        }
        out.extend_from_slice(&k.frame.to_le_bytes());
        out.push(k.mode);
        floats(&mut out, &[k.distance]);
    }
    if vmd.property_keys.is_empty() {
        return Ok(out);
    }
    count(&mut out, file, "the number of IK keys", vmd.property_keys.len())?;
    for k in &vmd.property_keys {
        out.extend_from_slice(&k.frame.to_le_bytes());
        out.push(u8::from(k.visible));
        count(&mut out, file, "the number of IK switches in a key", k.ik.len())?;
        for (name, on) in &k.ik {
            name_field(&mut out, file, "IK bone name", name, 20)?;
            out.push(u8::from(*on));
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use glam::{Quat, Vec3};

    use super::*;
    use crate::import::vmd::{self, BoneCurves, BoneKey, CameraKey, LightKey, MorphKey, PropertyKey, SelfShadowKey, VmdVersion};

    fn sample() -> Vmd {
        let ease = Bezier { x1: 127, y1: 0, x2: 0, y2: 127 };
        Vmd {
            version: VmdVersion::V2,
            model_name: "初音ミク".into(),
            bone_keys: vec![
                BoneKey { name: "センター".into(), frame: 0, translation: Vec3::new(0.5, -1.25, 3.0), rotation: Quat::IDENTITY, curves: BoneCurves::default() },
                BoneKey {
                    name: "左足ＩＫ".into(),
                    frame: 30,
                    translation: Vec3::new(1.0, 2.0, -3.0),
                    rotation: Quat::from_rotation_y(0.3),
                    curves: BoneCurves { x: ease, y: Bezier::LINEAR, z: Bezier { x1: 1, y1: 2, x2: 3, y2: 4 }, rotation: ease },
                },
            ],
            morph_keys: vec![MorphKey { name: "まばたき".into(), frame: 12, weight: 0.75 }],
            camera_keys: vec![],
            light_keys: vec![],
            self_shadow_keys: vec![],
            property_keys: vec![],
        }
    }

    #[test]
    fn write_then_read_gives_every_key_back() {
        let v = sample();
        let bytes = write("t.vmd", &v).unwrap();
        // Header, bone keys, morph keys, then the camera, light and self-shadow counts (0), as
        // MMD writes them (three.js's parser needs the camera count).
        assert_eq!(bytes.len(), 54 + 2 * BONE_KEY_BYTES + 4 + MORPH_KEY_BYTES + 3 * 4);
        assert_eq!(&bytes[bytes.len() - 12..], &[0u8; 12]);
        assert_eq!(vmd::read("t.vmd", &bytes).unwrap(), v);
    }

    #[test]
    fn every_section_round_trips() {
        let mut v = sample();
        v.camera_keys.push(CameraKey {
            frame: 3,
            distance: -45.0,
            target: Vec3::new(0.0, 10.0, 0.0),
            rotation_rad: Vec3::new(0.1, 0.2, 0.0),
            curves: Default::default(),
            fov_deg: 30,
            perspective_off: false,
        });
        v.property_keys.push(PropertyKey { frame: 0, visible: true, ik: vec![("左足ＩＫ".into(), false), ("右足ＩＫ".into(), true)] });
        assert_eq!(vmd::read("t.vmd", &write("t.vmd", &v).unwrap()).unwrap(), v);
        v.light_keys.push(LightKey { frame: 1, colour: Vec3::splat(0.6), direction: Vec3::new(-0.5, -1.0, 0.5) });
        v.self_shadow_keys.push(SelfShadowKey { frame: 2, mode: 1, distance: 0.01 });
        assert_eq!(vmd::read("t.vmd", &write("t.vmd", &v).unwrap()).unwrap(), v);
    }

    #[test]
    fn bad_keys_are_refused_with_what_is_wrong() {
        let mut v = sample();
        v.bone_keys[1].name = "足😀".into();
        assert!(matches!(write("t.vmd", &v), Err(MmdError::NotShiftJis { character: '😀', .. })));
        let mut v = sample();
        v.bone_keys[0].translation.x = f32::NAN;
        assert!(matches!(write("t.vmd", &v), Err(MmdError::NotFinite { key: 0, what: "translation", .. })));
        let mut v = sample();
        v.bone_keys[1].curves.rotation.y2 = 200;
        assert!(matches!(write("t.vmd", &v), Err(MmdError::BadCurve { key: 1, value: 200, .. })));
    }
}
