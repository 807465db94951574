//! MMD files brought in as a set (issue 28 item 2) and dances written back as VMD (item 3, check
//! 4a), on the real files in ../shared/data/mmd: a model folder with its textures, a zip of it,
//! the WAVEFILE dance posed on the model its header names, the camera VMD as a camera track, and
//! the bad cases (truncated VMD, a VMD whose bones match no model, a model missing textures),
//! each a problem naming the file with a typed kind while the rest of the set still imports.

use std::io::Write;

use glam::Quat;
use odori_core::import::vmd;
use odori_core::mmd::export::{clip_on_rig, clip_to_vmd, EXPORT_BONES, IK_BONES};
use odori_core::mmd::files::{import_files, pose_vmd, MmdFilesOptions, STANDARD_RIG};
use odori_core::mmd::{standard_rig, MmdRig};
use odori_tests::{data_dir, read};

const MIKU_DIR: &str = "mmd/miku_v2";
const WAVEFILE: &str = "mmd/motion/wavefile_v2.vmd";

/// Every file of a data folder, named `folder/file` as a dropped folder gives them.
fn folder_files(rel: &str) -> Vec<(String, Vec<u8>)> {
    let dir = data_dir().join(rel);
    let mut out: Vec<(String, Vec<u8>)> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e} (the MMD test data is missing)", dir.display()))
        .filter_map(|e| e.ok())
        .filter(|e| e.path().is_file())
        .map(|e| {
            let name = e.file_name().to_string_lossy().to_string();
            (format!("{}/{name}", rel.rsplit('/').next().unwrap_or(rel)), std::fs::read(e.path()).expect("read"))
        })
        .collect();
    out.sort();
    out
}

fn one(rel: &str) -> (String, Vec<u8>) {
    (rel.rsplit('/').next().unwrap_or(rel).to_string(), read(rel))
}

#[test]
fn a_model_folder_and_its_dance_import_together() {
    let mut files = folder_files(MIKU_DIR);
    files.push(one(WAVEFILE));
    files.push(one("mmd/motion/tokino_kakera_cam.vmd"));
    let r = import_files(&files, &[], &MmdFilesOptions::default());
    assert!(r.problems.is_empty(), "{:?}", r.problems);
    assert_eq!(r.models.len(), 1);
    let m = &r.models[0];
    assert_eq!(m.model.bones.len(), 140);
    assert!(m.missing_textures.is_empty(), "{:?}", m.missing_textures);
    assert!(m.textures.iter().any(|(t, _, b)| t.eq_ignore_ascii_case("eyeM2.bmp") && b.starts_with(b"BM")), "{:?}", m.textures.iter().map(|t| &t.0).collect::<Vec<_>>());
    assert_eq!(r.motions.len(), 1);
    let w = &r.motions[0];
    assert_eq!(w.rig, m.model.name, "WAVEFILE's header names miku_v2");
    assert!(w.unmatched_bones.is_empty(), "{:?}", w.unmatched_bones);
    assert_eq!(w.clip.frame_count(), 2810);
    assert!(w.morph_keys > 1000 && r.notices.iter().any(|n| n.contains("morph")), "{:?}", r.notices);
    let status = odori_core::HumanoidMap::from_skeleton(&w.clip.skeleton).status(&w.clip.skeleton, Some(&w.clip));
    assert!(status.is_humanoid(), "{status}");
    assert_eq!(r.cameras.len(), 1);
    let cam = &r.cameras[0];
    assert_eq!(cam.keys.len(), 22);
    assert!(cam.keys.windows(2).all(|k| k[0].time_secs <= k[1].time_secs));
    println!("miku folder + WAVEFILE + camera: {} textures, clip {} frames, {} notices", m.textures.len(), w.clip.frame_count(), r.notices.len());
}

