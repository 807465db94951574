//! Broken files give typed errors that name the file and the problem; nothing panics.

use odori_core::import::{import_bytes, ImportError, ImportOptions};
use odori_tests::read;

fn salsa() -> Vec<u8> {
    read("mocap/cmu-salsa/salsa_02.bvh")
}

fn import(name: &str, bytes: &[u8]) -> Result<odori_core::Imported, ImportError> {
    import_bytes(name, bytes, &ImportOptions::default())
}

#[test]
fn empty_file() {
    for bytes in [&b""[..], b"   \n\t "] {
        let e = import("empty.bvh", bytes).unwrap_err();
        assert!(matches!(e, ImportError::Empty { .. }), "{e:?}");
        assert_eq!(e.to_string(), "empty.bvh: the file is empty");
    }
}

#[test]
fn random_bytes() {
    // A deterministic pseudo-random byte soup (xorshift).
    let mut x = 0x2545F4914F6CDD1Du64;
    let bytes: Vec<u8> = (0..4096)
        .map(|_| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x >> 24) as u8
        })
        .collect();
    let e = import("noise.glb", &bytes).unwrap_err();
    assert!(matches!(e, ImportError::UnknownFormat { .. }), "{e:?}");
    assert!(e.to_string().starts_with("noise.glb: not a BVH, glTF, GLB or VMD file"), "{e}");
}

#[test]
fn truncated_bvh() {
    let full = salsa();
    // Cut in the middle of the motion data: fewer rows than "Frames:" says.
    let cut = &full[..full.len() * 2 / 3];
    let e = import("salsa_02.bvh", cut).unwrap_err();
    let msg = e.to_string();
    assert!(matches!(e, ImportError::Bvh { .. }), "{e:?}");
    assert!(msg.starts_with("salsa_02.bvh:"), "{msg}");
    assert!(msg.contains("truncated") || msg.contains("values but the hierarchy declares"), "{msg}");
    // Cut inside the hierarchy.
    let e = import("salsa_02.bvh", &full[..2000]).unwrap_err();
    assert!(e.to_string().contains("the file ends where"), "{e}");
}

#[test]
fn truncations_at_many_points_never_panic() {
    let full = salsa();
    let header_end = full.windows(6).position(|w| w == b"MOTION").unwrap() + 200;
    for k in 1..200 {
        let at = k * header_end / 200;
        assert!(import("cut.bvh", &full[..at]).is_err(), "cut at byte {at} imported");
    }
}

