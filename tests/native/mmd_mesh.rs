//! MMD models as characters (issue 28 item 2, steps 1–2), on the real files in
//! ../shared/data/mmd: 初音ミク Ver2 (PMD, BMP textures), the low-poly PMD models (TGA textures)
//! and Gene (PMX 2.0, PNG textures) become engine characters whose skinned mesh, posed by a VMD
//! through the engine's clip and palette, lands where the MMD rig's own bone transforms put each
//! vertex (computed here straight from the file's skin weights); TGA textures decode to the same
//! pixels as the PNG copies shipped beside them.

use glam::{Mat4, Vec3};
use odori_core::import::mmd_model::{MmdModel, SkinKind};
use odori_core::mmd::files::{import_files, ImportedModel, MmdFilesOptions};
use odori_core::mmd::mesh::{model_character, ModelCharacter};
use odori_core::mmd::texture::{decode_rgba, mesh_texture};
use odori_core::mmd::{to_right_handed, MmdClipOptions, MmdMotion, MmdPose, MotionSampler, METRES_PER_MMD_UNIT};
use odori_core::HumanoidStatus;
use odori_tests::{data_dir, read};

/// Every file of a data folder, named `folder/file` as a dropped folder gives them.
fn folder_files(rel: &str) -> Vec<(String, Vec<u8>)> {
    let dir = data_dir().join(rel);
    let mut out: Vec<(String, Vec<u8>)> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e} (the MMD test data is missing)", dir.display()))
        .filter_map(|e| e.ok())
        .filter(|e| e.path().is_file())
        .map(|e| (format!("{}/{}", rel.rsplit('/').next().unwrap_or(rel), e.file_name().to_string_lossy()), std::fs::read(e.path()).expect("read")))
        .collect();
    out.sort();
    out
}

/// The model `file` of a folder imported with the folder's files (its textures resolved;
/// `extra`: sub-folders, named below the folder as a dropped folder names them), and the set.
fn imported_set(folder: &str, file: &str, extra: &[&str]) -> (ImportedModel, Vec<(String, Vec<u8>)>) {
    let mut files: Vec<(String, Vec<u8>)> = folder_files(folder).into_iter().filter(|(n, _)| !n.ends_with(".pmd") && !n.ends_with(".pmx") || n.ends_with(file)).collect();
    let top = folder.rsplit('/').next().unwrap_or(folder);
    for e in extra {
        let sub = e.strip_prefix(folder).unwrap_or(e).trim_start_matches('/');
        files.extend(folder_files(e).into_iter().map(|(n, b)| (format!("{top}/{sub}/{}", n.rsplit('/').next().unwrap_or(&n)), b)));
    }
    let r = import_files(&files, &[], &MmdFilesOptions::default());
    assert!(r.problems.is_empty(), "{:?}", r.problems);
    (r.models.into_iter().find(|m| m.file.ends_with(file)).unwrap_or_else(|| panic!("{file} not imported")), files)
}

fn imported(folder: &str, file: &str, extra: &[&str]) -> ImportedModel {
    imported_set(folder, file, extra).0
}

fn character(m: &ImportedModel) -> ModelCharacter {
    model_character(&m.file, &m.model, &m.textures, &m.missing_textures, &[]).unwrap_or_else(|e| panic!("{e}"))
}

/// The mesh covers the model: every triangle of every material, every vertex's position
/// (metres, z flipped), weights summing to 1 on palette slots in range, the humanoid complete.
fn check_mesh(m: &MmdModel, c: &ModelCharacter) {
    let mesh = &c.character.mesh;
    let tris: usize = mesh.parts.iter().map(|p| p.indices.len() / 3).sum();
    let want: usize = m.materials.iter().map(|x| x.index_count as usize / 3).sum();
    assert_eq!(tris, want, "{}: triangles", m.name);
    assert_eq!(c.looks.len(), mesh.parts.len());
    for p in &mesh.parts {
        assert_eq!(p.positions.len(), p.joints.len());
        for (w, j) in p.weights.iter().zip(&p.joints) {
            assert!((w.iter().sum::<f32>() - 1.0).abs() < 1e-5, "{w:?}");
            assert!(j.iter().all(|&s| (s as usize) < mesh.palette.len()));
        }
        assert!(p.indices.iter().all(|&i| (i as usize) < p.positions.len()));
    }
    let mut seen = 0;
    let parts_pos: Vec<[f32; 3]> = mesh.parts.iter().flat_map(|p| p.positions.iter().copied()).collect();
    for v in m.vertices.iter().step_by(97) {
        let want = (to_right_handed(v.position) * METRES_PER_MMD_UNIT).to_array();
        if parts_pos.iter().any(|p| (Vec3::from(*p) - Vec3::from(want)).length() < 1e-6) {
            seen += 1;
        }
    }
    let sampled = m.vertices.iter().step_by(97).count();
    assert!(seen as f32 >= 0.99 * sampled as f32, "{}: {seen} of {sampled} sampled vertices in the mesh", m.name);
    let status = c.character.map.status(&c.character.skeleton, None);
    assert!(status.is_humanoid() && !matches!(status, HumanoidStatus::NotHumanoid { .. }), "{status}");
}