#[test]
fn a_zip_with_backslashes_and_other_case_imports_like_the_folder() {
    let files = folder_files(MIKU_DIR);
    let mut zip_bytes = Vec::new();
    {
        let mut z = zip::ZipWriter::new(std::io::Cursor::new(&mut zip_bytes));
        let opts = zip::write::SimpleFileOptions::default().compression_method(zip::CompressionMethod::Deflated);
        for (name, bytes) in &files {
            // Upper-case texture names under a Windows-style folder.
            let base = name.rsplit('/').next().unwrap_or(name);
            let entry = if base.ends_with(".pmd") { format!("Miku Folder/{base}") } else { format!("Miku Folder/{}", base.to_uppercase()) };
            z.start_file(entry, opts).expect("zip entry");
            z.write_all(bytes).expect("zip write");
        }
        z.finish().expect("zip finish");
    }
    let r = import_files(&[("miku.zip".into(), zip_bytes), one(WAVEFILE)], &[], &MmdFilesOptions::default());
    assert!(r.problems.is_empty(), "{:?}", r.problems);
    assert_eq!(r.models.len(), 1);
    assert!(r.models[0].file.starts_with("miku.zip/"));
    assert!(r.models[0].missing_textures.is_empty());
    assert_eq!(r.motions[0].rig, r.models[0].model.name);
}

#[test]
fn a_dance_alone_plays_on_the_standard_skeleton_or_on_a_library_model() {
    let r = import_files(&[one(WAVEFILE)], &[], &MmdFilesOptions::default());
    assert_eq!(r.motions[0].rig, STANDARD_RIG);
    assert!(r.notices.iter().any(|n| n.contains(STANDARD_RIG)), "{:?}", r.notices);
    // The model already in the library is found by the header's name.
    let miku = odori_core::import::mmd_model::read_model("miku_v2.pmd", &read("mmd/miku_v2/miku_v2.pmd")).unwrap();
    let r = import_files(&[one(WAVEFILE)], &[&miku], &MmdFilesOptions::default());
    assert_eq!(r.motions[0].rig, miku.name);
    // The dialog's choice wins over the header.
    let r = import_files(&[one(WAVEFILE)], &[&miku], &MmdFilesOptions { model: Some(STANDARD_RIG.into()), ..Default::default() });
    assert_eq!(r.motions[0].rig, STANDARD_RIG);
    // The song offset: the clip starts at motion frame 160.
    let r = import_files(&[one(WAVEFILE)], &[&miku], &MmdFilesOptions { song_offset_frames: Some(160), ..Default::default() });
    assert_eq!(r.motions[0].clip.frame_count(), 2810 - 160);
}

#[test]
fn bad_files_are_named_problems_and_the_rest_still_imports() {
    let mut files = folder_files("mmd/low_poly");
    // A model missing its textures: drop every TGA/PNG.
    files.retain(|(n, _)| !(n.ends_with(".tga") || n.ends_with(".png")));
    let wave = read(WAVEFILE);
    files.push(("cut.vmd".into(), wave[..wave.len() / 3].to_vec()));
    // A VMD whose bones match no model: WAVEFILE's keys renamed.
    let mut v = vmd::read(WAVEFILE, &wave).unwrap();
    for k in &mut v.bone_keys {
        k.name = format!("x{}", k.frame % 7);
    }
    files.push(("nobones.vmd".into(), odori_core::export::vmd::write("nobones.vmd", &v).unwrap()));
    files.push(one(WAVEFILE));
    let r = import_files(&files, &[], &MmdFilesOptions::default());
    let kinds: Vec<(&str, &str)> = r.problems.iter().map(|p| (p.file.as_str(), p.kind)).collect();
    println!("{kinds:?}");
    // Cut inside its key list: the reader refuses the count the bytes left cannot hold.
    assert!(kinds.contains(&("cut.vmd", "mmd-count-too-large")), "{kinds:?}");
    assert!(r.problems.iter().any(|p| p.file == "cut.vmd" && p.message.contains("bytes are left")), "{:?}", r.problems);
    assert!(kinds.contains(&("nobones.vmd", "mmd-no-matching-bones")), "{kinds:?}");
    assert!(kinds.contains(&("low_poly/miku.pmd", "mmd-missing-textures")), "{kinds:?}");
    let miss = r.problems.iter().find(|p| p.file == "low_poly/miku.pmd").unwrap();
    assert!(miss.message.contains("ro_hatune01"), "{}", miss.message);
    // Nothing else lost: both models (kept despite missing textures) and WAVEFILE.
    assert_eq!(r.models.len(), 2);
    assert_eq!(r.motions.len(), 1);
    assert_eq!(r.motions[0].file, "wavefile_v2.vmd");
}

