//! Issue #14, import: options are validated at the boundary, files too large for the tab are
//! refused before allocation, doubtful units are reported, a node above the hips is not drawn
//! as a bone, and a clip's duration is the span of its frames. Every input here is made by the
//! test (no real data needed), so each case states exactly what it feeds the importer.

use odori_core::import::{import_bytes, ImportError, ImportOptions, MAX_SAMPLES};

/// A humanoid BVH (Mixamo-style names) in the given units: `unit` file units per metre
/// (100 for centimetres). With `root_above_hips`, a 6-channel `Root` node sits above the hips
/// and stays at the origin while the hips travel 3 m along +X (a Bandai-Namco-style rig).
fn humanoid_bvh(unit: f32, frames: usize, root_above_hips: bool) -> String {
    let u = |m: f32| m * unit;
    let mut s = String::from("HIERARCHY\n");
    let chain = |name: &str, offsets: &[(&str, [f32; 3])], s: &mut String| {
        // A chain of joints each the child of the previous, ending in an end site.
        let _ = name;
        for (j, (n, o)) in offsets.iter().enumerate() {
            s.push_str(&format!("JOINT {n}\n{{\nOFFSET {} {} {}\nCHANNELS 3 Zrotation Xrotation Yrotation\n", u(o[0]), u(o[1]), u(o[2])));
            if j + 1 == offsets.len() {
                s.push_str("End Site\n{\nOFFSET 0 0.0 0\n}\n");
            }
        }
        for _ in offsets {
            s.push_str("}\n");
        }
    };
    if root_above_hips {
        s.push_str("ROOT Root\n{\nOFFSET 0 0 0\nCHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\nJOINT Hips\n");
    } else {
        s.push_str("ROOT Hips\n");
    }
    s.push_str(&format!("{{\nOFFSET 0 {} 0\nCHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n", u(1.0)));
    chain("spine", &[("Spine", [0.0, 0.1, 0.0]), ("Spine1", [0.0, 0.15, 0.0]), ("Spine2", [0.0, 0.15, 0.0]), ("Neck", [0.0, 0.15, 0.0]), ("Head", [0.0, 0.1, 0.0]), ("HeadTop_End", [0.0, 0.18, 0.0])], &mut s);
    for (side, x) in [("Left", 1.0f32), ("Right", -1.0)] {
        chain(
            "leg",
            &[(&format!("{side}UpLeg"), [0.1 * x, -0.05, 0.0]), (&format!("{side}Leg"), [0.0, -0.45, 0.0]), (&format!("{side}Foot"), [0.0, -0.42, 0.0]), (&format!("{side}ToeBase"), [0.0, -0.06, 0.12])],
            &mut s,
        );
    }
    s.push_str("}\n");
    if root_above_hips {
        s.push_str("}\n");
    }
    // Rebuild the arms into the spine: simpler to splice them in after Spine2's CHANNELS line.
    let arms: String = [("Left", 1.0f32), ("Right", -1.0)]
        .iter()
        .map(|(side, x)| {
            let mut a = String::new();
            chain(
                "arm",
                &[(&format!("{side}Shoulder"), [0.05 * x, 0.12, 0.0]), (&format!("{side}Arm"), [0.12 * x, 0.0, 0.0]), (&format!("{side}ForeArm"), [0.28 * x, 0.0, 0.0]), (&format!("{side}Hand"), [0.25 * x, 0.0, 0.0])],
                &mut a,
            );
            a
        })
        .collect();
    let spine2 = s.find("JOINT Spine2").unwrap();
    let after = spine2 + s[spine2..].find("Yrotation\n").unwrap() + "Yrotation\n".len();
    s.insert_str(after, &arms);
    let channels = s.matches("CHANNELS 3").count() * 3 + s.matches("CHANNELS 6").count() * 6;
    s.push_str(&format!("MOTION\nFrames: {frames}\nFrame Time: 0.0333333\n"));
    for f in 0..frames {
        let mut row = vec![0.0f32; channels];
        let hips = if root_above_hips { 6 } else { 0 };
        row[hips] = u(3.0 * f as f32 / frames.max(1) as f32);
        row[hips + 1] = u(1.0);
        s.push_str(&row.iter().map(|v| v.to_string()).collect::<Vec<_>>().join(" "));
        s.push('\n');
    }
    s
}

