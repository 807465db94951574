//! Writes the golden `.odori` file of the build's schema version (`tests/golden/project_v1.odori`;
//! `project_v2.odori` was written by it at main 8823db9, schema 2), made
//! from the engine's own content only (the demo song's envelope, a three-joint BVH written
//! here, built-in moves), so it can be committed. Run once per released schema version and
//! review the result; the test run only reads it:
//!
//! ```sh
//! cargo run -p odori-tests --example make_golden_project -- tests/golden/project_v1.odori
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
    let bytes = project::save(&p).expect("save");
    std::fs::write(&out, &bytes).unwrap_or_else(|e| panic!("{out}: {e}"));
    println!("{out}: {} bytes, {} bars, {} undo steps", bytes.len(), p.doc().dance.bars.len(), p.undo_history().len());
}