fn miku_rig() -> (MmdRig, odori_core::import::mmd_model::MmdModel) {
    let m = odori_core::import::mmd_model::read_model("miku_v2.pmd", &read("mmd/miku_v2/miku_v2.pmd")).unwrap();
    (MmdRig::from_model(&m).unwrap(), m)
}

/// The largest component difference of two rotations (q and −q are one rotation).
fn qdist(a: Quat, b: Quat) -> f32 {
    let (a, b) = (a.normalize(), b.normalize());
    let b = if a.dot(b) < 0.0 { -b } else { b };
    (glam::Vec4::from(a) - glam::Vec4::from(b)).abs().max_element()
}

/// Check 4a: WAVEFILE imported on miku, exported as VMD on miku, imported again: every key the
/// export writes for the item-3 bones reads back as the first import posed it, within 1e-4 (rotation
/// as the largest quaternion component difference, position in units), and the original file's keys of the bones that no IK
/// drives are kept at their frames.
#[test]
fn an_imported_dance_exported_and_imported_again_keeps_its_keys() {
    let (rig, model) = miku_rig();
    let wave = vmd::read(WAVEFILE, &read(WAVEFILE)).unwrap();
    let first = pose_vmd("wavefile_v2.vmd", wave.clone(), &[&model], &MmdFilesOptions::default()).unwrap();
    // The writer's exactness on a key per frame (the export before key reduction).
    let t0 = std::time::Instant::now();
    let out = odori_core::mmd::export::clip_to_vmd_every_frame(&first.clip, &rig, &model.name).unwrap();
    let bytes = odori_core::export::vmd::write("out.vmd", &out).unwrap();
    println!("export, a key per frame: {} keys, {} bytes, {:.0} ms", out.bone_keys.len(), bytes.len(), t0.elapsed().as_secs_f64() * 1e3);
    let back = vmd::read("out.vmd", &bytes).unwrap();
    assert_eq!(back.model_name, model.name);
    let second = pose_vmd("out.vmd", back.clone(), &[&model], &MmdFilesOptions::default()).unwrap();
    assert_eq!(second.clip.frame_count(), first.clip.frame_count());
    // Keyed bones: the item-3 ones the model has (miku has no 全ての親 / グルーブ / 上半身2), and the IK ones.
    let names: std::collections::BTreeSet<&str> = back.bone_keys.iter().map(|k| k.name.as_str()).collect();
    for b in EXPORT_BONES.iter().chain(IK_BONES) {
        assert_eq!(names.contains(b), rig.find(b).is_some(), "{b}");
    }
    // Posed bone by bone, frame by frame, the two imports agree.
    let sk = &first.clip.skeleton;
    let mut worst_q = 0.0f32;
    let mut worst_t = 0.0f32;
    let mut compared = 0;
    for f in 0..first.clip.frame_count() {
        let (wa, wb) = (first.clip.world_positions(f), second.clip.world_positions(f));
        for (j, joint) in sk.joints.iter().enumerate() {
            if !EXPORT_BONES.contains(&joint.name.as_str()) {
                continue;
            }
            let (qa, qb) = (first.clip.frame_rotations(f)[j], second.clip.frame_rotations(f)[j]);
            let (dq, dt) = (qdist(qa, qb), (wa[j] - wb[j]).length() / odori_core::mmd::METRES_PER_MMD_UNIT);
            worst_q = worst_q.max(dq);
            worst_t = worst_t.max(dt);
            compared += 1;
        }
    }
    println!("re-import: {compared} bone-frames, worst quaternion component {worst_q:.2e}, worst position {worst_t:.2e} units");
    assert!(worst_q < 1e-4 && worst_t < 1e-4, "rotation {worst_q}, position {worst_t}");
    // The export as it is (keys reduced), keeping the file's own keys: they come back within
    // 1e-4, and every frame lands within 1 mm of the first import.
    let mut own: std::collections::HashMap<&str, std::collections::HashSet<u32>> = std::collections::HashMap::new();
    for k in &wave.bone_keys {
        own.entry(k.name.as_str()).or_default().insert(k.frame);
    }
    let t0 = std::time::Instant::now();
    let out = odori_core::mmd::export::clip_to_vmd_keeping(&first.clip, &rig, &model.name, &|b, f| own.get(b).is_some_and(|s| s.contains(&f))).unwrap();
    let bytes = odori_core::export::vmd::write("out.vmd", &out).unwrap();
    let back = vmd::read("out.vmd", &bytes).unwrap();
    let reduced = pose_vmd("out.vmd", back.clone(), &[&model], &MmdFilesOptions::default()).unwrap();
    let mut worst_m = 0.0f32;
    for f in 0..first.clip.frame_count() {
        let (wa, wb) = (first.clip.world_positions(f), reduced.clip.world_positions(f));
        for (j, joint) in sk.joints.iter().enumerate() {
            if EXPORT_BONES.contains(&joint.name.as_str()) {
                worst_m = worst_m.max((wa[j] - wb[j]).length());
            }
        }
    }
    println!("export, keys reduced (the file's own kept): {} keys, {} bytes, {:.0} ms; every frame within {:.3} mm of the first import", out.bone_keys.len(), bytes.len(), t0.elapsed().as_secs_f64() * 1e3, worst_m * 1e3);
    assert!(worst_m < 1e-3, "{worst_m} m");
    // The original keys of bones no IK drives come back at their frames.
    let keys_at: std::collections::HashMap<(&str, u32), &vmd::BoneKey> = back.bone_keys.iter().map(|k| ((k.name.as_str(), k.frame), k)).collect();
    let mut kept = 0;
    for k in &wave.bone_keys {
        if !EXPORT_BONES.contains(&k.name.as_str()) || ["左足", "右足", "左ひざ", "右ひざ", "左足首", "右足首"].contains(&k.name.as_str()) {
            continue;
        }
        let Some(e) = keys_at.get(&(k.name.as_str(), k.frame)) else { continue };
        assert!(qdist(e.rotation, k.rotation) < 1e-4, "{} frame {}: {:?} vs {:?}", k.name, k.frame, e.rotation, k.rotation);
        assert!((e.translation - k.translation).length() < 1e-4, "{} frame {}: {} vs {}", k.name, k.frame, e.translation, k.translation);
        kept += 1;
    }
    println!("original keys of non-IK item-3 bones kept: {kept}");
    assert!(kept > 3000, "{kept}");
}