fn opts(unit_scale: Option<f32>) -> ImportOptions {
    ImportOptions { unit_scale, ..Default::default() }
}

#[test]
fn humanoid_fixture_is_humanoid_and_plausible() {
    // Control for the tests below: the fixture in centimetres imports as a 1.7 m humanoid
    // with no warning.
    let im = import_bytes("person_cm.bvh", humanoid_bvh(100.0, 4, false).as_bytes(), &ImportOptions::default()).unwrap();
    assert!(im.status.is_humanoid(), "{:?}", im.status);
    let h = odori_core::import::bvh::figure_height_m(&im.clips[0]);
    assert!((1.5..1.9).contains(&h), "height {h}");
    assert!(im.warnings.is_empty(), "{:?}", im.warnings);
}

#[test]
fn unit_scale_outside_its_range_is_refused_with_the_value() {
    let bvh = humanoid_bvh(100.0, 2, false);
    for bad in [f32::NAN, 0.0, -1.0, 1e30, f32::INFINITY, 1e-9] {
        let e = import_bytes("person.bvh", bvh.as_bytes(), &opts(Some(bad))).unwrap_err();
        assert!(matches!(e, ImportError::BadOption { option: "unitScale", .. }), "{bad}: {e:?}");
        assert_eq!(e.kind(), "bad-argument");
        let msg = e.to_string();
        let shown = if bad.is_finite() && bad != 0.0 && !(1e-3..1e6).contains(&bad.abs()) { format!("{bad:e}") } else { bad.to_string() };
        assert!(msg.contains(&format!("unitScale = {shown} ")), "{msg}");
        assert!(msg.len() < 160, "{msg}");
    }
    // Sensible scales still work: millimetres, inches, metres.
    for good in [0.001, 0.0254, 1.0] {
        import_bytes("person.bvh", bvh.as_bytes(), &opts(Some(good))).unwrap();
    }
    for (what, o) in [
        ("fpsOverride", ImportOptions { fps_override: Some(f32::NAN), ..Default::default() }),
        ("fpsOverride", ImportOptions { fps_override: Some(-5.0), ..Default::default() }),
        ("gltfFps", ImportOptions { gltf_fps: 0.0, ..Default::default() }),
    ] {
        let e = import_bytes("person.bvh", bvh.as_bytes(), &o).unwrap_err();
        assert!(e.to_string().contains(what), "{e}");
    }
}

#[test]
fn implausible_height_for_the_unit_is_reported() {
    // The same centimetre figure read as decimetres (0.1 m per unit) stands 17 m tall; read
    // in metres, 170 m. Each is kept (the person may know better) but with a warning that names
    // the height and the option to fix it.
    let bvh = humanoid_bvh(100.0, 2, false);
    for scale in [0.1f32, 1.0] {
        let im = import_bytes("mixamo.bvh", bvh.as_bytes(), &opts(Some(scale))).unwrap();
        let w = im.warnings.join("\n");
        assert!(w.contains("m tall") && w.contains("unitScale"), "scale {scale}: {w:?}");
    }
    // A centimetre file whose figure is 2.3× a person (the Mixamo case: 3.89 m with the
    // guessed unit): the guess is kept and said to be doubtful, with the height.
    let tall = humanoid_bvh(230.0, 2, false);
    let im = import_bytes("tall.bvh", tall.as_bytes(), &ImportOptions::default()).unwrap();
    let h = odori_core::import::bvh::figure_height_m(&im.clips[0]);
    assert!(h > 2.5, "fixture height {h}");
    assert!(im.warnings.iter().any(|w| w.contains(&format!("{h:.2} m tall")) && w.contains("guessed")), "{:?}", im.warnings);
}