/// Skins every vertex of the engine's mesh at a clip frame (Σ w · world · bind), and the same
/// vertex from the MMD rig's pose and the file's own weights (Σ w · (P_b + R_b (v − rest_b)));
/// returns the largest distance, metres.
fn skin_error(m: &MmdModel, c: &ModelCharacter, motion: &MmdMotion, frame: usize) -> f32 {
    let clip = c.rig.motion_to_clip(motion, &MmdClipOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(clip.skeleton.len(), c.character.skeleton.len(), "the VMD's clip is on the character's own skeleton");
    let mut world = Vec::new();
    odori_core::motion::WorldPose::new().of_frame(&clip, frame.min(clip.frame_count() - 1)).matrices_into(&mut world);
    let mesh = &c.character.mesh;
    let skin: Vec<Mat4> = mesh.palette.iter().map(|(j, bind)| world[*j] * *bind).collect();
    let engine: Vec<Vec3> = mesh
        .parts
        .iter()
        .flat_map(|p| p.positions.iter().zip(p.joints.iter().zip(&p.weights)).map(|(pos, (j, w))| (0..4).map(|k| w[k] * skin[j[k] as usize].transform_point3(Vec3::from(*pos))).sum::<Vec3>()))
        .collect();
    // The reference, from the rig's pose and the file's weights, vertex by vertex in the same
    // order the parts list them (matched by rest position).
    let mut sampler = MotionSampler::new(&c.rig, motion);
    let mut pose = MmdPose::default();
    sampler.pose_at(frame as f32, &mut pose).unwrap();
    let rest: Vec<Vec3> = c.rig.bones.iter().map(|b| b.rest_position).collect();
    let mut worst = 0.0f32;
    // Walk the model's materials as the mesh was built (reversed triangle order, first use).
    let mut at = 0;
    for &mi in &c.part_material {
        let begin: usize = m.materials[..mi].iter().map(|x| x.index_count as usize).sum();
        let run = &m.indices[begin..begin + m.materials[mi].index_count as usize];
        let mut first = std::collections::HashSet::new();
        for tri in run.chunks_exact(3) {
            for &vi in &[tri[0], tri[2], tri[1]] {
                if !first.insert(vi) {
                    continue;
                }
                let v = &m.vertices[vi as usize];
                let s = &v.skin;
                let (bones, weights): (Vec<u32>, Vec<f32>) = match s.kind {
                    SkinKind::Bdef1 => (vec![s.bones[0]], vec![1.0]),
                    SkinKind::Bdef2 | SkinKind::Sdef => (vec![s.bones[0], s.bones[1]], vec![s.weights[0], 1.0 - s.weights[0]]),
                    _ => (s.bones.to_vec(), s.weights.to_vec()),
                };
                let total: f32 = weights.iter().sum();
                let x = to_right_handed(v.position);
                let mut want = Vec3::ZERO;
                for (b, w) in bones.iter().zip(&weights) {
                    let b = *b as usize;
                    want += (w / total) * (pose.world_positions[b] + pose.world_rotations[b] * (x - rest[b]));
                }
                worst = worst.max((engine[at] - want * METRES_PER_MMD_UNIT).length());
                at += 1;
            }
        }
    }
    assert_eq!(at, engine.len());
    worst
}

fn vmd_motion(rel: &str) -> MmdMotion {
    MmdMotion::from_vmd(&odori_core::import::vmd::read(rel, &read(rel)).unwrap_or_else(|e| panic!("{e}")))
}

#[test]
fn miku_v2_plays_wavefile_with_her_skin_where_the_rig_puts_it() {
    let (m, set) = imported_set("mmd/miku_v2", "miku_v2.pmd", &[]);
    let c = model_character(&m.file, &m.model, &m.textures, &m.missing_textures, &set).unwrap_or_else(|e| panic!("{e}"));
    check_mesh(&m.model, &c);
    assert!(c.notices.is_empty(), "{:?}", c.notices);
    // eyeM2.bmp (24-bit BMP) decoded and drawn on the eyes' material; the shared toon ramps
    // (toonNN.bmp beside the model) found for every material that names one, and not without them.
    assert!(c.looks.iter().any(|l| l.texture.is_some()), "a textured material");
    let toon_named = c.looks.iter().filter(|l| !matches!(l.toon, odori_core::import::mmd_model::Toon::None)).count();
    assert!(toon_named > 0 && c.looks.iter().all(|l| l.toon_texture.is_some() || matches!(l.toon, odori_core::import::mmd_model::Toon::None)), "{:?}", c.looks.iter().map(|l| (l.toon, l.toon_texture)).collect::<Vec<_>>());
    assert!(c.character.mesh.parts.iter().all(|p| p.toon.is_some()));
    assert!(character(&m).looks.iter().all(|l| l.toon_texture.is_none()), "no ramps without the toon files");
    let dance = vmd_motion("mmd/motion/wavefile_v2.vmd");
    let rest_motion = MmdMotion { model_name: String::new(), bones: Vec::new() };
    for frame in [0, 700, 1500, 2400] {
        let e = skin_error(&m.model, &c, &dance, frame);
        assert!(e < 1e-4, "frame {frame}: a vertex is {e} m from where the rig puts it");
    }
    // A control: the rest pose's skin against the dance's pose moves vertices by far more.
    let clip = c.rig.motion_to_clip(&dance, &MmdClipOptions::default()).unwrap();
    let mut world = Vec::new();
    odori_core::motion::WorldPose::new().of_frame(&clip, 1500).matrices_into(&mut world);
    let moved = c.character.mesh.palette.iter().map(|(j, bind)| (world[*j] * *bind).transform_point3(Vec3::ZERO).length()).fold(0.0f32, f32::max);
    assert!(moved > 0.05, "the dance moves the skin ({moved} m)");
    assert!(skin_error(&m.model, &c, &rest_motion, 0) < 1e-5);
}

#[test]
fn gene_pmx_plays_a_gesture_with_her_skin_where_the_rig_puts_it() {
    let m = imported("mmd/gene", "Gene_light.pmx", &["mmd/gene/light"]);
    assert_eq!(m.model.vertices.len(), 28_646);
    let c = character(&m);
    check_mesh(&m.model, &c);
    assert!(c.notices.is_empty(), "{:?}", c.notices);
    let textured = c.looks.iter().filter(|l| l.texture.is_some()).count();
    assert!(textured >= 10, "Gene's materials with a PNG texture: {textured} of {}", c.looks.len());
    assert!(c.character.mesh.textures.iter().all(|t| t.mime_type == "image/png"));
    for file in ["mmd/gene/motion/01_happy.vmd", "mmd/gene/motion/33_angry.vmd"] {
        let motion = vmd_motion(file);
        for frame in [30, 120] {
            let e = skin_error(&m.model, &c, &motion, frame);
            assert!(e < 1e-4, "{file} frame {frame}: a vertex is {e} m from where the rig puts it");
        }
    }
}

#[test]
fn low_poly_models_decode_their_tga_textures() {
    for (file, tga) in [("miku.pmd", "ro_hatune01.tga"), ("gumi.pmd", "ro_gumi01.tga")] {
        let m = imported("mmd/low_poly", file, &[]);
        let c = character(&m);
        check_mesh(&m.model, &c);
        assert!(m.model.textures.iter().any(|t| t.eq_ignore_ascii_case(tga)), "{file} names {tga}: {:?}", m.model.textures);
        assert!(c.looks.iter().any(|l| l.texture.is_some()), "{file}: a textured material");
        assert!(c.notices.is_empty(), "{:?}", c.notices);
    }
    // The TGA decodes to the pixels of the PNG copy beside it (converted by someone else);
    // the control, the other gumi texture's PNG, does not match.
    let (w, h, tga) = decode_rgba("ro_gumi01.tga", "tga", &read("mmd/low_poly/ro_gumi01.tga")).unwrap();
    let png = image::load_from_memory(&read("mmd/low_poly/ro_gumi01.png")).unwrap().to_rgba8();
    let other = image::load_from_memory(&read("mmd/low_poly/ro_gumi01_2.png")).unwrap().to_rgba8();
    assert_eq!((w, h), png.dimensions());
    let diff = |a: &[u8], b: &[u8]| a.chunks_exact(4).zip(b.chunks_exact(4)).map(|(x, y)| (0..3).map(|k| (x[k] as i32 - y[k] as i32).abs()).max().unwrap_or(0)).filter(|&d| d > 2).count();
    let same = diff(&tga, png.as_raw());
    assert!(same * 1000 <= (w * h) as usize, "{same} of {} pixels differ from the PNG copy", w * h);
    // Controls: the PNG upside down (the TGA origin read the wrong way), and gumi's other texture.
    let flipped: Vec<u8> = png.as_raw().chunks_exact(w as usize * 4).rev().flatten().copied().collect();
    let upside = diff(&tga, &flipped);
    let differs = if other.dimensions() == (w, h) { diff(&tga, other.as_raw()) } else { (w * h) as usize };
    println!("ro_gumi01.tga: {same} of {} pixels off its PNG copy by more than 2/255; upside down {upside}; ro_gumi01_2.png {differs}", w * h);
    assert!(upside * 10 > (w * h) as usize, "the flipped control should differ ({upside})");
    // Re-encoded as PNG, the decoded TGA reads back bit for bit.
    let t = mesh_texture("ro_gumi01.tga", &read("mmd/low_poly/ro_gumi01.tga")).unwrap();
    assert_eq!(image::load_from_memory(&t.image).unwrap().to_rgba8().as_raw(), &tga);
}

#[test]
fn a_missing_texture_leaves_the_model_drawn_with_a_notice_naming_it() {
    let files: Vec<(String, Vec<u8>)> = folder_files("mmd/low_poly").into_iter().filter(|(n, _)| n.ends_with("miku.pmd")).collect();
    let r = import_files(&files, &[], &MmdFilesOptions::default());
    let m = &r.models[0];
    let c = character(m);
    assert!(c.looks.iter().all(|l| l.texture.is_none()));
    assert!(c.notices.iter().any(|n| n.to_lowercase().contains("ro_hatune01.tga")), "{:?}", c.notices);
    // A texture that is not an image: a notice, the rest drawn.
    let mut bad = m.clone();
    bad.textures.push(("ro_hatune01.tga".into(), "low_poly/ro_hatune01.tga".into(), vec![1, 2, 3]));
    let c = model_character(&bad.file, &bad.model, &bad.textures, &[], &[]).unwrap();
    assert!(c.notices.iter().any(|n| n.contains("ro_hatune01.tga") && n.contains("decoded")), "{:?}", c.notices);
}

/// Step 5: Gene's head turns 60° in 0.2 s and holds; her hair (the bones her rigid bodies
/// simulate) follows by the damped spring: the tip of the longest chain under the head lags the
/// animated pose by ≥ 10° at the end of the turn and is back within 2° a second later; the
/// same clip at 60 fps swings alike (frame-rate independent); with no spring bones there is no lag.
/// The tip itself turns during the turn: its lag is not a tip standing still, as it was when each
/// bone of a chain lagged its parent in world space (no carry: the control).
#[test]
fn gene_hair_lags_a_head_turn_and_settles_within_a_second() {
    use odori_core::mmd::spring::{apply_springs, spring_bones, SpringParams};
    use odori_core::Clip;
    use std::sync::Arc;
    let m = imported("mmd/gene", "Gene_light.pmx", &["mmd/gene/light"]);
    let c = character(&m);
    let sk = c.character.skeleton.clone();
    let bones = spring_bones(&m.model);
    let joints: Vec<usize> = bones.iter().filter_map(|b| c.rig_index.iter().position(|i| i == b)).collect();
    assert!(joints.len() >= 5, "Gene's simulated bones: {}", joints.len());
    let head = sk.find("頭").expect("頭");
    let under = |mut j: usize, anc: usize| loop {
        match sk.joints[j].parent {
            Some(p) if p == anc => return true,
            Some(p) => j = p,
            None => return false,
        }
    };
    let depth = |mut j: usize| {
        let mut d = 0;
        while let Some(p) = sk.joints[j].parent {
            if !joints.contains(&j) {
                break;
            }
            d += 1;
            j = p;
        }
        d
    };
    let tip = *joints.iter().filter(|&&j| under(j, head)).max_by_key(|&&j| depth(j)).expect("a simulated chain under the head (hair)");
    assert!(depth(tip) >= 2, "the hair chain is {} bones long", depth(tip));
    let fps = 30.0;
    let frames = 60;
    let n = sk.len();
    let mut rotations = vec![glam::Quat::IDENTITY; frames * n];
    for f in 0..frames {
        let t = (f as f32 / fps / 0.2).min(1.0);
        rotations[f * n + head] = glam::Quat::from_rotation_y(60f32.to_radians() * t);
    }
    let clip = Clip { name: "turn".into(), source: "test".into(), fps, skeleton: Arc::new((*sk).clone()), rotations, translations: vec![odori_core::clip::TranslationTrack { joint: 0, values: vec![sk.joints[0].rest_offset; frames] }] };
    clip.validate().unwrap();
    let tip_rot = |c: &Clip, f: usize| {
        let mut w = Vec::new();
        odori_core::motion::WorldPose::new().of_frame(&c, f).matrices_into(&mut w);
        w[tip].to_scale_rotation_translation().1
    };
    let lag = |c: &Clip, secs: f32| tip_rot(c, (secs * c.fps).round() as usize).angle_between(tip_rot(&clip, (secs * fps).round() as usize)).to_degrees();
    let sprung = apply_springs(&clip, &joints, SpringParams::default());
    let at_turn_end = lag(&sprung, 0.2);
    let after_1s = lag(&sprung, 1.2);
    let peak = (0..frames).map(|f| lag(&sprung, f as f32 / fps)).fold(0.0f32, f32::max);
    println!("Gene hair tip '{}': lag {at_turn_end:.1}° at the end of a 60° head turn, peak {peak:.1}°, {after_1s:.2}° a second later", sk.joints[tip].name);
    assert!(at_turn_end >= 10.0, "lag at the end of the turn {at_turn_end}°");
    assert!(after_1s < 2.0, "still {after_1s}° off a second after the turn");
    // 60 fps: the same swing within 1.5° at the same times.
    let clip60 = clip.resampled(60.0);
    let sprung60 = apply_springs(&clip60, &joints, SpringParams::default());
    for secs in [0.1, 0.2, 0.4, 0.8] {
        let (a, b) = (lag(&sprung, secs), lag(&sprung60, secs));
        assert!((a - b).abs() < 1.5, "at {secs} s: {a}° at 30 fps vs {b}° at 60 fps");
    }
    // Control: springs off.
    assert!(lag(&apply_springs(&clip, &[], SpringParams::default()), 0.2) < 1e-3);
    // The viewer's follower, stepped frame by frame from the last drawn time, is the same
    // integrator: at each frame time it gives the whole-clip springs' pose (quaternions within 1e-5: acos's f32 floor near 1 is 7e-4 rad);
    // a jump back (a seek) or forward by more than MAX_GAP_S puts the hair at the animated pose.
    {
        use odori_core::mmd::spring::{SpringFollower, MAX_GAP_S};
        // The distance between two unit quaternions of the same rotation up to sign.
        let qdiff = |a: glam::Quat, b: glam::Quat| (glam::Vec4::from(a) - glam::Vec4::from(b)).length().min((glam::Vec4::from(a) + glam::Vec4::from(b)).length());
        let mut f = SpringFollower::new(&sk, &joints);
        assert!(f.has_springs());
        for fr in 0..frames {
            let (rot, _) = f.pose(&clip, fr as f32 / fps, SpringParams::default());
            let want = sprung.frame_rotations(fr);
            let worst = rot.iter().zip(want).map(|(a, b)| qdiff(*a, *b)).fold(0.0f32, f32::max);
            assert!(worst < 1e-5, "frame {fr}: the follower is {worst} off the whole-clip springs");
        }
        let animated = |t: f32| {
            let (mut r, mut tr) = (Vec::new(), Vec::new());
            clip.sample_into(t, &mut r, &mut tr);
            r
        };
        for (from, to) in [(1.0f32, 0.1f32), (0.05, 0.05 + MAX_GAP_S + 0.05)] {
            f.pose(&clip, from, SpringParams::default());
            f.pose(&clip, from + 1.0 / fps, SpringParams::default());
            let (rot, _) = f.pose(&clip, to, SpringParams::default());
            let worst = rot.iter().zip(animated(to)).map(|(a, b)| qdiff(*a, b)).fold(0.0f32, f32::max);
            assert!(worst < 1e-5, "a jump from {from} s to {to} s: {worst} off the animated pose");
        }
        // Mid-turn without the jump, the hair is off the animated pose (the check above can fail).
        let mut g = SpringFollower::new(&sk, &joints);
        for fr in 0..=3 {
            g.pose(&clip, fr as f32 / fps, SpringParams::default());
        }
        let (rot, _) = g.pose(&clip, 4.0 / fps, SpringParams::default());
        let off = rot.iter().zip(animated(4.0 / fps)).map(|(a, b)| qdiff(*a, b)).fold(0.0f32, f32::max);
        assert!(off > 0.02, "stepped mid-turn the hair should lag: {off}");
    }
    // The lag is a lag, not a tip standing still: with the default carry the tip turns ≥ 10°
    // during the turn; the control without carry (each bone left where it was in world space)
    // is the 12th-order filter whose tip does not move at all during the turn.
    let moved = |p: SpringParams| {
        let sp = apply_springs(&clip, &joints, p);
        tip_rot(&sp, (0.2 * fps) as usize).angle_between(tip_rot(&sp, 0)).to_degrees()
    };
    let (with_carry, without) = (moved(SpringParams::default()), moved(SpringParams { carry: 0.0, ..SpringParams::default() }));
    println!("Gene hair tip (a chain of {}): turned {with_carry:.1}° during the 60° head turn with carry {}, {without:.1}° without", depth(tip), SpringParams::default().carry);
    assert!(with_carry >= 10.0, "the tip turned only {with_carry}° during the turn");
    assert!(without < 1.0, "control: without carry the tip turned {without}°");
}

/// Face morphs (issue 28): WAVEFILE's morph keys on miku_v2.pmd. Each keyed morph's weight is
/// its key's weight at every key frame and linear between keys (checked at every key of あ and
/// まばたき and midway between neighbours); the offsets put on the model's vertices are the
/// morph's own vertex offsets × weight, z negated and in metres, on exactly its vertices; at a
/// frame where no morph is keyed above 0 nothing moves. On Gene (PMX), each group morph expands
/// into its vertex-morph members × member weight.
#[test]
fn wavefile_face_morphs_move_mikus_vertices_by_the_models_offsets() {
    use odori_core::import::mmd_model::MorphData;
    use odori_core::mmd::morph::{vertex_offsets_into, FaceMorphs};
    let m = imported("mmd/miku_v2", "miku_v2.pmd", &[]);
    let vmd = odori_core::import::vmd::read("wavefile_v2.vmd", &read("mmd/motion/wavefile_v2.vmd")).expect("wavefile_v2.vmd reads");
    assert!(!vmd.morph_keys.is_empty(), "WAVEFILE has morph keys");
    let faces = FaceMorphs::new(&m.model, &vmd.morph_keys);
    assert!(!faces.is_empty());
    let mut offsets = Vec::new();
    let mut checked = 0;
    for name in ["あ", "まばたき"] {
        let mi = m.model.morphs.iter().position(|x| x.name == name).unwrap_or_else(|| panic!("miku_v2 has no morph {name}"));
        let MorphData::Vertex(data) = &m.model.morphs[mi].data else { panic!("{name} is not a vertex morph") };
        let mut keys: Vec<(u32, f32)> = vmd.morph_keys.iter().filter(|k| k.name == name).map(|k| (k.frame, k.weight)).collect();
        keys.sort_by_key(|k| k.0);
        // The last key of a frame wins.
        keys.dedup_by(|later, earlier| {
            if later.0 == earlier.0 {
                earlier.1 = later.1;
                true
            } else {
                false
            }
        });
        assert!(keys.len() >= 2, "{name}: {} keys", keys.len());
        let weight = |f: f32| faces.weights_at(f).iter().find(|(k, _)| *k == mi).map_or(0.0, |(_, w)| *w);
        for (i, &(f, w)) in keys.iter().enumerate() {
            assert!((weight(f as f32) - w).abs() < 1e-6, "{name} at frame {f}: {} vs key {w}", weight(f as f32));
            if let Some(&(f1, w1)) = keys.get(i + 1) {
                let mid = (f as f32 + f1 as f32) / 2.0;
                assert!((weight(mid) - (w + w1) / 2.0).abs() < 1e-5, "{name} midway {mid}");
            }
        }
        // The frame of the morph's strongest key, with only this morph weighted.
        let &(f, w) = keys.iter().max_by(|a, b| a.1.total_cmp(&b.1)).expect("keys");
        assert!(w >= 0.25, "{name}: strongest key {w}");
        let moved = vertex_offsets_into(&m.model, &[(mi, weight(f as f32))], &mut offsets);
        let mut want = vec![glam::Vec3::ZERO; m.model.vertices.len()];
        for (v, d) in data {
            want[*v] += glam::Vec3::new(d.x, d.y, -d.z) * w * 0.08;
        }
        let worst = offsets.iter().zip(&want).map(|(a, b)| (*a - *b).length()).fold(0.0f32, f32::max);
        let largest = want.iter().map(|o| o.length()).fold(0.0f32, f32::max);
        println!("miku_v2 {name} at frame {f} (weight {w}): {moved} vertices moved, largest {:.2} mm, worst miss {worst:e} m", largest * 1000.0);
        assert!(worst < 1e-7 && largest > 1e-4, "{name}: worst {worst}, largest {largest}");
        assert_eq!(moved, want.iter().filter(|o| **o != glam::Vec3::ZERO).count());
        checked += 1;
    }
    assert_eq!(checked, 2);
    // Control: no weights, nothing moves.
    assert_eq!(vertex_offsets_into(&m.model, &[], &mut offsets), 0);
    assert!(offsets.iter().all(|o| *o == glam::Vec3::ZERO));

    // Groups, on Gene.
    let g = imported("mmd/gene", "Gene_light.pmx", &["mmd/gene/light"]);
    let mut groups = 0;
    for (gi, gm) in g.model.morphs.iter().enumerate() {
        let MorphData::Group(members) = &gm.data else { continue };
        let mut want = vec![glam::Vec3::ZERO; g.model.vertices.len()];
        let mut any = false;
        for &(member, mw) in members {
            if let Some(MorphData::Vertex(data)) = g.model.morphs.get(member).map(|x| &x.data) {
                any = true;
                for (v, d) in data {
                    want[*v] += glam::Vec3::new(d.x, d.y, -d.z) * (0.7 * mw * 0.08);
                }
            }
        }
        if !any {
            continue;
        }
        vertex_offsets_into(&g.model, &[(gi, 0.7)], &mut offsets);
        let worst = offsets.iter().zip(&want).map(|(a, b)| (*a - *b).length()).fold(0.0f32, f32::max);
        assert!(worst < 1e-6, "Gene group morph {}: worst {worst}", gm.name);
        groups += 1;
    }
    println!("Gene: {groups} group morphs of vertex morphs expand to their members");
}

/// The drawn mesh's map back to the model (issue 28, face morphs drawn): each part draws every
/// model vertex its material's triangles use exactly once, nothing else, at that vertex's
/// position (metres, z flipped); every vertex a triangle uses is drawn. Checked on miku_v2 (PMD)
/// and Gene (PMX), whose materials share vertices.
#[test]
fn drawn_vertices_map_each_part_back_to_the_models_vertices_once_per_use() {
    use std::collections::HashSet;
    for (folder, file, extra) in [("mmd/miku_v2", "miku_v2.pmd", &[][..]), ("mmd/gene", "Gene_light.pmx", &["mmd/gene/light"][..])] {
        let m = imported(folder, file, extra);
        let c = character(&m);
        let mesh = &c.character.mesh;
        assert_eq!(c.drawn_vertices.len(), mesh.parts.len(), "{file}: a map per part");
        let mut start = 0usize;
        let mut starts = Vec::new();
        for mat in &m.model.materials {
            starts.push(start);
            start += mat.index_count as usize;
        }
        let mut drawn_anywhere: HashSet<u32> = HashSet::new();
        let mut shared = 0usize;
        for (k, (part, map)) in mesh.parts.iter().zip(&c.drawn_vertices).enumerate() {
            let mi = c.part_material[k];
            let run = &m.model.indices[starts[mi]..starts[mi] + m.model.materials[mi].index_count as usize];
            let used: HashSet<u32> = run.iter().copied().collect();
            let listed: HashSet<u32> = map.iter().copied().collect();
            assert_eq!(listed.len(), map.len(), "{file} part {k}: a model vertex drawn twice in one part");
            assert_eq!(listed, used, "{file} part {k}: the drawn vertices are not the material's");
            assert_eq!(map.len(), part.positions.len(), "{file} part {k}");
            for (p, &v) in part.positions.iter().zip(map) {
                let want = to_right_handed(m.model.vertices[v as usize].position) * METRES_PER_MMD_UNIT;
                assert!((Vec3::from(*p) - want).length() < 1e-6, "{file} part {k}: vertex {v} drawn at {p:?}, model at {want}");
            }
            shared += listed.iter().filter(|v| !drawn_anywhere.insert(**v)).count();
        }
        let all_used: HashSet<u32> = m.model.indices.iter().copied().collect();
        assert_eq!(drawn_anywhere, all_used, "{file}: every vertex a triangle uses is drawn");
        let total: usize = c.drawn_vertices.iter().map(Vec::len).sum();
        println!("{file}: {} model vertices, {} used, {total} drawn in {} parts ({shared} drawn again in another part)", m.model.vertices.len(), all_used.len(), mesh.parts.len());
    }
}

/// Face morphs on the drawn mesh: WAVEFILE's weights at a frame where あ is high, laid on
/// miku_v2's drawn vertices by `DrawnMorphs`, equal at every drawn vertex the sum of the model's
/// own vertex-morph offsets × weight (read here straight from the file's morphs, z negated, in
/// metres) at the model vertex it draws; the same at a まばたき key; no weights, nothing moves.
/// On Gene, each group morph lands on the drawn vertices of its members.
#[test]
fn face_morph_offsets_on_the_drawn_mesh_are_the_models_own_at_a_frame() {
    use odori_core::import::mmd_model::MorphData;
    use odori_core::mmd::morph::DrawnMorphs;
    let m = imported("mmd/miku_v2", "miku_v2.pmd", &[]);
    let c = character(&m);
    let vmd = odori_core::import::vmd::read("wavefile_v2.vmd", &read("mmd/motion/wavefile_v2.vmd")).expect("wavefile_v2.vmd reads");
    let drawn = DrawnMorphs::new(&m.model, &c.drawn_vertices);
    let map: Vec<u32> = c.drawn_vertices.iter().flatten().copied().collect();
    assert_eq!(drawn.drawn_len(), map.len());
    assert!(!drawn.is_empty());
    let faces = drawn.faces(&vmd.morph_keys);
    let model_faces = odori_core::mmd::morph::FaceMorphs::new(&m.model, &vmd.morph_keys);
    // The expected offset of each model vertex, from the model's morph data alone.
    let expected = |weights: &[(usize, f32)]| {
        let mut want = vec![Vec3::ZERO; m.model.vertices.len()];
        for &(mi, w) in weights {
            if let MorphData::Vertex(data) = &m.model.morphs[mi].data {
                for (v, d) in data {
                    want[*v] += Vec3::new(d.x, d.y, -d.z) * w * 0.08;
                }
            }
        }
        want
    };
    let key_frame = |name: &str| {
        vmd.morph_keys.iter().filter(|k| k.name == name).max_by(|a, b| a.weight.total_cmp(&b.weight)).map(|k| (k.frame, k.weight)).unwrap_or_else(|| panic!("no {name} key"))
    };
    let mut out = Vec::new();
    for name in ["あ", "まばたき"] {
        let mi = m.model.morphs.iter().position(|x| x.name == name).expect("morph");
        let (frame, w) = key_frame(name);
        let weights = faces.weights_at(frame as f32);
        assert_eq!(weights, model_faces.weights_at(frame as f32), "matched by name as on the model");
        assert!(weights.iter().any(|&(k, x)| k == mi && (x - w).abs() < 1e-6), "{name} at frame {frame}: {weights:?}");
        let moved = drawn.offsets_into(&weights, &mut out);
        let want = expected(&weights);
        let worst = out.iter().zip(&map).map(|(o, &v)| (*o - want[v as usize]).length()).fold(0.0f32, f32::max);
        let largest = out.iter().map(|o| o.length()).fold(0.0f32, f32::max);
        let own = match &m.model.morphs[mi].data {
            MorphData::Vertex(d) => d.len(),
            _ => 0,
        };
        println!("miku_v2 frame {frame} ({name} {w:.2}, {} morphs weighted): {moved} drawn vertices moved ({name} alone moves {own} model vertices), largest {:.2} mm, worst miss {worst:e} m", weights.len(), largest * 1e3);
        assert!(worst < 1e-6 && largest > 1e-3, "{name}: worst {worst}, largest {largest}");
        assert_eq!(moved, map.iter().filter(|&&v| want[v as usize] != Vec3::ZERO).count());
    }
    // Control: no weights, nothing moves.
    assert_eq!(drawn.offsets_into(&[], &mut out), 0);
    assert!(out.len() == map.len() && out.iter().all(|o| *o == Vec3::ZERO));

    // Groups, on Gene's drawn mesh.
    let g = imported("mmd/gene", "Gene_light.pmx", &["mmd/gene/light"]);
    let gc = character(&g);
    let gd = DrawnMorphs::new(&g.model, &gc.drawn_vertices);
    let gmap: Vec<u32> = gc.drawn_vertices.iter().flatten().copied().collect();
    let mut model_out = Vec::new();
    let mut groups = 0;
    for (gi, gm) in g.model.morphs.iter().enumerate() {
        if !matches!(gm.data, MorphData::Group(_)) {
            continue;
        }
        odori_core::mmd::morph::vertex_offsets_into(&g.model, &[(gi, 0.7)], &mut model_out);
        gd.offsets_into(&[(gi, 0.7)], &mut out);
        let worst = out.iter().zip(&gmap).map(|(o, &v)| (*o - model_out[v as usize]).length()).fold(0.0f32, f32::max);
        assert!(worst < 1e-6, "Gene group morph {}: worst {worst}", gm.name);
        groups += usize::from(model_out.iter().any(|o| *o != Vec3::ZERO));
    }
    assert!(groups > 0, "Gene has group morphs of vertex morphs");
    println!("Gene: {groups} group morphs land on their members' drawn vertices");
}

/// Every model in ../shared/data/mmd (found by walking it, so a model added there is not
/// missed) becomes a character whose mesh covers the model and plays WAVEFILE with its skin
/// where the rig puts it — mokou_A.pmd too, whose hair IK chain 右髪ＣＩＫ lists 右髪Ｃ０, a bone
/// off the chain's path (MMD and three r171's CCDIKSolver keep such a link; the rig used to
/// refuse the model).
#[test]
fn every_real_model_becomes_a_character_and_plays_wavefile() {
    let mut found = Vec::new();
    let mut stack = vec![data_dir().join("mmd")];
    while let Some(dir) = stack.pop() {
        for e in std::fs::read_dir(&dir).unwrap_or_else(|e| panic!("{}: {e} (the MMD test data is missing)", dir.display())).filter_map(|e| e.ok()) {
            let p = e.path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x.eq_ignore_ascii_case("pmd") || x.eq_ignore_ascii_case("pmx")) {
                found.push(p.strip_prefix(data_dir()).unwrap_or(&p).to_string_lossy().replace('\\', "/"));
            }
        }
    }
    found.sort();
    let sets: [(&str, &str, &[&str]); 7] = [
        ("mmd/gene", "Gene_light.pmd", &["mmd/gene/light"]),
        ("mmd/gene", "Gene_light.pmx", &["mmd/gene/light"]),
        ("mmd/low_poly", "gumi.pmd", &[]),
        ("mmd/low_poly", "miku.pmd", &[]),
        ("mmd/miku_v2", "miku_v2.pmd", &[]),
        ("mmd/mokou", "mokou_A.pmd", &[]),
        ("mmd/mokou", "mokou_B.pmd", &[]),
    ];
    let listed: Vec<String> = sets.iter().map(|(d, f, _)| format!("{d}/{f}")).collect();
    assert_eq!(found, listed, "the models in the data folder");
    let dance = vmd_motion("mmd/motion/wavefile_v2.vmd");
    for (folder, file, extra) in sets {
        let (m, set) = imported_set(folder, file, extra);
        let c = model_character(&m.file, &m.model, &m.textures, &m.missing_textures, &set).unwrap_or_else(|e| panic!("{file}: {e}"));
        check_mesh(&m.model, &c);
        let worst = [0, 1500].iter().map(|&f| skin_error(&m.model, &c, &dance, f)).fold(0.0f32, f32::max);
        eprintln!("{file}: {} vertices in {} parts, {} bones; WAVEFILE's skin at most {worst:.2e} m from the rig's; notices {:?}", m.model.vertices.len(), c.character.mesh.parts.len(), m.model.bones.len(), c.notices);
        assert!(worst < 1e-4, "{file}: a vertex is {worst} m from where the rig puts it");
    }
}