/// A clip from another skeleton (a BVH dance) exported on the standard skeleton and on miku,
/// then imported back with MMD's IK solved: 下半身, 頭, the wrists and ankles land where the
/// engine's own retargeting onto the same rig puts them, within 2 cm per metre of height (the
/// 足ＩＫ / つま先ＩＫ keys reproduce the legs through the IK).
#[test]
fn a_bvh_dance_exported_plays_back_where_the_engine_puts_it() {
    let rel = odori_tests::all_bvh().into_iter().find(|r| r.contains("salsa")).expect("a salsa BVH in ../shared/data");
    let im = odori_core::import::import_bytes(&rel, &read(&rel), &odori_core::ImportOptions { fps_override: odori_tests::fps_override_for(&rel), ..Default::default() }).unwrap();
    let clip = im.clips[0].slice(0, 600.min(im.clips[0].frame_count()), "dance");
    let (miku, model) = miku_rig();
    for (rig, name, models) in [(standard_rig(), String::new(), vec![]), (miku, model.name.clone(), vec![&model])] {
        let engine = clip_on_rig(&clip, &rig).unwrap();
        let out = clip_to_vmd(&clip, &rig, &name).unwrap();
        let bytes = odori_core::export::vmd::write("d.vmd", &out).unwrap();
        let opts = MmdFilesOptions { model: models.is_empty().then(|| STANDARD_RIG.to_string()), ..Default::default() };
        let back = pose_vmd("d.vmd", vmd::read("d.vmd", &bytes).unwrap(), &models, &opts).unwrap();
        assert_eq!(back.clip.frame_count(), engine.frame_count());
        let height_m = rig.bones[rig.find("頭").unwrap()].rest_position.y * odori_core::mmd::METRES_PER_MMD_UNIT;
        let id = |c: &odori_core::Clip, b: &str| c.skeleton.joints.iter().position(|j| j.name == b).unwrap_or_else(|| panic!("no {b}"));
        let bones = ["下半身", "頭", "左手首", "右手首", "左足首", "右足首"];
        let (mut worst, mut sum, mut count) = (0.0f32, 0.0f32, 0);
        for f in 0..back.clip.frame_count() {
            let (p, q) = (back.clip.world_positions(f), engine.world_positions(f));
            for b in bones {
                let d = (p[id(&back.clip, b)] - q[id(&engine, b)]).length();
                worst = worst.max(d);
                sum += d;
                count += 1;
            }
        }
        println!("{rel} on {}: {count} positions, mean {:.2} mm, worst {:.2} mm (tolerance {:.1} mm: 2 cm per metre of {height_m:.2} m)", rig.name, 1e3 * sum / count as f32, 1e3 * worst, 20.0 * height_m);
        assert!(worst < 0.02 * height_m, "{}: worst {worst} m", rig.name);
    }
}