#[test]
fn bvh_claiming_a_billion_frames_is_refused_before_allocation() {
    // Two real rows, a header claiming 10⁹ frames: refused with the count named, no allocation
    // of 10⁹ × joints quaternions (which would abort the process, not return an error).
    let bvh = humanoid_bvh(100.0, 2, false).replace("Frames: 2", "Frames: 1000000000");
    let e = import_bytes("huge.bvh", bvh.as_bytes(), &ImportOptions::default()).unwrap_err();
    assert!(matches!(e, ImportError::TooLarge { .. }), "{e:?}");
    assert_eq!(e.kind(), "too-large");
    assert!(e.to_string().contains("1000000000 frames"), "{e}");
    // Under the sample limit but far beyond the bytes present: read, then refused as truncated
    // (the reservation is bounded by what the file can hold).
    let frames = MAX_SAMPLES / 40;
    let bvh = humanoid_bvh(100.0, 2, false).replace("Frames: 2", &format!("Frames: {frames}"));
    let e = import_bytes("short.bvh", bvh.as_bytes(), &ImportOptions::default()).unwrap_err();
    assert!(e.to_string().contains(&format!("after 2 of the {frames} frames")), "{e}");
}

/// A GLB: the JSON chunk padded to 4 bytes, then an optional BIN chunk.
fn glb(json: &str, bin: &[u8]) -> Vec<u8> {
    let mut j = json.as_bytes().to_vec();
    while j.len() % 4 != 0 {
        j.push(b' ');
    }
    let mut b = bin.to_vec();
    while b.len() % 4 != 0 {
        b.push(0);
    }
    let total = 12 + 8 + j.len() + if b.is_empty() { 0 } else { 8 + b.len() };
    let mut out = Vec::new();
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(j.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&j);
    if !b.is_empty() {
        out.extend_from_slice(&(b.len() as u32).to_le_bytes());
        out.extend_from_slice(b"BIN\0");
        out.extend_from_slice(&b);
    }
    out
}

/// Two nodes, one animation whose sampler input (times) and output (rotations) accessors are
/// given; buffer 0 holds `bin`.
fn animated_gltf_json(input: &str, output: &str, bin_len: usize) -> String {
    format!(
        r#"{{"asset":{{"version":"2.0"}},"nodes":[{{"name":"Hips","children":[1]}},{{"name":"Spine","translation":[0,0.5,0]}}],
"scenes":[{{"nodes":[0]}}],"buffers":[{{"byteLength":{bin_len}}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":8}},{{"buffer":0,"byteOffset":8,"byteLength":32}}],
"accessors":[{input},{output}],
"animations":[{{"channels":[{{"sampler":0,"target":{{"node":1,"path":"rotation"}}}}],"samplers":[{{"input":0,"output":1}}]}}]}}"#
    )
}

fn key_bytes(end_secs: f32) -> Vec<u8> {
    let mut bin = Vec::new();
    for t in [0.0f32, end_secs] {
        bin.extend_from_slice(&t.to_le_bytes());
    }
    for q in [[0.0f32, 0.0, 0.0, 1.0], [0.0, 0.0, 0.70710677, 0.70710677]] {
        for v in q {
            bin.extend_from_slice(&v.to_le_bytes());
        }
    }
    bin
}

const TIMES: &str = r#"{"bufferView":0,"componentType":5126,"count":2,"type":"SCALAR","min":[0],"max":[1]}"#;
const ROTS: &str = r#"{"bufferView":1,"componentType":5126,"count":2,"type":"VEC4"}"#;

