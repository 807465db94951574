//! Bone and UV morphs played on a model's mesh (issue 28: "face morph keys play on the model").
//!
//! Bone morphs: no
//! shared model has a bone morph, so the test makes one: a copy of `Gene_light.pmx` with one
//! PMX bone morph (type 2) on 頭 written into its bytes after the model's 184 morphs. The drawn
//! vertices at weight w — the viewer's path: the still clip sampled, `DrawnMorphs::bone_morph_pose`
//! on the local pose, `WorldPose::of_locals`, the mesh's palette, linear blend skinning — must
//! equal the same model's vertices with 頭 keyed by w × the morph's offset and posed through
//! the MMD rig (`MmdRig::pose_into`, grants and IK; an independent path to world transforms);
//! at weight 0 nothing moves (control), and at weight 1 the head moves.
//!
//! The bytes inserted (PMX 2.0, little-endian; Gene: UTF-16LE text, bone indices of 2 bytes):
//! the morph count (i32 at the end of the bone section) goes from 184 to 185, and right before
//! the display-frame section comes one morph: name (i32 byte length, UTF-16LE "骨テスト"),
//! English name (i32 length, UTF-16LE "bone test"), panel u8 = 4, type u8 = 2 (bone), offset
//! count i32 = 1, then the offset: bone index (i16), translation 3 × f32 (MMD units,
//! left-handed as the file), rotation quaternion 4 × f32 (x, y, z, w, left-handed).
//!
//! UV morphs: Gene's one (メッシュなし, base UV) laid on the drawn mesh gives, at weight w, every
//! drawn copy of each of its model vertices the model's offset × w (as three's parser reads the
//! file: x, y of the four floats), and nothing to any other drawn vertex; at weight 0 nothing.

use glam::{Mat4, Quat, Vec3};
use odori_core::import::mmd_model::{read_model, MmdModel, MorphData};
use odori_core::import::SkinnedMesh;
use odori_core::mmd::mesh::model_character;
use odori_core::mmd::morph::DrawnMorphs;
use odori_core::mmd::{quat_to_right_handed, to_right_handed, MmdClipOptions, MmdMotion, MmdPose, METRES_PER_MMD_UNIT};
use odori_core::motion::WorldPose;
use odori_tests::read;

const GENE: &str = "mmd/gene/Gene_light.pmx";
const BONE: &str = "頭";
/// The morph's offset as the file holds it (left-handed, MMD units).
const T_FILE: [f32; 3] = [0.4, 0.6, -0.3];

fn rotation_file() -> Quat {
    Quat::from_axis_angle(Vec3::new(0.3, 1.0, 0.2).normalize(), 0.7)
}

/// PMX text as Gene stores it: i32 byte length, UTF-16LE.
fn text(s: &str) -> Vec<u8> {
    let units: Vec<u8> = s.encode_utf16().flat_map(u16::to_le_bytes).collect();
    let mut out = (units.len() as i32).to_le_bytes().to_vec();
    out.extend(units);
    out
}

/// The one place `pattern` occurs in `bytes` (the test fails if it is not exactly one).
fn unique(bytes: &[u8], pattern: &[u8], what: &str) -> usize {
    let at: Vec<usize> = bytes.windows(pattern.len()).enumerate().filter(|(_, w)| *w == pattern).map(|(i, _)| i).collect();
    assert_eq!(at.len(), 1, "{what}: found {} times", at.len());
    at[0]
}

/// Gene_light.pmx with the bone morph inserted on `bone`, and its morph index.
fn gene_with_bone_morph(bytes: &[u8], model: &MmdModel, bone: usize) -> (Vec<u8>, usize) {
    assert_eq!(bytes[9], 0, "Gene's text is UTF-16LE");
    assert_eq!(bytes[14], 2, "Gene's bone indices are 2 bytes");
    let n = model.morphs.len();
    // The morph count, found by the first morph's names after it.
    let mut head = (n as i32).to_le_bytes().to_vec();
    head.extend(text(&model.morphs[0].name));
    head.extend(text(&model.morphs[0].name_en));
    let count_at = unique(bytes, &head, "the morph count and the first morph");
    // The display-frame section, found by its count and its first frame's names.
    let f = &model.display_frames[0];
    let mut frames = (model.display_frames.len() as i32).to_le_bytes().to_vec();
    frames.extend(text(&f.name));
    frames.extend(text(&f.name_en));
    let frames_at = unique(bytes, &frames, "the display-frame section");
    assert!(frames_at > count_at);
    let mut morph = text("骨テスト");
    morph.extend(text("bone test"));
    morph.extend([4u8, 2u8]);
    morph.extend(1i32.to_le_bytes());
    morph.extend((bone as i16).to_le_bytes());
    let q = rotation_file();
    for v in T_FILE.into_iter().chain([q.x, q.y, q.z, q.w]) {
        morph.extend(v.to_le_bytes());
    }
    let mut out = bytes[..frames_at].to_vec();
    out[count_at..count_at + 4].copy_from_slice(&((n + 1) as i32).to_le_bytes());
    out.extend(morph);
    out.extend_from_slice(&bytes[frames_at..]);
    (out, n)
}