/// Issue 28: face morph keys survive a VMD round trip. WAVEFILE's 1,279 morph keys, set aside at
/// import (with and without the song offset), are written back by the export and read back
/// equal (name, weight; frames on the export's timeline); the re-import sets them aside again.
#[test]
fn face_morph_keys_survive_a_vmd_round_trip() {
    use odori_core::mmd::export::put_morph_keys;
    let (rig, model) = miku_rig();
    let wave = vmd::read(WAVEFILE, &read(WAVEFILE)).unwrap();
    assert!(wave.morph_keys.len() > 1000, "{}", wave.morph_keys.len());
    for offset in [0u32, 160] {
        let opts = MmdFilesOptions { song_offset_frames: (offset > 0).then_some(offset), ..Default::default() };
        let first = pose_vmd("wavefile_v2.vmd", wave.clone(), &[&model], &opts).unwrap();
        assert_eq!(first.morph_keys, wave.morph_keys.len());
        let mut out = clip_to_vmd(&first.clip, &rig, &model.name).unwrap();
        assert!(out.morph_keys.is_empty(), "the clip itself carries bones only");
        put_morph_keys(&mut out, &first.vmd.morph_keys, offset);
        let bytes = odori_core::export::vmd::write("out.vmd", &out).unwrap();
        let back = vmd::read("out.vmd", &bytes).unwrap();
        let want: Vec<(String, u32, f32)> = wave.morph_keys.iter().filter(|k| k.frame >= offset).map(|k| (k.name.clone(), k.frame - offset, k.weight)).collect();
        let got: Vec<(String, u32, f32)> = back.morph_keys.iter().map(|k| (k.name.clone(), k.frame, k.weight)).collect();
        assert_eq!(got, want, "offset {offset}");
        let again = import_files(&[("out.vmd".into(), bytes)], &[&model], &MmdFilesOptions::default());
        assert!(again.notices.iter().any(|n| n.contains(&format!("{} morph (face) keys kept aside", want.len()))), "{:?}", again.notices);
        println!("offset {offset}: {} morph keys written back and read back equal", want.len());
    }
}