#[test]
fn tiny_glb_declaring_billions_of_elements_is_refused_before_allocation() {
    // The control imports.
    let ok = glb(&animated_gltf_json(TIMES, ROTS, 40), &key_bytes(1.0));
    import_bytes("ok.glb", &ok, &ImportOptions::default()).unwrap();
    // The same file whose time accessor has no buffer view (sparse: zeros plus one value) and
    // claims 2³¹−1 elements: 8 GB of f32 from a file under 1 KB.
    let huge = r#"{"componentType":5126,"count":2147483647,"type":"SCALAR","sparse":{"count":1,"indices":{"bufferView":0,"componentType":5125},"values":{"bufferView":0}}}"#;
    let bytes = glb(&animated_gltf_json(huge, ROTS, 40), &key_bytes(1.0));
    assert!(bytes.len() < 1024);
    let e = import_bytes("bomb.glb", &bytes, &ImportOptions::default()).unwrap_err();
    assert!(matches!(e, ImportError::TooLarge { .. }), "{e:?}");
    assert!(e.to_string().contains("2147483647 elements"), "{e}");
    // An animation an hour long resampled at 1000 fps on this 2-joint skeleton is within the
    // limit; the sample count is what is bounded, not the duration alone.
    let mut long = key_bytes(3500.0);
    long.truncate(40);
    let o = ImportOptions { gltf_fps: 1000.0, ..Default::default() };
    let e = import_bytes("long.glb", &glb(&animated_gltf_json(TIMES, ROTS, 40), &long), &o);
    assert!(e.is_ok() || matches!(e, Err(ImportError::TooLarge { .. })), "{e:?}");
}

#[test]
fn duration_is_the_span_of_the_frames_and_resampling_keeps_the_last_frame() {
    // A glTF animation of exactly 1 s sampled at 30 fps: 31 frames, 1 s long.
    let im = import_bytes("one_second.glb", &glb(&animated_gltf_json(TIMES, ROTS, 40), &key_bytes(1.0)), &ImportOptions::default()).unwrap();
    let c = &im.clips[0];
    assert_eq!(c.frame_count(), 31);
    assert!((c.duration_secs() - 1.0).abs() < 1e-5, "{}", c.duration_secs());
    // Resampled to 60 fps: 61 frames, the last one the source's last pose, the one before it
    // halfway between the source's last two (not a repeat of the last).
    let r = c.resampled(60.0);
    assert_eq!(r.frame_count(), 61);
    assert!((r.duration_secs() - 1.0).abs() < 1e-5);
    let n = c.joint_count();
    let last = |clip: &odori_core::Clip, back: usize| clip.rotations[(clip.frame_count() - 1 - back) * n + 1];
    assert!(last(&r, 0).angle_between(last(c, 0)) < 1e-4);
    assert!(last(&r, 0).angle_between(last(&r, 1)) > 1e-3, "the last frame is repeated");
    // BVH: 2 frames at 30 fps span one frame time.
    let im = import_bytes("two.bvh", humanoid_bvh(100.0, 2, false).as_bytes(), &ImportOptions::default()).unwrap();
    assert!((im.clips[0].duration_secs() - 0.0333333).abs() < 1e-5, "{}", im.clips[0].duration_secs());
}

#[test]
fn node_above_the_hips_is_not_drawn_as_a_bone() {
    // Root stays at the origin, the hips travel 3 m: drawn with every parent link, the figure
    // has a 3 m stick from the origin. The figure's bones start at the hips.
    let im = import_bytes("namco.bvh", humanoid_bvh(100.0, 30, true).as_bytes(), &ImportOptions::default()).unwrap();
    assert!(im.status.is_humanoid(), "{:?}", im.status);
    let sk = &im.skeleton;
    let root = sk.find("Root").unwrap();
    let hips = sk.find("Hips").unwrap();
    assert!(sk.bones().contains(&(root, hips)), "fixture: Root is the hips' parent");
    let bones = im.humanoid.figure_bones(sk);
    assert!(!bones.iter().any(|&(p, _)| p == root), "{bones:?}");
    // Every other bone is kept, and the longest drawn bone at the last frame is body-sized.
    assert_eq!(bones.len(), sk.bones().len() - 1);
    let c = &im.clips[0];
    let p = c.world_positions(c.frame_count() - 1);
    let longest = bones.iter().map(|&(a, b)| (p[a] - p[b]).length()).fold(0.0f32, f32::max);
    assert!(longest < 0.6, "longest bone {longest} m");
    // A rig whose root is the hips keeps all its bones.
    let plain = import_bytes("plain.bvh", humanoid_bvh(100.0, 2, false).as_bytes(), &ImportOptions::default()).unwrap();
    assert_eq!(plain.humanoid.figure_bones(&plain.skeleton), plain.skeleton.bones());
}