/// Every vertex of `mesh` skinned by `palette` (world · bind per slot).
fn skinned(mesh: &SkinnedMesh, world: &[Mat4]) -> Vec<Vec3> {
    let palette: Vec<Mat4> = mesh.palette.iter().map(|(j, bind)| world[*j] * *bind).collect();
    mesh.parts
        .iter()
        .flat_map(|p| p.positions.iter().zip(p.joints.iter().zip(&p.weights)).map(|(pos, (j, w))| (0..4).map(|k| w[k] * palette[j[k] as usize].transform_point3(Vec3::from(*pos))).sum::<Vec3>()))
        .collect()
}

fn max_gap(a: &[Vec3], b: &[Vec3]) -> f32 {
    assert_eq!(a.len(), b.len());
    a.iter().zip(b).map(|(p, q)| p.distance(*q)).fold(0.0, f32::max)
}

#[test]
fn a_bone_morph_moves_the_drawn_mesh_as_its_bone_keyed_by_weight_times_its_offset() {
    let bytes = read(GENE);
    let plain = read_model("Gene_light.pmx", &bytes).expect("Gene reads");
    let bone = plain.bones.iter().position(|b| b.name == BONE).expect("Gene has 頭");
    let (edited, morph) = gene_with_bone_morph(&bytes, &plain, bone);
    let model = read_model("Gene_bone_morph.pmx", &edited).expect("the edited Gene reads");
    // The insertion is where the reader takes it: the new morph last, every other section as before.
    assert_eq!(model.morphs.len(), plain.morphs.len() + 1);
    assert_eq!(&model.morphs[..morph], &plain.morphs[..]);
    assert_eq!(model.display_frames, plain.display_frames);
    assert_eq!(model.rigid_bodies.len(), plain.rigid_bodies.len());
    assert_eq!(model.joints.len(), plain.joints.len());
    match &model.morphs[morph].data {
        MorphData::Bone(v) => assert_eq!(v, &vec![(bone, Vec3::from(T_FILE), rotation_file())]),
        other => panic!("the inserted morph reads as {other:?}"),
    }

    let c = model_character("Gene_bone_morph.pmx", &model, &[], &[], &[]).expect("a character");
    let drawn = DrawnMorphs::new(&model, &c.drawn_vertices).with_effects(&model, &c.part_material).with_rig_index(&c.rig_index);
    assert!(drawn.has_bone_morphs());
    let still = MmdMotion { model_name: model.name.clone(), bones: Vec::new() };
    let clip = c.rig.motion_to_clip(&still, &MmdClipOptions::default()).expect("the still clip");
    let mesh = &c.character.mesh;

    // The viewer's path: sample, bone morphs on the locals, world pose, skin.
    let viewer = |w: f32| {
        let (mut rot, mut trans) = (Vec::new(), Vec::new());
        clip.sample_into(0.0, &mut rot, &mut trans);
        let moved = drawn.bone_morph_pose(&[(morph, w)], &mut Vec::new(), &mut rot, &mut trans);
        let mut pose = WorldPose::new();
        let mut mats = Vec::new();
        pose.of_locals(&clip.skeleton, &rot, &trans).matrices_into(&mut mats);
        (skinned(mesh, &mats), moved)
    };
    // The rig's path: 頭 keyed by w × the morph's offset, posed by the MMD rig (grants, IK).
    let rig = |w: f32| {
        let n = c.rig.len();
        let (mut rot, mut trans) = (vec![Quat::IDENTITY; n], vec![Vec3::ZERO; n]);
        rot[bone] = Quat::IDENTITY.slerp(quat_to_right_handed(rotation_file()), w);
        trans[bone] = to_right_handed(Vec3::from(T_FILE)) * w;
        let mut p = MmdPose::default();
        c.rig.pose_into(&rot, &trans, &mut p).expect("posed");
        let mats: Vec<Mat4> = c.rig_index.iter().map(|&b| Mat4::from_rotation_translation(p.world_rotations[b], p.world_positions[b] * METRES_PER_MMD_UNIT)).collect();
        skinned(mesh, &mats)
    };

    let (rest, moved0) = viewer(0.0);
    assert_eq!(moved0, 0, "weight 0 moves no joint");
    let rest_rig = rig(0.0);
    let gap0 = max_gap(&rest, &rest_rig);
    assert!(gap0 < 1e-4, "at weight 0 the two paths differ by {gap0} m");
    let mut report = Vec::new();
    for w in [0.35f32, 1.0] {
        let (a, moved) = viewer(w);
        assert_eq!(moved, 1, "one joint (頭) moves");
        let b = rig(w);
        let gap = max_gap(&a, &b);
        let shift = max_gap(&a, &rest);
        let moved_vertices = a.iter().zip(&rest).filter(|(p, q)| p.distance(**q) > 1e-5).count();
        assert!(gap < 1e-4, "weight {w}: the drawn mesh is {gap} m from the rig's pose");
        assert!(shift > 0.02, "weight {w}: the head moved only {shift} m");
        assert!(moved_vertices > 100 && moved_vertices < a.len() / 2, "weight {w}: {moved_vertices} of {} vertices moved", a.len());
        report.push(format!("w {w}: {moved_vertices} vertices moved, up to {:.1} cm; max gap to the rig's pose {:.2e} m", shift * 100.0, gap));
    }
    println!("Gene + a bone morph on 頭: {}", report.join("; "));
}