/// Issue 28: the export keeps only the keys linear interpolation does not reproduce. Printed:
/// keys and bytes with a key per frame (the control) and reduced, for WAVEFILE exported again on
/// miku and a salsa BVH on the standard skeleton; the reduced file played back (IK solved) lands
/// where the every-frame file does, within 2 cm per metre (the bound the three.js check uses).
#[test]
fn exported_keys_are_reduced_and_play_back_the_same() {
    use odori_core::mmd::export::clip_to_vmd_every_frame;
    let (rig, model) = miku_rig();
    let wave = vmd::read(WAVEFILE, &read(WAVEFILE)).unwrap();
    let first = pose_vmd("wavefile_v2.vmd", wave, &[&model], &MmdFilesOptions::default()).unwrap();
    let rel = odori_tests::all_bvh().into_iter().find(|r| r.contains("salsa")).expect("a salsa BVH in ../shared/data");
    let im = odori_core::import::import_bytes(&rel, &read(&rel), &odori_core::ImportOptions { fps_override: odori_tests::fps_override_for(&rel), ..Default::default() }).unwrap();
    let salsa = im.clips[0].slice(0, 600.min(im.clips[0].frame_count()), "salsa");
    for (label, clip, rig, models) in [("WAVEFILE on miku_v2", &first.clip, rig, vec![&model]), ("salsa on the standard skeleton", &salsa, standard_rig(), vec![])] {
        let name = if models.is_empty() { String::new() } else { model.name.clone() };
        let t = std::time::Instant::now();
        let every = clip_to_vmd_every_frame(clip, &rig, &name).unwrap();
        let t_every = t.elapsed().as_secs_f64() * 1e3;
        let t = std::time::Instant::now();
        let reduced = clip_to_vmd(clip, &rig, &name).unwrap();
        let t_reduced = t.elapsed().as_secs_f64() * 1e3;
        let (be, br) = (odori_core::export::vmd::write("e.vmd", &every).unwrap(), odori_core::export::vmd::write("r.vmd", &reduced).unwrap());
        let opts = MmdFilesOptions { model: models.is_empty().then(|| STANDARD_RIG.to_string()), ..Default::default() };
        let pe = pose_vmd("e.vmd", vmd::read("e.vmd", &be).unwrap(), &models, &opts).unwrap().clip;
        let pr = pose_vmd("r.vmd", vmd::read("r.vmd", &br).unwrap(), &models, &opts).unwrap().clip;
        assert_eq!(pe.frame_count(), pr.frame_count());
        let height_m = rig.bones[rig.find("頭").unwrap()].rest_position.y * odori_core::mmd::METRES_PER_MMD_UNIT;
        let tol = 0.02 * height_m;
        let mut worst = 0.0f32;
        for f in 0..pe.frame_count() {
            let (a, b) = (pe.world_positions(f), pr.world_positions(f));
            for (j, joint) in pe.skeleton.joints.iter().enumerate() {
                if EXPORT_BONES.contains(&joint.name.as_str()) {
                    worst = worst.max((a[j] - b[j]).length());
                }
            }
        }
        println!(
            "{label}: {} keys, {} bytes a key per frame ({t_every:.0} ms) → {} keys, {} bytes reduced ({t_reduced:.0} ms, {:.0}% of the size); played back: worst {:.3} mm from the every-frame file (tolerance {:.3} mm)",
            every.bone_keys.len(),
            be.len(),
            reduced.bone_keys.len(),
            br.len(),
            100.0 * br.len() as f64 / be.len() as f64,
            worst * 1e3,
            tol * 1e3
        );
        assert!(reduced.bone_keys.len() < every.bone_keys.len(), "{label}: no key dropped");
        assert!(worst <= tol, "{label}: worst {worst} m");
    }
}

/// Item 4's last bad case: PMX 2.1-only data (QDEF skins, flip and impulse morphs, soft bodies,
/// from the synthetic seeds `fuzz/make_seeds.py` writes: no real 2.1 file is in the data) comes
/// through the set import as a model, beside a PMX 2.0 of the same name imported again (replaced,
/// not lost), and a PMX claiming version 2.2 is a named `mmd-bad-version` problem while the rest
/// still imports.
#[test]
fn pmx_2_1_only_data_imports_and_an_unknown_version_is_a_named_problem() {
    let seed = |n: &str| {
        let p = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../fuzz/corpus/import_pmx").join(n);
        std::fs::read(&p).unwrap_or_else(|e| panic!("{}: {e} (run fuzz/make_seeds.py)", p.display()))
    };
    let v21 = seed("pmx21_utf8_wide_indices.pmx");
    let mut v22 = v21.clone();
    // The version float follows the 4-byte magic "PMX ".
    v22[4..8].copy_from_slice(&2.2f32.to_le_bytes());
    let files = vec![("a/v21.pmx".to_string(), v21), ("b/v22.pmx".to_string(), v22), one(WAVEFILE)];
    let r = import_files(&files, &[], &MmdFilesOptions::default());
    let kinds: Vec<(&str, &str)> = r.problems.iter().map(|p| (p.file.as_str(), p.kind)).collect();
    println!("{kinds:?}");
    assert!(kinds.contains(&("b/v22.pmx", "mmd-bad-version")), "{kinds:?}");
    assert!(r.problems.iter().any(|p| p.file == "b/v22.pmx" && p.message.contains("2.2")), "{:?}", r.problems);
    let m = r.models.iter().find(|m| m.file == "a/v21.pmx").expect("the 2.1 model is kept");
    assert_eq!(m.model.format, odori_core::import::mmd_model::ModelFormat::Pmx { version: 2.1 });
    assert_eq!(r.motions.len(), 1, "WAVEFILE still imports");
}
