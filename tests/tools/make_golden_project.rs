//! Writes the golden `.odori` file of the build's schema version (`tests/golden/project_v1.odori`;
//! `project_v2.odori` was written by it at main 8823db9, schema 2; `project_v3.odori` at main
//! 8ed782d, schema 3; `project_v4.odori` at main 67f699e, schema 4, which adds a camera VMD;
//! `project_v5.odori` at s14-repeats, schema 5, which adds a repeat marked and one removed;
//! `project_v6.odori` by this version, schema 6, which adds a face (lip-sync) track), made from
//! the engine's own content only (the demo song's envelope, a three-joint BVH, a three-key camera
//! VMD and a three-key face VMD written here, built-in moves), so it can be committed. Run once
//! per released schema version and review the result; the test run only reads it:
//!
//! ```sh
//! cargo run -p odori-tests --example make_golden_project -- tests/golden/project_v6.odori
//! ```

use odori_core::library::builtin_moves;
use odori_core::music::{demo_song, envelope, AnalysisOptions, GridCorrection};
use odori_core::project::{self, Camera, ClipRef, MoveKey, Project};
use odori_core::ImportOptions;

/// A tiny BVH of our own (a hips joint and a spine that leans over three frames).
pub const TINY_BVH: &str = "HIERARCHY
ROOT Hips
{
  OFFSET 0 0 0
  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
  JOINT Spine
  {
    OFFSET 0 10 0
    CHANNELS 3 Zrotation Xrotation Yrotation
    End Site
    {
      OFFSET 0 10 0
    }
  }
}
MOTION
Frames: 3
Frame Time: 0.0333333
0 90 0 0 0 0 0 0 0
0 90 0 0 10 0 5 0 0
0 90 0 0 20 0 10 0 0
";

/// A camera VMD of our own: no bone or morph keys, three camera keys (frames 0, 30, 60) orbiting
/// a point 10 MMD units up, written byte by byte as MMD lays the file out (61 bytes a key).
pub fn tiny_camera_vmd() -> Vec<u8> {
    let mut out = Vec::new();
    let mut magic = b"Vocaloid Motion Data 0002".to_vec();
    magic.resize(30, 0);
    out.extend_from_slice(&magic);
    let mut model = b"camera".to_vec();
    model.resize(20, 0);
    out.extend_from_slice(&model);
    out.extend_from_slice(&0u32.to_le_bytes()); // bone keys
    out.extend_from_slice(&0u32.to_le_bytes()); // morph keys
    out.extend_from_slice(&3u32.to_le_bytes()); // camera keys
    for (frame, yaw) in [(0u32, 0.0f32), (30, 0.5), (60, 1.0)] {
        out.extend_from_slice(&frame.to_le_bytes());
        out.extend_from_slice(&(-40.0f32).to_le_bytes()); // distance (in front of the target)
        for v in [0.0f32, 10.0, 0.0, 0.1, yaw, 0.0] {
            out.extend_from_slice(&v.to_le_bytes()); // target x y z, rotation x y z
        }
        for _ in 0..6 {
            out.extend_from_slice(&[20, 107, 20, 107]); // linear easing (x1, x2, y1, y2)
        }
        out.extend_from_slice(&30u32.to_le_bytes()); // field of view, degrees
        out.push(0); // perspective
    }
    out
}

/// A lip-sync VMD of our own: no bone keys, three morph keys of あ (the mouth open) — shut at
/// frame 0, open at 15, shut at 30 — written byte by byte as MMD lays the file out (a 15-byte
/// Shift-JIS name, the frame, the weight: 23 bytes a key).
pub fn tiny_face_vmd() -> Vec<u8> {
    let mut out = Vec::new();
    let mut magic = b"Vocaloid Motion Data 0002".to_vec();
    magic.resize(30, 0);
    out.extend_from_slice(&magic);
    let mut model = b"golden".to_vec();
    model.resize(20, 0);
    out.extend_from_slice(&model);
    out.extend_from_slice(&0u32.to_le_bytes()); // bone keys
    out.extend_from_slice(&3u32.to_le_bytes()); // morph keys
    for (frame, weight) in [(0u32, 0.0f32), (15, 1.0), (30, 0.0)] {
        let mut name = vec![0x82, 0xA0]; // あ in Shift-JIS
        name.resize(15, 0);
        out.extend_from_slice(&name);
        out.extend_from_slice(&frame.to_le_bytes());
        out.extend_from_slice(&weight.to_le_bytes());
    }
    out
}

fn main() {
    let out = std::env::args().nth(1).unwrap_or_else(|| panic!("usage: make_golden_project OUT.odori"));
    let song = demo_song(22_050.0).expect("demo song");
    let env = envelope(&[song.samples.as_slice()], song.sample_rate_hz).expect("envelope");
    let mut p = Project::new();
    p.set_name("golden v1");
    p.set_song("demo", None, &env, AnalysisOptions::default()).expect("song");
    p.correct_grid(GridCorrection { nudge_secs: Some(0.02), ..Default::default() }).expect("nudge");
    let src = p.add_source("tiny.bvh", TINY_BVH.as_bytes(), ImportOptions { fps_override: Some(30.0), ..Default::default() }).expect("bvh");
    let clip = ClipRef { source: src.id, clip: 0 };
    p.set_tags(clip, vec!["lean".into(), "傾く".into()]).expect("tags");
    p.set_texts(vec!["Taro walks, then he rejoices.".into(), "歩きながら右手を振る".into()]);
    p.set(1, &MoveKey::Builtin { r#move: builtin_moves()[7] }).expect("pin bar 2");
    let round = p.candidates(3).expect("candidates");
    p.search(3, &round[..2]).expect("search");
    p.generate().expect("generate");
    p.set_rho(0.5).expect("rho");
    p.set_camera(Some(Camera { yaw_rad: 0.5, pitch_rad: 0.2, distance_m: 4.0, target_m: [0.0, 1.0, 0.0] }));
    // Schema 4: a camera VMD kept in the project.
    p.add_camera("golden_cam.vmd", &tiny_camera_vmd(), Some(0)).expect("camera");
    // Schema 5: the repeat the analysis finds in the demo song (its second chorus) removed, and
    // the last two bars marked as repeating the first two.
    let found = p.repeat_runs().expect("repeats").first().copied().expect("the demo song's second chorus repeats the first");
    p.remove_repeat(found.first_bar).expect("remove the found repeat");
    let n = p.doc().dance.bars.len();
    p.mark_repeat(project::BarRange { first_bar: n - 2, bars: 2 }, project::BarRange { first_bar: 0, bars: 2 }).expect("mark a repeat");
    // Schema 6: a face (lip-sync) track, its frame 10 at song time 0.
    p.add_face_track("golden_lip.vmd", &tiny_face_vmd(), Some(10)).expect("face track");
    let bytes = project::save(&p).expect("save");
    std::fs::write(&out, &bytes).unwrap_or_else(|e| panic!("{out}: {e}"));
    println!("{out}: {} bytes, {} bars, {} undo steps", bytes.len(), p.doc().dance.bars.len(), p.undo_history().len());
}
