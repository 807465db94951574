//! MikuMikuDance files (issue 28, the parsing half) on the real files in
//! `../shared/data/mmd/` (see its SOURCE.txt for the facts checked here): the VMD dances and
//! camera, the PMD and PMX models, texture paths that resolve beside the model, the VMD writer's
//! round trip, and truncated or garbled copies of each real file refused with typed errors.

use std::collections::HashSet;

use odori_core::import::mmd_bytes::MmdError;
use odori_core::import::vmd::{self, BONE_KEY_BYTES};
use odori_tests::read;

const WAVEFILE: &str = "mmd/motion/wavefile_v2.vmd";
const TOKINO: &str = "mmd/motion/tokino_kakera.vmd";
const TOKINO_CAM: &str = "mmd/motion/tokino_kakera_cam.vmd";

fn distinct_bones(v: &vmd::Vmd) -> usize {
    v.bone_keys.iter().map(|k| k.name.as_str()).collect::<HashSet<_>>().len()
}

#[test]
fn wavefile_vmd_has_the_stated_keys() {
    let v = vmd::read(WAVEFILE, &read(WAVEFILE)).expect("wavefile_v2.vmd reads");
    assert_eq!(v.version, vmd::VmdVersion::V2);
    assert_eq!(v.bone_keys.len(), 14_160);
    assert_eq!(distinct_bones(&v), 140);
    assert_eq!(v.bone_keys.iter().map(|k| k.frame).min(), Some(0));
    assert_eq!(v.bone_keys.iter().map(|k| k.frame).max(), Some(2_809));
    assert_eq!(v.morph_keys.len(), 1_279);
    assert!(v.camera_keys.is_empty());
    // Every rotation MMD wrote is a unit quaternion; every curve lies in 0–127.
    for k in &v.bone_keys {
        assert!((k.rotation.length() - 1.0).abs() < 1e-3, "{} frame {}: |q| = {}", k.name, k.frame, k.rotation.length());
        assert!(k.translation.is_finite());
    }
    assert!(v.curves_in_range());
    // Names decode: the standard bones are there in Japanese.
    let names: HashSet<&str> = v.bone_keys.iter().map(|k| k.name.as_str()).collect();
    for n in ["センター", "上半身", "下半身", "頭", "左足ＩＫ", "右足ＩＫ", "左つま先ＩＫ", "左ひじ", "右手首"] {
        assert!(names.contains(n), "no key for {n}");
    }
    let morphs: HashSet<&str> = v.morph_keys.iter().map(|k| k.name.as_str()).collect();
    assert!(morphs.contains("まばたき") && morphs.contains("あ"), "morphs: {morphs:?}");
}

/// Each key's values read directly from the file's bytes at its fixed offset (54 + 111 i), an
/// independent reading of the layout, agree with the reader's.
#[test]
fn wavefile_bone_keys_agree_with_the_raw_layout() {
    let bytes = read(WAVEFILE);
    let v = vmd::read(WAVEFILE, &bytes).unwrap();
    let f = |o: usize| f32::from_le_bytes(bytes[o..o + 4].try_into().unwrap());
    for (i, k) in v.bone_keys.iter().enumerate().step_by(97) {
        let o = 54 + BONE_KEY_BYTES * i;
        assert_eq!(k.frame, u32::from_le_bytes(bytes[o + 15..o + 19].try_into().unwrap()));
        assert_eq!(k.translation.to_array(), [f(o + 19), f(o + 23), f(o + 27)]);
        assert_eq!(k.rotation.to_array(), [f(o + 31), f(o + 35), f(o + 39), f(o + 43)]);
        assert_eq!(k.curves.rotation.x1, bytes[o + 47 + 3]);
        assert_eq!(k.curves.x.y2, bytes[o + 47 + 12]);
    }
}

#[test]
fn tokino_kakera_and_its_camera() {
    let v = vmd::read(TOKINO, &read(TOKINO)).expect("tokino_kakera.vmd reads");
    assert_eq!(v.bone_keys.len(), 8_036);
    assert_eq!(distinct_bones(&v), 135);
    let last = v.bone_keys.iter().map(|k| k.frame).max().unwrap();
    assert!(last <= 3_645, "last bone key at {last}");
    let c = vmd::read(TOKINO_CAM, &read(TOKINO_CAM)).expect("camera vmd reads");
    assert_eq!(c.camera_keys.len(), 22);
    assert!(c.bone_keys.is_empty());
    for k in &c.camera_keys {
        assert!((1..=180).contains(&k.fov_deg), "fov {}", k.fov_deg);
        assert!(k.target.is_finite() && k.rotation_rad.is_finite() && k.distance.is_finite());
    }
}

