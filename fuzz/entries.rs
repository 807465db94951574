//! The fuzzed entry points, shared by the libFuzzer targets (`fuzz/fuzz_targets/`) and the
//! stable-toolchain corpus replay (`tests/native/fuzz_corpus.rs`), so both exercise exactly the
//! same code. Each takes arbitrary bytes and must return (an `Ok` or a typed error) without
//! panicking, aborting on allocation, or hanging.

// Each libFuzzer target uses one of these.
#![allow(dead_code)]

use odori_core::import::{bvh, gltf, mmd_model, vmd, ImportOptions};
use odori_core::music::{analyze, AnalysisOptions, RmsEnvelope};
use odori_core::text::{parse, Lexicon};

/// The BVH importer on the bytes, with the default options and with an explicit unit and rate
/// taken from the first byte (so option handling is fuzzed too).
pub fn import_bvh(data: &[u8]) {
    let _ = bvh::import("fuzz.bvh", data, &ImportOptions::default());
    if let Some(&b) = data.first() {
        let o = ImportOptions { unit_scale: Some(0.001 * f32::from(b.max(1))), fps_override: Some(f32::from(b) + 0.5), ..Default::default() };
        let _ = bvh::import("fuzz.bvh", &data[1..], &o);
    }
}

/// The glTF / GLB importer on the bytes.
pub fn import_gltf(data: &[u8]) {
    let _ = gltf::import("fuzz.glb", data, &ImportOptions::default());
}

/// Song analysis of an envelope decoded from the bytes: byte 0 picks the hop (5–50 ms, or a
/// bad one), byte 1 the band count (1–4); the rest are little-endian u16 RMS values (0xFFFF is
/// NaN, 0xFFFE negative: bad values the analysis must refuse).
pub fn music_envelope(data: &[u8]) {
    if data.len() < 2 {
        return;
    }
    let hop_secs = match data[0] {
        0 => f32::NAN,
        1 => 0.0,
        h => 0.005 + 0.045 * f32::from(h) / 255.0,
    };
    let bands_n = usize::from(data[1] % 4) + 1;
    let values: Vec<f32> = data[2..]
        .chunks_exact(2)
        .map(|c| match u16::from_le_bytes([c[0], c[1]]) {
            0xFFFF => f32::NAN,
            0xFFFE => -1.0,
            v => f32::from(v) / 65535.0,
        })
        .collect();
    let frames = values.len() / bands_n;
    let bands: Vec<Vec<f32>> = (0..bands_n).map(|b| values[b * frames..(b + 1) * frames].to_vec()).collect();
    let _ = analyze(&RmsEnvelope { hop_secs, bands }, &AnalysisOptions::default());
}

/// The text parser on the bytes read as UTF-8 (lossily, so every input is a text).
pub fn text_parse(data: &[u8]) {
    thread_local! {
        static LEXICON: Lexicon = Lexicon::builtin();
    }
    let text = String::from_utf8_lossy(data);
    LEXICON.with(|lex| {
        let p = parse(&text, lex);
        // The table's references must point inside it.
        for e in &p.elements {
            assert!(e.previous.is_none_or(|k| k < e.index), "element {} refers forward to {:?}", e.index, e.previous);
        }
    });
}

/// The `.odori` project reader on the bytes (a zip of a JSON manifest and content-addressed
/// blobs; every check of `project::file::open` on hostile input).
pub fn project_open(data: &[u8]) {
    let _ = odori_core::project::file::open(data);
}

/// The VMD reader on the bytes; what reads is sampled on every track and, where the writer
/// takes it (finite values, Shift-JIS names, curves within 0–127), written and read back to
/// the same keys.
pub fn import_vmd(data: &[u8]) {
    let Ok(v) = vmd::read("fuzz.vmd", data) else { return };
    for t in v.bone_tracks() {
        let last = t.keys.last().map_or(0.0, |k| k.frame as f32);
        let keys: Vec<_> = t.keys.iter().map(odori_core::mmd::VmdBoneKey::from_vmd_key).collect();
        let s = odori_core::mmd::BoneSampler::new(&keys);
        for f in [-1.0, 0.0, 0.5 * last, last - 0.25, last + 1.0] {
            let _ = s.sample(f);
        }
    }
    if let Ok(bytes) = odori_core::export::vmd::write("fuzz.vmd", &v) {
        let back = vmd::read("fuzz.vmd", &bytes).expect("a written VMD reads back");
        assert_eq!(back.bone_keys, v.bone_keys, "bone keys changed in a write/read round trip");
        assert_eq!(back.morph_keys, v.morph_keys, "morph keys changed in a write/read round trip");
    }
}

/// The model reader (PMX or PMD, chosen by magic) on the bytes; a model that reads has every
/// index in range (what the reader promises its consumers).
pub fn import_pmx(data: &[u8]) {
    let Ok(m) = mmd_model::read_model("fuzz.pmx", data) else { return };
    let (nv, nb, nt, nm, nr) = (m.vertices.len(), m.bones.len(), m.textures.len(), m.materials.len(), m.rigid_bodies.len());
    assert!(m.indices.iter().all(|&i| (i as usize) < nv));
    assert!(m.vertices.iter().all(|v| v.skin.bones.iter().all(|&b| (b as usize) < nb.max(1))));
    for b in &m.bones {
        let refs = [b.parent, b.grant.map(|g| g.parent), b.ik.as_ref().map(|ik| ik.target)];
        assert!(refs.iter().flatten().all(|&i| i < nb));
        assert!(b.ik.iter().flat_map(|ik| &ik.links).all(|l| l.bone < nb));
    }
    for x in &m.materials {
        assert!([x.texture, x.sphere].iter().flatten().all(|&t| t < nt));
    }
    assert!(m.rigid_bodies.iter().all(|r| r.bone.is_none_or(|b| b < nb)));
    assert!(m.joints.iter().all(|j| j.rigid_a < nr && j.rigid_b < nr));
    let _ = nm;
}

/// `mmd::files::import_files` on the bytes as a `.zip` (the set the MMD dialog gives: opened,
/// each VMD/PMX/PMD entry read, textures looked up, each VMD posed on the model it names or the
/// standard skeleton) and as a lone `.vmd` (posed on the standard skeleton, the project-source
/// path). Whatever the bytes, every problem names a file and a kind, and every motion is a
/// valid clip.
pub fn import_files(data: &[u8]) {
    use odori_core::mmd::files::{import_files, MmdFilesOptions};
    for name in ["fuzz.zip", "fuzz.vmd"] {
        let r = import_files(&[(name.to_string(), data.to_vec())], &[], &MmdFilesOptions::default());
        assert!(r.problems.iter().all(|p| !p.file.is_empty() && !p.kind.is_empty() && !p.message.is_empty()), "{:?}", r.problems);
        for m in &r.motions {
            assert!(m.clip.validate().is_ok(), "{}: posed clip is invalid", m.file);
        }
    }
}