#[test]
fn wrong_channel_count() {
    let text = String::from_utf8(salsa()).unwrap();
    // A joint declares 3 channels but lists 2 names: the third "name" is the next keyword.
    let bad = text.replacen("CHANNELS 3 Zrotation Xrotation Yrotation", "CHANNELS 3 Zrotation Xrotation", 1);
    let e = import("bad.bvh", bad.as_bytes()).unwrap_err();
    assert!(e.to_string().contains("declares 3 channels but"), "{e}");
    // A joint declares 2 channels and lists 2: every frame row now has one value too many.
    let bad = text.replacen("CHANNELS 3 Zrotation Xrotation Yrotation", "CHANNELS 2 Zrotation Xrotation", 1);
    let e = import("bad.bvh", bad.as_bytes()).unwrap_err();
    let msg = e.to_string();
    assert!(msg.contains("frame 1 has more than the 131 values"), "{msg}");
    // A frame row missing a value.
    let mut lines: Vec<&str> = text.lines().collect();
    let motion = lines.iter().position(|l| l.trim() == "MOTION").unwrap();
    let row = lines[motion + 5].rsplit_once(' ').unwrap().0.to_string();
    lines[motion + 5] = &row;
    let e = import("bad.bvh", lines.join("\n").as_bytes()).unwrap_err();
    match &e {
        ImportError::Bvh { line, message, .. } => {
            assert_eq!(*line, motion + 6, "{e}");
            assert!(message.contains("frame 3 has 131 values but the hierarchy declares 132 channels"), "{message}");
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn non_numeric_values() {
    let text = String::from_utf8(salsa()).unwrap();
    let bad = text.replacen("OFFSET 0 20.6881 -0.73152", "OFFSET 0 twenty -0.73152", 1);
    let e = import("bad.bvh", bad.as_bytes()).unwrap_err();
    assert!(e.to_string().contains("'twenty' is not a number"), "{e}");
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    let motion = lines.iter().position(|l| l.trim() == "MOTION").unwrap();
    lines[motion + 10] = lines[motion + 10].replacen(' ', " nan ", 1);
    let e = import("bad.bvh", lines.join("\n").as_bytes()).unwrap_err();
    assert!(e.to_string().contains("frame 8: 'nan' is not a number"), "{e}");
    let bad = text.replacen("Frames:\t2", "Frames:\tmany", 1).replacen("Frames: ", "Frames: many ", 1);
    assert!(import("bad.bvh", bad.as_bytes()).is_err());
}

fn glb_json_and_bin(bytes: &[u8]) -> (Vec<u8>, Vec<u8>) {
    let jlen = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    let json = bytes[20..20 + jlen].to_vec();
    let bstart = 20 + jlen;
    let blen = u32::from_le_bytes(bytes[bstart..bstart + 4].try_into().unwrap()) as usize;
    (json, bytes[bstart + 8..bstart + 8 + blen].to_vec())
}

fn make_glb(json: &[u8], bin: &[u8]) -> Vec<u8> {
    let mut json = json.to_vec();
    while json.len() % 4 != 0 {
        json.push(b' ');
    }
    let mut bin = bin.to_vec();
    while bin.len() % 4 != 0 {
        bin.push(0);
    }
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json);
    out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(&bin);
    out
}

#[test]
fn glb_with_broken_buffer() {
    let robot = read("gltf/RobotExpressive.glb");
    let (json, bin) = glb_json_and_bin(&robot);
    // Rebuilt unchanged, it still imports (the test's GLB writer is right).
    assert!(import("robot.glb", &make_glb(&json, &bin)).is_ok());
    // The binary chunk cut to a tenth: the buffer is shorter than it declares.
    let e = import("robot.glb", &make_glb(&json, &bin[..bin.len() / 10])).unwrap_err();
    assert!(matches!(e, ImportError::Gltf { .. }), "{e:?}");
    assert!(e.to_string().starts_with("robot.glb: invalid glTF:"), "{e}");
    // Buffer length intact but a view pointing past the end.
    let mut doc: serde_json::Value = serde_json::from_slice(&json).unwrap();
    doc["bufferViews"][3]["byteOffset"] = serde_json::json!(bin.len() as u64 + 64);
    let e = import("robot.glb", &make_glb(&serde_json::to_vec(&doc).unwrap(), &bin)).unwrap_err();
    assert!(e.to_string().contains("runs past the end of buffer"), "{e}");
    // An accessor whose count overruns its view.
    let mut doc: serde_json::Value = serde_json::from_slice(&json).unwrap();
    doc["accessors"][0]["count"] = serde_json::json!(10_000_000);
    let e = import("robot.glb", &make_glb(&serde_json::to_vec(&doc).unwrap(), &bin)).unwrap_err();
    assert!(e.to_string().contains("accessor 0 needs"), "{e}");
    // The file cut in half (GLB header says more than there is).
    let e = import("robot.glb", &robot[..robot.len() / 2]).unwrap_err();
    assert!(matches!(e, ImportError::Gltf { .. }), "{e:?}");
    // Garbage JSON.
    let e = import("robot.gltf", b"{ \"asset\": {\"version\": \"2.0\"}, \"nodes\": [ {\"children\": [7]} ] ").unwrap_err();
    assert!(matches!(e, ImportError::Gltf { .. }), "{e:?}");
}

#[test]
fn gltf_with_external_buffer_names_it() {
    let json = br#"{"asset":{"version":"2.0"},"buffers":[{"uri":"robot.bin","byteLength":16}],"nodes":[{"name":"a"}],"skins":[{"joints":[0]}]}"#;
    let e = import("robot.gltf", json).unwrap_err();
    assert!(e.to_string().contains("separate file 'robot.bin'"), "{e}");
}

#[test]
fn gltf_without_anything_to_animate() {
    let json = br#"{"asset":{"version":"2.0"},"nodes":[{"name":"a"}],"scenes":[{"nodes":[0]}]}"#;
    let e = import("static.gltf", json).unwrap_err();
    assert!(matches!(e, ImportError::Unsupported { .. }), "{e:?}");
    assert!(e.to_string().contains("nothing to animate"), "{e}");
}
