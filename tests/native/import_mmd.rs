//! MikuMikuDance files (issue 28, the parsing half) on the real files in
//! `../shared/data/mmd/` (see its SOURCE.txt for the facts checked here): the VMD dances and
//! camera, the PMD and PMX models, texture paths that resolve beside the model, the VMD writer's
//! round trip, and truncated or garbled copies of each real file refused with typed errors.

use std::collections::HashSet;

use glam::Vec3;

use odori_core::import::mmd_bytes::MmdError;
use odori_core::import::vmd::{self, BONE_KEY_BYTES};
use odori_core::mmd::{BoneSampler, VmdBoneKey};
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
        }
        let keys: Vec<VmdBoneKey> = tr.keys.iter().map(VmdBoneKey::from_vmd_key).collect();
        let s = BoneSampler::new(&keys);
        for w in tr.keys.windows(2) {
            let (a, b) = (&w[0], &w[1]);
            // The sampler works in three.js's right-handed frame (z negated): back to the file's.
            let file = |v: Vec3| Vec3::new(v.x, v.y, -v.z);
            // At a key: the key, up to three's 15-step bisection of the curve at x = 0 (≈ 2^-16).
            let at = file(s.sample(a.frame as f32).1);
            assert!((at - a.translation).abs().max_element() <= 1e-4 * (1.0 + (b.translation - a.translation).abs().max_element()), "{} at {}: {at} vs {}", tr.name, a.frame, a.translation);
            let mid = (a.frame as f32 + b.frame as f32) / 2.0;
            let (q, t) = s.sample(mid);
            let t = file(t);
            for c in 0..3 {
                let (lo, hi) = (a.translation[c].min(b.translation[c]), a.translation[c].max(b.translation[c]));
                assert!(t[c] >= lo - 1e-4 && t[c] <= hi + 1e-4, "{} at {mid}: {t} outside {} .. {}", tr.name, a.translation, b.translation);
            }
            let span = a.rotation.normalize().angle_between(b.rotation.normalize());
            assert!(q.angle_between(odori_core::mmd::quat_to_right_handed(a.rotation.normalize())) <= span + 1e-3);
            // (Keys one frame apart do not interpolate, as in three.js.)
            if b.curves.x == vmd::Bezier::LINEAR && b.frame - a.frame >= 2 {
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

// ---- models ------------------------------------------------------------------------------

use odori_core::import::mmd_model::{self, bone_flags, find_texture, MmdModel, ModelFormat, MorphData, Toon};

const MIKU: &str = "mmd/miku_v2/miku_v2.pmd";
const GENE: &str = "mmd/gene/Gene_light.pmx";

fn model(rel: &str) -> MmdModel {
    mmd_model::read_model(rel, &read(rel)).unwrap_or_else(|e| panic!("{rel}: {e}"))
}

/// Files beside a model (relative to its folder, recursively, `/`-separated).
fn files_beside(rel: &str) -> Vec<String> {
    let dir = odori_tests::data_dir().join(rel).parent().unwrap().to_path_buf();
    let mut out = Vec::new();
    let mut stack = vec![dir.clone()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap().flatten() {
            let p = e.path();
            if p.is_dir() {
                stack.push(p);
            } else {
                out.push(p.strip_prefix(&dir).unwrap().to_string_lossy().replace('\\', "/"));
            }
        }
    }
    out
}

/// Structure every real model must have: the materials' runs cover the triangle list, each
/// leg IK chain's links are ancestors of its target in order, every skin's weights are usable.
fn check_structure(rel: &str, m: &MmdModel) {
    let runs: u64 = m.materials.iter().map(|x| u64::from(x.index_count)).sum();
    assert_eq!(runs, m.indices.len() as u64, "{rel}: material runs vs indices");
    // The leg chains (足ＩＫ) follow the skeleton exactly; hair chains of some models skip a
    // bone (mokou's 右髪ＣＩＫ), which MMD tolerates.
    for (i, ik) in m.ik_bones().filter(|(i, _)| m.bones[*i].name.ends_with("足ＩＫ")) {
        let mut chain = Vec::new();
        let mut b = m.bones[ik.target].parent;
        while let Some(p) = b {
            chain.push(p);
            b = m.bones[p].parent;
        }
        let links: Vec<usize> = ik.links.iter().map(|l| l.bone).collect();
        assert_eq!(&chain[..links.len()], &links[..], "{rel}: IK {} links are not the target's ancestors", m.bones[i].name);
    }
    assert!(m.ik_bones().all(|(_, ik)| ik.loop_count > 0 && ik.limit_angle_rad > 0.0));
    for v in &m.vertices {
        let w: f32 = v.skin.weights.iter().sum();
        assert!((w - 1.0).abs() < 1e-3, "{rel}: skin weights sum to {w}");
    }
}

#[test]
fn miku_v2_pmd_has_the_stated_parts() {
    let m = model(MIKU);
    assert_eq!(m.format, ModelFormat::Pmd);
    assert_eq!(m.vertices.len(), 12_354);
    assert_eq!(m.materials.len(), 17);
    assert_eq!(m.bones.len(), 140);
    assert_eq!(m.ik_bones().count(), 7);
    // The file's 31 morphs count PMD's base morph, which holds the others' vertex list and is
    // not a morph of its own (see MmdMorph).
    assert_eq!(m.morphs.len() + 1, 31);
    assert_eq!(m.rigid_bodies.len(), 45);
    assert!(m.name.contains("ミク"), "name {}", m.name);
    check_structure(MIKU, &m);
    // The standard bones, an old-style rig without 全ての親 / グルーブ / 上半身2.
    for n in ["センター", "上半身", "下半身", "頭", "左足ＩＫ", "右つま先ＩＫ", "左ひざ", "右手首"] {
        assert!(m.bone_index(n).is_some(), "no bone {n}");
    }
    for n in ["全ての親", "グルーブ", "上半身2"] {
        assert!(m.bone_index(n).is_none(), "miku_v2 should not have {n}");
    }
    // 左足ＩＫ moves 左ひざ and 左足 to put 左足首 on it; the knee bends one way.
    let ik_bone = m.bone_index("左足ＩＫ").unwrap();
    let ik = m.bones[ik_bone].ik.as_ref().unwrap();
    assert_eq!(m.bones[ik.target].name, "左足首");
    assert_eq!(ik.links.iter().map(|l| m.bones[l.bone].name.as_str()).collect::<Vec<_>>(), ["左ひざ", "左足"]);
    let (lo, hi) = ik.links[0].limits.expect("knee limited");
    assert!(lo.x < hi.x && hi.x < 0.0 && lo.y == 0.0 && hi.z == 0.0);
    assert!(ik.links[1].limits.is_none());
    assert!(m.bones[ik_bone].has(bone_flags::IK) && m.bones[ik_bone].has(bone_flags::TRANSLATABLE));
    // Rigid bodies are placed in model space: near their bones, not near the origin.
    let head = m.bone_index("頭").unwrap();
    for rb in m.rigid_bodies.iter().filter(|rb| rb.bone == Some(head)) {
        assert!((rb.position - m.bones[head].position).length() < 5.0, "{}: {} vs head {}", rb.name, rb.position, m.bones[head].position);
    }
    // PMD morphs became vertex morphs on real vertices.
    assert!(m.morphs.iter().any(|x| x.name == "まばたき"));
    assert!(m.morphs.iter().all(|x| matches!(&x.data, MorphData::Vertex(v) if !v.is_empty())));
    assert!(!m.name_en.is_empty(), "miku_v2 has the English extension");
    // Its eyes take 両目's rotation (PMD bone type 9: grant parent in the tail field).
    let eye = &m.bones[m.bone_index("左目").unwrap()];
    let g = eye.grant.expect("左目 grant");
    assert_eq!(m.bones[g.parent].name, "両目");
}

#[test]
fn gene_pmx_has_the_stated_parts() {
    let m = model(GENE);
    assert_eq!(m.format, ModelFormat::Pmx { version: 2.0 });
    assert_eq!(m.vertices.len(), 28_646);
    assert_eq!(m.materials.len(), 13);
    assert_eq!(m.bones.len(), 224);
    assert_eq!(m.ik_bones().count(), 6);
    assert_eq!(m.morphs.len(), 184);
    assert_eq!(m.rigid_bodies.len(), 87);
    check_structure(GENE, &m);
    for n in ["全ての親", "センター", "グルーブ", "上半身", "上半身2", "下半身", "首", "頭", "左足ＩＫ", "右つま先ＩＫ", "左腕捩", "右手捩"] {
        assert!(m.bone_index(n).is_some(), "no bone {n}");
    }
    // Twist bones turn about a fixed axis; some bone takes a grant (付与) from another.
    let twist = &m.bones[m.bone_index("左腕捩").unwrap()];
    assert!(twist.fixed_axis.is_some_and(|a| (a.length() - 1.0).abs() < 1e-3), "左腕捩 axis {:?}", twist.fixed_axis);
    assert!(m.bones.iter().any(|b| b.grant.is_some_and(|g| g.rotation && g.ratio > 0.0)));
    // Knees: limited links.
    let ik = m.bones[m.bone_index("右足ＩＫ").unwrap()].ik.as_ref().unwrap();
    assert!(ik.links.iter().any(|l| m.bones[l.bone].name.contains("ひざ") && l.limits.is_some()));
}

#[test]
fn every_real_model_reads_and_its_textures_resolve_beside_it() {
    for rel in [MIKU, GENE, "mmd/gene/Gene_light.pmd", "mmd/low_poly/miku.pmd", "mmd/low_poly/gumi.pmd", "mmd/mokou/mokou_A.pmd", "mmd/mokou/mokou_B.pmd"] {
        let m = model(rel);
        check_structure(rel, &m);
        let files = files_beside(rel);
        let files: Vec<&str> = files.iter().map(String::as_str).collect();
        let used: Vec<usize> = m.materials.iter().flat_map(|x| [x.texture, x.sphere, if let Toon::Texture(t) = x.toon { Some(t) } else { None }]).flatten().collect();
        assert!(!used.is_empty(), "{rel}: no textures");
        for t in used {
            assert!(find_texture(&m.textures[t], &files).is_some(), "{rel}: texture {:?} not found among {files:?}", m.textures[t]);
        }
    }
}

#[test]
fn vmd_bone_names_exist_in_the_model() {
    let m = model(MIKU);
    let names: HashSet<&str> = m.bones.iter().map(|b| b.name.as_str()).collect();
    let w = vmd::read(WAVEFILE, &read(WAVEFILE)).unwrap();
    let missing: HashSet<&str> = w.bone_keys.iter().map(|k| k.name.as_str()).filter(|n| !names.contains(n)).collect();
    assert!(missing.is_empty(), "WAVEFILE bones not in miku_v2: {missing:?}");
    let t = vmd::read(TOKINO, &read(TOKINO)).unwrap();
    let found = t.bone_tracks().iter().filter(|tr| m.bones.iter().any(|b| odori_core::import::mmd_text::vmd_name_matches(&tr.name, &b.name, 15))).count();
    assert_eq!(found, 93);
}

fn expect_model_err(file: &str, bytes: &[u8]) -> MmdError {
    match mmd_model::read_model(file, bytes) {
        Ok(_) => panic!("{file}: a damaged copy ({} bytes) was read without error", bytes.len()),
        Err(e) => {
            assert!(e.to_string().contains(file), "the message names the file: {e}");
            e
        }
    }
}

#[test]
fn damaged_pmd_copies_give_typed_errors() {
    let bytes = read(MIKU);
    // Header 283 bytes; vertex count at 283; vertices 38 bytes each; then the face count.
    let nv = 12_354usize;
    let faces = 283 + 4 + 38 * nv;
    // Cut inside the vertices: the vertex count no longer fits.
    assert!(matches!(expect_model_err("cut.pmd", &bytes[..283 + 4 + 38 * 100]), MmdError::CountTooLarge { ref section, .. } if section == "vertices"));
    // Cut inside the header's comment.
    assert!(matches!(expect_model_err("cut.pmd", &bytes[..100]), MmdError::Truncated { ref section, .. } if section == "header"));
    // A face index past the last vertex.
    let mut b = bytes.clone();
    b[faces + 4..faces + 6].copy_from_slice(&(nv as u16 + 5).to_le_bytes());
    match expect_model_err("face.pmd", &b) {
        MmdError::IndexOutOfRange { what: "vertex", index, count, .. } => assert_eq!((index, count), (nv as i64 + 5, nv)),
        e => panic!("{e:?}"),
    }
    // A vertex skinned to bone 500 of 140.
    let mut b = bytes.clone();
    b[287 + 32..287 + 34].copy_from_slice(&500u16.to_le_bytes());
    b[287 + 36] = 100;
    assert!(matches!(expect_model_err("skin.pmd", &b), MmdError::IndexOutOfRange { what: "bone", index: 500, count: 140, .. }));
    // Bad version, bad magic.
    let mut b = bytes.clone();
    b[3..7].copy_from_slice(&2.0f32.to_le_bytes());
    assert!(matches!(expect_model_err("version.pmd", &b), MmdError::BadVersion { .. }));
    assert!(matches!(expect_model_err("magic.pmd", &bytes[1..]), MmdError::BadMagic { .. }));
    // A vertex count of four billion: refused before allocating.
    let mut b = bytes.clone();
    b[283..287].copy_from_slice(&u32::MAX.to_le_bytes());
    assert!(matches!(expect_model_err("count.pmd", &b), MmdError::CountTooLarge { .. }));
    for cut in (0..bytes.len()).step_by(4_999) {
        let _ = mmd_model::read_model("prefix.pmd", &bytes[..cut]);
    }
}

#[test]
fn damaged_pmx_copies_give_typed_errors() {
    let bytes = read(GENE);
    // Header: magic, version, globals count 8 at byte 8, globals at 9–16.
    assert_eq!(bytes[8], 8);
    let mut b = bytes.clone();
    b[9 + 2] = 3; // vertex index size 3
    assert!(matches!(expect_model_err("size.pmx", &b), MmdError::BadValue { what: "vertex index size", value: 3, .. }));
    let mut b = bytes.clone();
    b[9] = 7; // text encoding 7
    assert!(matches!(expect_model_err("enc.pmx", &b), MmdError::BadValue { what: "text encoding", .. }));
    let mut b = bytes.clone();
    b[4..8].copy_from_slice(&3.0f32.to_le_bytes());
    assert!(matches!(expect_model_err("version.pmx", &b), MmdError::BadVersion { .. }));
    // Cuts in each part of the file: typed errors naming a section, never a panic.
    let mut sections = HashSet::new();
    for cut in (0..bytes.len()).step_by(20_011) {
        match mmd_model::read_model("cut.pmx", &bytes[..cut]) {
            Err(MmdError::Truncated { section, .. }) | Err(MmdError::CountTooLarge { section, .. }) => {
                sections.insert(section);
            }
            Err(e) => {
                assert!(matches!(e, MmdError::BadMagic { .. } | MmdError::Truncated { .. }), "cut at {cut}: {e:?}");
            }
            Ok(_) => panic!("a copy cut at {cut} of {} bytes read without error", bytes.len()),
        }
    }
    for s in ["vertices", "faces", "bones", "morphs", "rigid bodies"] {
        assert!(sections.contains(s), "no cut fell in {s}: {sections:?}");
    }
    // A one-byte-short copy.
    assert!(mmd_model::read_model("short.pmx", &bytes[..bytes.len() - 1]).is_err());
}

// ---- VMD writer ------------------------------------------------------------------------------

/// The real dances and the camera written back and read again give every key exactly; the
/// bytes differ from the originals only inside the interpolation blocks' redundant rows 1–3
/// (MMD's own copies, which the reader does not use) and in the garbage after names' NULs.
#[test]
fn real_vmds_round_trip_through_the_writer() {
    for rel in [WAVEFILE, TOKINO, TOKINO_CAM] {
        let v = vmd::read(rel, &read(rel)).unwrap();
        let bytes = odori_core::export::vmd::write(rel, &v).unwrap_or_else(|e| panic!("{rel}: {e}"));
        let back = vmd::read("written.vmd", &bytes).unwrap();
        assert_eq!(back, v, "{rel}: keys changed in the round trip");
        // Stable: writing what was read back gives the same bytes.
        assert_eq!(odori_core::export::vmd::write(rel, &back).unwrap(), bytes);
    }
    // A key of every bone of WAVEFILE written alone, read back, samples the same.
    let v = vmd::read(WAVEFILE, &read(WAVEFILE)).unwrap();
    let back = vmd::read("w.vmd", &odori_core::export::vmd::write("w.vmd", &v).unwrap()).unwrap();
    for (a, b) in v.bone_tracks().iter().zip(back.bone_tracks().iter()) {
        let sampler = |t: &vmd::BoneTrack| BoneSampler::new(&t.keys.iter().map(VmdBoneKey::from_vmd_key).collect::<Vec<_>>());
        let (a, b) = (sampler(a), sampler(b));
        for f in [0.0, 100.5, 1234.25, 2809.0] {
            assert_eq!(a.sample(f), b.sample(f));
        }
    }
}

// ---- synthetic files (the fuzz seeds fuzz/make_seeds.py writes from the formats) ------------

fn seed(name: &str) -> Vec<u8> {
    let p = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../fuzz/corpus").join(name);
    std::fs::read(&p).unwrap_or_else(|e| panic!("{}: {e} (run fuzz/make_seeds.py)", p.display()))
}

/// The paths real files do not take: PMX 2.1 (QDEF, flip and impulse morphs, soft bodies),
/// UTF-8 text, index sizes 1 and 4, additional UVs, SDEF; PMD's bone types 5 and 9, its base
/// morph, English names and own toon file.
#[test]
fn synthetic_models_read_every_section() {
    use odori_core::import::mmd_model::{SkinKind, SphereMode};
    for (name, version, auv) in [("import_pmx/pmx20_utf16.pmx", 2.0, 0), ("import_pmx/pmx21_utf8_wide_indices.pmx", 2.1, 2), ("import_pmx/pmx21_byte_indices.pmx", 2.1, 1)] {
        let m = mmd_model::read_model(name, &seed(name)).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(m.format, ModelFormat::Pmx { version });
        assert_eq!((m.name.as_str(), m.name_en.as_str()), ("テスト", "test"));
        assert_eq!(m.vertices.len(), 4);
        assert_eq!(m.additional_uvs.len(), 4 * auv);
        let kinds: Vec<SkinKind> = m.vertices.iter().map(|v| v.skin.kind).collect();
        let four = if version > 2.0 { SkinKind::Qdef } else { SkinKind::Bdef4 };
        assert_eq!(kinds, [SkinKind::Bdef1, SkinKind::Bdef2, four, SkinKind::Sdef]);
        assert_eq!(m.vertices[1].skin.weights, [0.25, 0.75, 0.0, 0.0]);
        // The BDEF4 slot naming bone −1 reads as bone 0 at weight 0.
        assert_eq!((m.vertices[2].skin.bones[3], m.vertices[2].skin.weights[3]), (0, 0.0));
        assert_eq!(m.vertices[3].skin.sdef.unwrap().r0, glam::Vec3::new(0.0, 12.0, 0.0));
        assert_eq!(m.indices, [0, 1, 2, 1, 3, 2]);
        assert_eq!(m.textures, ["tex\\Body.png", "toon_own.bmp"]);
        assert_eq!(m.materials[0].toon, Toon::Shared(0));
        assert_eq!(m.materials[1].toon, Toon::Texture(1));
        assert_eq!(find_texture(&m.textures[0], &["TEX/body.PNG"]), Some(0));
        let leg = &m.bones[1];
        assert_eq!(leg.grant.map(|g| (g.parent, g.ratio, g.rotation, g.translation)), Some((0, 0.5, true, false)));
        assert_eq!(leg.fixed_axis, Some(glam::Vec3::X));
        assert_eq!(leg.local_axes, Some((glam::Vec3::X, glam::Vec3::Z)));
        let ik = m.bones[2].ik.as_ref().unwrap();
        assert_eq!((ik.target, ik.loop_count, ik.links[0].bone), (1, 40, 1));
        assert_eq!(ik.links[0].limits.unwrap().0.x, -3.14);
        let morph_kinds: Vec<&str> = m.morphs.iter().map(|x| match &x.data {
            MorphData::Group(_) => "group",
            MorphData::Vertex(_) => "vertex",
            MorphData::Bone(_) => "bone",
            MorphData::Uv { .. } => "uv",
            MorphData::Material(_) => "material",
            MorphData::Flip(_) => "flip",
            MorphData::Impulse(_) => "impulse",
        }).collect();
        let mut want = vec!["vertex", "bone", "uv", "material", "group"];
        if version > 2.0 {
            want.extend(["flip", "impulse"]);
        }
        assert_eq!(morph_kinds, want);
        assert_eq!(m.display_frames.len(), 2);
        assert_eq!((m.rigid_bodies.len(), m.joints.len()), (2, 1));
        assert_eq!(m.soft_bodies.len(), usize::from(version > 2.0));
    }
    let m = mmd_model::read_model("pmd10.pmd", &seed("import_pmx/pmd10.pmd")).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(m.format, ModelFormat::Pmd);
    assert_eq!((m.vertices.len(), m.bones.len(), m.morphs.len()), (3, 6, 1));
    assert_eq!(m.textures, ["body.bmp", "shine.sph", "own_toon.bmp"]);
    assert_eq!((m.materials[0].texture, m.materials[0].sphere, m.materials[0].sphere_mode), (Some(0), Some(1), SphereMode::Multiply));
    assert_eq!(m.materials[0].toon, Toon::Texture(2));
    assert_eq!(m.bones[4].grant.map(|g| (g.parent, g.ratio)), Some((0, 1.0)));
    assert_eq!(m.bones[5].grant.map(|g| (g.parent, g.ratio)), Some((0, 0.5)));
    assert!(m.bones[3].ik.as_ref().unwrap().links[0].limits.is_some(), "a PMD knee is limited");
    assert_eq!(m.bones[3].ik.as_ref().unwrap().limit_angle_rad, 2.0);
    // まばたき's one offset, against base entry 1, moves model vertex 2.
    assert_eq!(m.morphs[0].data, MorphData::Vertex(vec![(2, glam::Vec3::new(0.0, -0.5, 0.0))]));
    assert_eq!(m.bones[1].name_en, "bone1");
    // Rigid body 頭 on bone 0 at (0, 8, 0), stored relative: (0, 2, 0) → model (0, 10, 0).
    assert_eq!(m.rigid_bodies[0].position, glam::Vec3::new(0.0, 10.0, 0.0));
    assert!(mmd_model::read_model("p.pmd", &seed("import_pmx/pmd_no_extensions.pmd")).is_ok_and(|m| m.rigid_bodies.is_empty() && m.name_en.is_empty()));
    for name in ["import_vmd/dance", "import_vmd/camera", "import_vmd/all_sections", "import_vmd/old_header"] {
        let v = vmd::read(name, &seed(name)).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(vmd::read("w", &odori_core::export::vmd::write("w", &v).unwrap()).unwrap().bone_keys, v.bone_keys);
    }
    let v = vmd::read("all", &seed("import_vmd/all_sections")).unwrap();
    assert_eq!((v.camera_keys.len(), v.light_keys.len(), v.self_shadow_keys.len(), v.property_keys.len()), (1, 1, 1, 1));
    assert_eq!(v.property_keys[0].ik, [("左足ＩＫ".to_string(), false), ("右足ＩＫ".to_string(), true)]);
}

/// Indices out of range in a PMX: a face naming vertex 9 of 4, a material naming texture 7 of
/// 2; each refused with where it is and what it names.
#[test]
fn pmx_indices_out_of_range_are_named() {
    let bytes = seed("import_pmx/pmx20_utf16.pmx");
    // The face list: count 6, then 0 1 2 1 3 2 as u16.
    let faces: Vec<u8> = [6u32.to_le_bytes().to_vec(), [0u16, 1, 2, 1, 3, 2].iter().flat_map(|v| v.to_le_bytes()).collect()].concat();
    let at = bytes.windows(faces.len()).position(|w| w == faces.as_slice()).expect("face list in the seed") + 4;
    let mut b = bytes.clone();
    b[at..at + 2].copy_from_slice(&9u16.to_le_bytes());
    match expect_model_err("faces.pmx", &b) {
        MmdError::IndexOutOfRange { section: "face index", entry: 0, what: "vertex", index: 9, count: 4, .. } => {}
        e => panic!("{e:?}"),
    }
    // Material 0's texture index (1 byte, 0) follows its edge colour (0, 0, 0, 1) and size 1.
    let edge: Vec<u8> = [0f32, 0.0, 0.0, 1.0, 1.0].iter().flat_map(|v| v.to_le_bytes()).collect();
    let at = bytes.windows(edge.len()).position(|w| w == edge.as_slice()).expect("material edge in the seed") + edge.len();
    let mut b = bytes.clone();
    b[at] = 7;
    match expect_model_err("texture.pmx", &b) {
        MmdError::IndexOutOfRange { section: "material", entry: 0, what: "texture", index: 7, count: 2, .. } => {}
        e => panic!("{e:?}"),
    }
}

/// The 40 gesture motions made for Gene: each reads, round-trips through the writer, and keys
/// only bones Gene_light has. (Their morph keys name 64 morphs of the full Gene that the light
/// model lacks, e.g. ボトムス形状 and the 総合/色 expression sets: printed, not asserted.)
#[test]
fn gene_gesture_vmds_read_round_trip_and_key_genes_bones() {
    let gene = model(GENE);
    let dir = odori_tests::data_dir().join("mmd/gene/motion");
    let mut files: Vec<_> = std::fs::read_dir(&dir).unwrap().flatten().map(|e| e.path()).filter(|p| p.extension().is_some_and(|x| x == "vmd")).collect();
    files.sort();
    assert_eq!(files.len(), 40, "{}", dir.display());
    let bones: Vec<&str> = gene.bones.iter().map(|b| b.name.as_str()).collect();
    let morphs: Vec<&str> = gene.morphs.iter().map(|m| m.name.as_str()).collect();
    let named = |name: &str, names: &[&str]| names.iter().any(|n| odori_core::import::mmd_text::vmd_name_matches(name, n, 15));
    let (mut missing_bones, mut missing_morphs) = (std::collections::BTreeSet::new(), std::collections::BTreeSet::new());
    for p in &files {
        let rel = p.file_name().unwrap().to_string_lossy().to_string();
        let v = vmd::read(&rel, &std::fs::read(p).unwrap()).unwrap_or_else(|e| panic!("{e}"));
        // Some are facial expressions only (morph keys, no bone keys). SOURCE.txt says ≤ 300
        // frames each; 09_unexpected.vmd runs to frame 315.
        assert!(v.bone_keys.len() + v.morph_keys.len() > 0 && v.last_frame() <= 320, "{rel}: {} + {} keys to frame {}", v.bone_keys.len(), v.morph_keys.len(), v.last_frame());
        let back = vmd::read("w.vmd", &odori_core::export::vmd::write(&rel, &v).unwrap()).unwrap();
        assert_eq!((back.bone_keys == v.bone_keys, back.morph_keys == v.morph_keys), (true, true), "{rel}");
        for t in v.bone_tracks() {
            if !named(&t.name, &bones) {
                missing_bones.insert(t.name.clone());
            }
        }
        for k in &v.morph_keys {
            if !named(&k.name, &morphs) {
                missing_morphs.insert(k.name.clone());
            }
        }
    }
    println!("bones not in Gene_light: {missing_bones:?}\nmorphs not in Gene_light: {missing_morphs:?}");
    assert!(missing_bones.is_empty());
}