/// The morph kinds of every real model, as read (three r171's MMDParser reads Gene_light.pmx as
/// 3 group, 177 vertex, 1 UV and 3 material morphs; PMD has vertex morphs only): no model here
/// has a bone morph. Gene's 3 material morphs each add 1 to the alpha of an overlay material
/// drawn at alpha 0 (青ざめ, どんより: the pale face 青ざめ; いらいら: イライラ), and 29_Terrified.vmd
/// keys 青ざめ: at its key the part drawing that material gets the model's data × the key's
/// weight (diffuse alpha 0 + 1 × w), every other part none; its one UV morph (メッシュなし, of
/// the base UV) is played (`mmd_morph_play.rs`), so no morph is named as not played.
#[test]
fn gene_material_morphs_give_the_overlay_part_the_models_data_times_weight() {
    use odori_core::import::mmd_model::MorphData;
    use odori_core::mmd::morph::DrawnMorphs;
    use odori_core::mmd::morph_effects::{unplayed_morphs, MaterialFactors};
    let kinds = |m: &MmdModel| {
        let mut k = [0usize; 5]; // group, vertex, bone, UV, material
        for x in &m.morphs {
            match x.data {
                MorphData::Group(_) => k[0] += 1,
                MorphData::Vertex(_) => k[1] += 1,
                MorphData::Bone(_) => k[2] += 1,
                MorphData::Uv { .. } => k[3] += 1,
                MorphData::Material(_) => k[4] += 1,
                _ => {}
            }
        }
        k
    };
    for (folder, file, extra) in [("mmd/miku_v2", "miku_v2.pmd", &[][..]), ("mmd/low_poly", "miku.pmd", &[]), ("mmd/low_poly", "gumi.pmd", &[]), ("mmd/mokou", "mokou_A.pmd", &[]), ("mmd/mokou", "mokou_B.pmd", &[]), ("mmd/gene", "Gene_light.pmd", &["mmd/gene/light"])] {
        let k = kinds(&imported(folder, file, extra).model);
        println!("{file}: morphs group {} vertex {} bone {} UV {} material {}", k[0], k[1], k[2], k[3], k[4]);
        assert_eq!((k[0], k[2], k[3], k[4]), (0, 0, 0, 0), "{file}: a PMD has vertex morphs only");
    }
    let m = imported("mmd/gene", "Gene_light.pmx", &["mmd/gene/light"]);
    let k = kinds(&m.model);
    println!("Gene_light.pmx: morphs group {} vertex {} bone {} UV {} material {}", k[0], k[1], k[2], k[3], k[4]);
    assert_eq!(k, [3, 177, 0, 1, 3], "Gene_light.pmx's morph kinds as three r171's MMDParser reads them");
    assert_eq!(unplayed_morphs(&m.model), vec![], "Gene's UV morph moves the base UV: played");
    let c = character(&m);
    let drawn = DrawnMorphs::new(&m.model, &c.drawn_vertices).with_effects(&m.model, &c.part_material);
    assert!(drawn.effects().has_material_morphs() && !drawn.shows_nothing());
    let vmd = odori_core::import::vmd::read("29_Terrified.vmd", &read("mmd/gene/motion/29_Terrified.vmd")).expect("29_Terrified.vmd reads");
    let faces = drawn.faces(&vmd.morph_keys);
    let key = vmd.morph_keys.iter().filter(|k| k.name == "青ざめ" && k.weight > 0.0).min_by_key(|k| k.frame).expect("29_Terrified keys 青ざめ");
    let pale = m.model.morphs.iter().position(|x| x.name == "青ざめ").expect("the morph 青ざめ");
    let target = match &m.model.morphs[pale].data {
        MorphData::Material(o) => o[0].material.expect("one material"),
        d => panic!("青ざめ is {d:?}"),
    };
    let part = c.part_material.iter().position(|&x| x == target).expect("a part draws the overlay");
    assert_eq!(c.looks[part].diffuse.w, 0.0, "the overlay is drawn at alpha 0 without the morph");
    let mut parts = Vec::new();
    // The control: no weights, nothing changed and the overlay stays unseen.
    assert_eq!(drawn.part_factors_into(&[], &mut parts), 0);
    assert_eq!(parts[part].0.diffuse(c.looks[part].diffuse).w, 0.0);
    let weights = faces.weights_at(key.frame as f32);
    let w_pale = weights.iter().find(|(i, _)| *i == pale).map_or(0.0, |x| x.1);
    assert!((w_pale - key.weight).abs() < 1e-6, "青ざめ at frame {}: {weights:?}", key.frame);
    let changed = drawn.part_factors_into(&weights, &mut parts);
    assert_eq!(parts.len(), c.character.mesh.parts.len());
    let alpha = parts[part].0.diffuse(c.looks[part].diffuse).w;
    println!("29_Terrified frame {}: 青ざめ at {w_pale:.2}, {} morphs weighted: {changed} parts changed; the overlay's alpha {alpha:.2}", key.frame, weights.len());
    assert!((alpha - w_pale).abs() < 1e-6, "the overlay's alpha {alpha} vs the key's weight {w_pale}");
    // Only parts whose material a weighted material morph names change.
    let named: Vec<usize> = weights
        .iter()
        .filter_map(|(i, _)| match &m.model.morphs[*i].data {
            MorphData::Material(o) => Some(o.iter().filter_map(|x| x.material).collect::<Vec<_>>()),
            _ => None,
        })
        .flatten()
        .collect();
    for (k, (f, _)) in parts.iter().enumerate() {
        assert!(named.contains(&c.part_material[k]) || *f == MaterialFactors::NONE, "part {k} changed: {f:?}");
    }
    assert!(key.weight > 0.5, "a strong key: {}", key.weight);
}
