//! Export round trips on real data (spec §M): what the product writes (GLB, BVH) re-imports
//! into the product with the same world joint positions within 1 mm per metre of body height,
//! for the built-in dance on the built-in body, the CMU salsa, and the glTF characters
//! (Xbot, RobotExpressive) on their own mesh and skin. The third-party checks (Khronos
//! validator, three.js) are in tests/node/export.test.mjs.

use odori_core::canon::builtin::demo_clip;
use odori_core::export::{bvh::bvh, gltf::{glb, GlbOptions}, ExportError};
use odori_core::import::{import_bytes, ImportOptions};
use odori_core::library::body::builtin_body;
use odori_core::canon::normalize::body_height;
use odori_core::Clip;
use odori_tests::{fps_override_for, read};

/// Largest distance between same-named joints over every frame, divided by body height.
fn worst_error_per_metre(a: &Clip, b: &Clip) -> f32 {
    assert_eq!(a.frame_count(), b.frame_count(), "{}: frame counts differ", a.name);
    let height = body_height(&a.skeleton.rest_positions()).max(1e-3);
    let pairs: Vec<(usize, usize)> = a.skeleton.joints.iter().enumerate().filter_map(|(i, j)| b.skeleton.find(&j.name).map(|k| (i, k))).collect();
    assert!(pairs.len() >= a.skeleton.animated_joint_count(), "{}: only {} joints found again by name", a.name, pairs.len());
    let mut worst = 0.0f32;
    for f in 0..a.frame_count() {
        let (pa, pb) = (a.world_positions(f), b.world_positions(f));
        for &(i, k) in &pairs {
            worst = worst.max((pa[i] - pb[k]).length());
        }
    }
    worst / height
}

fn glb_round_trip(clip: &Clip, mesh: Option<&odori_core::import::SkinnedMesh>) -> (f32, odori_core::Imported) {
    let bytes = glb(&clip.skeleton, &[clip], &GlbOptions { mesh }).expect("export");
    let back = import_bytes("out.glb", &bytes, &ImportOptions { gltf_fps: clip.fps, ..Default::default() }).expect("re-import");
    let err = worst_error_per_metre(clip, &back.clips[0]);
    (err, back)
}

#[test]
fn builtin_dance_on_builtin_body_round_trips_through_glb() {
    let clip = demo_clip();
    let body = builtin_body(&clip.skeleton);
    let (err, back) = glb_round_trip(&clip, Some(&body));
    println!("built-in demo GLB: worst joint error {:.4} mm per metre", err * 1000.0);
    assert!(err < 1e-3, "worst error {err} m per metre of height");
    let mesh = back.mesh.expect("the body comes back as a mesh");
    let verts: usize = mesh.parts.iter().map(|p| p.positions.len()).sum();
    assert_eq!(verts, body.parts[0].positions.len());
    assert!(back.status.is_humanoid(), "{:?}", back.status);
}

#[test]
fn characters_round_trip_through_glb_on_their_own_mesh() {
    for file in ["gltf/Xbot.glb", "gltf/RobotExpressive.glb"] {
        let src = import_bytes(file, &read(file), &ImportOptions::default()).unwrap_or_else(|e| panic!("{e}"));
        let mesh = src.mesh.as_ref().expect("character has a mesh");
        for clip in src.clips.iter().take(3) {
            let (err, back) = glb_round_trip(clip, Some(mesh));
            println!("{file} '{}': {} frames, worst joint error {:.4} mm per metre", clip.name, clip.frame_count(), err * 1000.0);
            assert!(err < 1e-3, "{file} '{}': worst error {err} m per metre", clip.name);
            let m = back.mesh.expect("mesh comes back");
            let (a, b): (usize, usize) = (mesh.parts.iter().map(|p| p.positions.len()).sum(), m.parts.iter().map(|p| p.positions.len()).sum());
            assert_eq!(a, b, "{file}: vertex count");
        }
    }
}

#[test]
fn bvh_round_trips_salsa_builtin_and_a_character_rig() {
    let salsa = "mocap/cmu-salsa/salsa_01.bvh";
    let mut clips: Vec<Clip> = Vec::new();
    let all = odori_tests::all_bvh();
    let rel = all.iter().find(|p| p.contains("salsa")).cloned().unwrap_or_else(|| salsa.to_string());
    let src = import_bytes(&rel, &read(&rel), &ImportOptions { fps_override: fps_override_for(&rel), ..Default::default() }).unwrap();
    clips.push(src.clips[0].clone());
    clips.push(demo_clip());
    let xbot = import_bytes("Xbot.glb", &read("gltf/Xbot.glb"), &ImportOptions::default()).unwrap();
    clips.push(xbot.clips[0].clone());
    for clip in &clips {
        let text = bvh(clip).expect("export");
        let back = import_bytes("out.bvh", &text, &ImportOptions { fps_override: Some(clip.fps), unit_scale: Some(0.01), ..Default::default() }).unwrap();
        let err = worst_error_per_metre(clip, &back.clips[0]);
        println!("BVH '{}': {} frames, worst joint error {:.4} mm per metre", clip.name, clip.frame_count(), err * 1000.0);
        assert!(err < 1e-3, "'{}': worst error {err} m per metre", clip.name);
        // The frame time is written exactly enough that the stated rate comes back.
        let plain = import_bytes("out.bvh", &text, &ImportOptions::default()).unwrap();
        assert!((plain.clips[0].fps - clip.fps).abs() < 1e-3 * clip.fps, "fps {} vs {}", plain.clips[0].fps, clip.fps);
    }
}

#[test]
fn bad_exports_are_typed_errors() {
    let clip = demo_clip();
    assert_eq!(glb(&clip.skeleton, &[], &GlbOptions::default()), Err(ExportError::NoClips));
    let mut bad = clip.clone();
    bad.rotations[5] = glam::Quat::from_xyzw(f32::NAN, 0.0, 0.0, 1.0);
    assert!(matches!(bvh(&bad), Err(ExportError::NotFinite { frame: 0, .. })));
    let mut body = builtin_body(&clip.skeleton);
    body.parts[0].indices.push(u32::MAX);
    assert!(matches!(glb(&clip.skeleton, &[&clip], &GlbOptions { mesh: Some(&body) }), Err(ExportError::BadMesh { .. })));
}