#[test]
fn glb_header_shorter_than_itself_is_an_error_not_a_panic() {
    // Found by the import_gltf fuzz target (kept in fuzz/corpus/import_gltf/): a GLB header
    // whose total length is under 12 made the gltf crate subtract with overflow.
    let mut bytes = glb(&animated_gltf_json(TIMES, ROTS, 40), &key_bytes(1.0));
    for declared in [0u32, 11] {
        bytes[8..12].copy_from_slice(&declared.to_le_bytes());
        let e = import_bytes("short_header.glb", &bytes, &ImportOptions::default()).unwrap_err();
        assert!(matches!(e, ImportError::Gltf { .. }), "{e:?}");
        assert!(e.to_string().contains(&format!("total length of {declared} bytes")), "{e}");
    }
}

#[test]
fn animation_channel_with_an_unknown_path_is_an_error_not_a_panic() {
    // Found by the import_gltf fuzz target (kept in fuzz/corpus/import_gltf/): the gltf crate
    // accepted a channel whose path is not a property, then panicked reading it.
    let json = animated_gltf_json(TIMES, ROTS, 40).replace(r#""path":"rotation""#, r#""path":"toanrtoi""#);
    let e = import_bytes("bad_path.glb", &glb(&json, &key_bytes(1.0)), &ImportOptions::default()).unwrap_err();
    assert!(matches!(e, ImportError::Gltf { .. }), "{e:?}");
    assert!(e.to_string().contains("animation 0, channel 0"), "{e}");
}

#[test]
fn accessor_of_the_wrong_element_type_is_an_error() {
    // Found by the import_gltf fuzz target (kept in fuzz/corpus/import_gltf/): keyframe times
    // read from a VEC4 accessor failed an assertion in the gltf crate's reader.
    let times_vec4 = r#"{"bufferView":1,"componentType":5126,"count":2,"type":"VEC4"}"#;
    let e = import_bytes("times.glb", &glb(&animated_gltf_json(times_vec4, ROTS, 40), &key_bytes(1.0)), &ImportOptions::default()).unwrap_err();
    assert!(e.to_string().contains("sampler 0 times: accessor 0 holds Some(Vec4) elements, Scalar expected"), "{e}");
    // Rotations from a SCALAR accessor.
    let rots_scalar = r#"{"bufferView":1,"componentType":5126,"count":2,"type":"SCALAR"}"#;
    let e = import_bytes("rots.glb", &glb(&animated_gltf_json(TIMES, rots_scalar, 40), &key_bytes(1.0)), &ImportOptions::default()).unwrap_err();
    assert!(e.to_string().contains("channel 0 values"), "{e}");
    // Rotations of u32 components (the crate's reader has no case for them: unreachable!).
    let rots_u32 = r#"{"bufferView":1,"componentType":5125,"count":2,"type":"VEC4"}"#;
    let e = import_bytes("u32.glb", &glb(&animated_gltf_json(TIMES, rots_u32, 40), &key_bytes(1.0)), &ImportOptions::default()).unwrap_err();
    assert!(e.to_string().contains("has U32 components"), "{e}");
    // An accessor with no elements (the crate's reader computes count − 1).
    let times_empty = r#"{"bufferView":0,"componentType":5126,"count":0,"type":"SCALAR"}"#;
    let e = import_bytes("empty.glb", &glb(&animated_gltf_json(times_empty, ROTS, 40), &key_bytes(1.0)), &ImportOptions::default()).unwrap_err();
    assert!(e.to_string().contains("accessor 0 has no elements"), "{e}");
}