#[test]
fn genes_uv_morph_moves_the_uvs_of_its_vertices_drawn_copies_by_weight() {
    let model = read_model("Gene_light.pmx", &read(GENE)).expect("Gene reads");
    let (uv_morph, offsets) = model
        .morphs
        .iter()
        .enumerate()
        .find_map(|(i, m)| match &m.data {
            MorphData::Uv { channel: 0, offsets } => Some((i, offsets.clone())),
            _ => None,
        })
        .expect("Gene has a base-UV morph");
    let c = model_character("Gene_light.pmx", &model, &[], &[], &[]).expect("a character");
    let drawn = DrawnMorphs::new(&model, &c.drawn_vertices);
    assert!(drawn.has_uv_morphs() && !drawn.shows_nothing());
    let drawn_of: Vec<u32> = c.drawn_vertices.iter().flatten().copied().collect();
    let mut want = vec![[0.0f32; 2]; drawn_of.len()];
    let mut out = Vec::new();
    assert_eq!(drawn.uv_offsets_into(&[], &mut out), 0);
    assert_eq!(drawn.uv_offsets_into(&[(uv_morph, 0.0)], &mut out), 0, "weight 0 moves no UV");
    assert!(out.iter().all(|o| *o == [0.0; 2]) && out.len() == drawn_of.len());
    for w in [0.4f32, 1.0] {
        for (k, v) in drawn_of.iter().enumerate() {
            want[k] = offsets.iter().filter(|(m, _)| *m == *v as usize).fold([0.0, 0.0], |a, (_, d)| [a[0] + d.x * w, a[1] + d.y * w]);
        }
        let moved = drawn.uv_offsets_into(&[(uv_morph, w)], &mut out);
        let expected = want.iter().filter(|o| **o != [0.0; 2]).count();
        let gap = out.iter().zip(&want).map(|(a, b)| (a[0] - b[0]).abs().max((a[1] - b[1]).abs())).fold(0.0f32, f32::max);
        println!("メッシュなし at {w}: {moved} drawn vertices' UVs moved ({} model vertices in the morph), max gap {gap:.1e}", offsets.len());
        assert_eq!(moved, expected);
        assert!(moved >= offsets.len().min(1) && gap < 1e-6, "weight {w}: {moved} moved, gap {gap}");
    }
}