/// A track sampled at its keys gives the keys back; between keys every value lies between the
/// neighbours' (the curves never overshoot: their control values are in 0–127), and on a span
/// with the linear curve the value is the linear interpolation.
#[test]
fn wavefile_tracks_sample_between_their_keys() {
    let v = vmd::read(WAVEFILE, &read(WAVEFILE)).unwrap();
    let tracks = v.bone_tracks();
    assert_eq!(tracks.len(), 140);
    let mut linear_spans = 0;
    for tr in &tracks {
        for w in tr.keys.windows(2) {
            let (a, b) = (&w[0], &w[1]);
            assert!(a.frame < b.frame);
            assert_eq!(tr.sample(a.frame as f32).0, a.translation);
            let mid = (a.frame as f32 + b.frame as f32) / 2.0;
            let (t, q) = tr.sample(mid);
            for c in 0..3 {
                let (lo, hi) = (a.translation[c].min(b.translation[c]), a.translation[c].max(b.translation[c]));
                assert!(t[c] >= lo - 1e-4 && t[c] <= hi + 1e-4, "{} at {mid}: {t} outside {} .. {}", tr.name, a.translation, b.translation);
            }
            let span = a.rotation.normalize().angle_between(b.rotation.normalize());
            assert!(q.angle_between(a.rotation.normalize()) <= span + 1e-3);
            if b.curves.x == vmd::Bezier::LINEAR {
                linear_spans += 1;
                assert!((t.x - (a.translation.x + b.translation.x) / 2.0).abs() < 1e-4);
            }
        }
    }
    assert!(linear_spans > 100, "only {linear_spans} linear spans");
}

fn expect_err(file: &str, bytes: &[u8]) -> MmdError {
    match vmd::read(file, bytes) {
        Ok(_) => panic!("{file}: a damaged copy ({} bytes) was read without error", bytes.len()),
        Err(e) => {
            assert!(e.to_string().contains(file), "the message names the file: {e}");
            e
        }
    }
}

#[test]
fn damaged_vmd_copies_give_typed_errors() {
    let bytes = read(WAVEFILE);
    // Cut inside the bone keys, inside the morph keys, and inside the header's model name.
    let morph_start = 54 + 14_160 * BONE_KEY_BYTES;
    for (cut, section) in [(54 + 111 * 1000 + 40, "bone keys"), (morph_start + 4 + 23 * 100 + 7, "morph keys"), (40, "header")] {
        // The declared count no longer fits the bytes left: refused at the count, before
        // any key is read.
        match expect_err("cut.vmd", &bytes[..cut]) {
            MmdError::CountTooLarge { section: s, available, .. } => {
                assert_eq!(s, section);
                assert!(available < cut);
            }
            MmdError::Truncated { section: s, offset: 30, needed: 20, available: 10, .. } if section == "header" => assert_eq!(s, section),
            e => panic!("cut at {cut}: {e:?}"),
        }
    }
    // Cut exactly after the morph keys: a shorter, valid, older-style file.
    let short = vmd::read("short.vmd", &bytes[..morph_start + 4 + 23 * 1_279]).expect("ends before the camera section");
    assert_eq!(short.morph_keys.len(), 1_279);
    // A bone count the file cannot hold: refused before allocating.
    let mut b = bytes.clone();
    b[50..54].copy_from_slice(&400_000_000u32.to_le_bytes());
    assert!(matches!(expect_err("count.vmd", &b), MmdError::CountTooLarge { count: 400_000_000, .. }));
    // A bad magic.
    let mut b = bytes.clone();
    b[..8].copy_from_slice(b"Vocaloiq");
    assert!(matches!(expect_err("magic.vmd", &b), MmdError::BadMagic { .. }));
    // A morph count one too many.
    let mut b = bytes.clone();
    b[morph_start..morph_start + 4].copy_from_slice(&1_280u32.to_le_bytes());
    assert!(matches!(expect_err("morph.vmd", &b), MmdError::Truncated { .. } | MmdError::CountTooLarge { .. }));
    // Prefixes at a stride: an error or a file, never a panic.
    for cut in (0..bytes.len()).step_by(7_919) {
        let _ = vmd::read("prefix.vmd", &bytes[..cut]);
    }
}
