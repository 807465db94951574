//! Writes the golden `.odori` file of the build's schema version (`tests/golden/project_v1.odori`;
//! `project_v2.odori` was written by it at main 8823db9, schema 2; `project_v3.odori` at main
//! 8ed782d, schema 3; `project_v4.odori` at main 67f699e, schema 4, which adds a camera VMD;
//! `project_v5.odori` at s14-repeats, schema 5, which adds a repeat marked and one removed;
//! `project_v6.odori` at s15-mmdface, schema 6, which adds a face (lip-sync) track;
//! `project_v7.odori` by this version, schema 7, which adds a VMD dance posed on an MMD model
//! kept with its texture and shared toon ramp, and a Generate under *my moves* whose built-in
//! bars keep why they are built-in), made from the engine's own content only (the demo song's
//! envelope, a three-joint BVH, a three-key camera VMD, a three-key face VMD, a one-bone PMD
//! model with one triangle, a two-key dance VMD and two tiny BMPs written here, built-in moves
//! and the engine's own dance of them as a BVH), so it can be committed. Run once per released
//! schema version and review the result; the test run only reads it:
//!
//! ```sh
//! cargo run -p odori-tests --example make_golden_project -- tests/golden/project_v7.odori
//! ```

use odori_core::library::builtin_moves;
use odori_core::music::{demo_song, envelope, AnalysisOptions, GridCorrection};
use odori_core::choreo::{GenerateOptions, MovesSource, RenderOptions};
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

/// The golden texture's four pixels (RGB, top row first): red, green / blue, white.
pub const GOLDEN_TEXTURE: [[u8; 3]; 4] = [[255, 0, 0], [0, 255, 0], [0, 0, 255], [255, 255, 255]];
/// The golden toon ramp's: white to grey, top to bottom.
pub const GOLDEN_TOON: [[u8; 3]; 4] = [[255, 255, 255], [255, 255, 255], [128, 128, 128], [128, 128, 128]];

/// A 2×2 24-bit BMP of `pixels` (RGB, top row first), written as the format lays it out: the
/// 14-byte file header, the 40-byte BITMAPINFOHEADER, then the rows bottom-up, BGR, each padded
/// to 4 bytes.
pub fn tiny_bmp(pixels: [[u8; 3]; 4]) -> Vec<u8> {
    let row = 8; // 2 pixels × 3 bytes, padded to 4
    let size = 54 + 2 * row;
    let mut out = Vec::with_capacity(size);
    out.extend_from_slice(b"BM");
    out.extend_from_slice(&(size as u32).to_le_bytes());
    out.extend_from_slice(&0u32.to_le_bytes());
    out.extend_from_slice(&54u32.to_le_bytes());
    out.extend_from_slice(&40u32.to_le_bytes());
    out.extend_from_slice(&2i32.to_le_bytes()); // width
    out.extend_from_slice(&2i32.to_le_bytes()); // height (positive: bottom-up)
    out.extend_from_slice(&1u16.to_le_bytes()); // planes
    out.extend_from_slice(&24u16.to_le_bytes()); // bits per pixel
    out.extend_from_slice(&0u32.to_le_bytes()); // BI_RGB
    out.extend_from_slice(&((2 * row) as u32).to_le_bytes());
    out.extend_from_slice(&2835u32.to_le_bytes()); // 72 dpi
    out.extend_from_slice(&2835u32.to_le_bytes());
    out.extend_from_slice(&0u32.to_le_bytes());
    out.extend_from_slice(&0u32.to_le_bytes());
    for y in [1, 0] {
        for x in 0..2 {
            let [r, g, b] = pixels[y * 2 + x];
            out.extend_from_slice(&[b, g, r]);
        }
        out.extend_from_slice(&[0, 0]);
    }
    out
}

/// Shift-JIS `name` in a zero-padded field of `len` bytes (the names here are ASCII or
/// センター, written out).
fn field(name: &[u8], len: usize) -> Vec<u8> {
    let mut f = name.to_vec();
    f.resize(len, 0);
    f
}

/// センター (MMD's centre bone) in Shift-JIS.
const CENTRE_SJIS: &[u8] = &[0x83, 0x5A, 0x83, 0x93, 0x83, 0x5E, 0x81, 0x5B];

/// A PMD 1.0 model of our own, written as the format lays it out: one bone (センター), one
/// triangle skinned to it, one material textured with `golden_tex.bmp` and MMD's shared toon
/// ramp 1 (`toon01.bmp`), no IK, morphs or display frames, no extensions.
pub fn tiny_model_pmd() -> Vec<u8> {
    let mut out = b"Pmd".to_vec();
    out.extend_from_slice(&1.0f32.to_le_bytes());
    out.extend(field(b"golden", 20));
    out.extend(field(b"", 256));
    let f = |out: &mut Vec<u8>, v: &[f32]| v.iter().for_each(|x| out.extend_from_slice(&x.to_le_bytes()));
    out.extend_from_slice(&3u32.to_le_bytes()); // vertices, 38 bytes each
    for (pos, uv) in [([-1.0, 8.0, 0.0], [0.0, 1.0]), ([1.0, 8.0, 0.0], [1.0, 1.0]), ([0.0, 10.0, 0.0], [0.5, 0.0])] {
        f(&mut out, &pos);
        f(&mut out, &[0.0, 0.0, -1.0]);
        f(&mut out, &uv);
        out.extend_from_slice(&0u16.to_le_bytes()); // bone 0
        out.extend_from_slice(&0u16.to_le_bytes()); // bone 1
        out.push(100); // weight of bone 0, percent
        out.push(0); // edge on
    }
    out.extend_from_slice(&3u32.to_le_bytes()); // triangle indices
    for i in [0u16, 1, 2] {
        out.extend_from_slice(&i.to_le_bytes());
    }
    out.extend_from_slice(&1u32.to_le_bytes()); // materials, 70 bytes each
    f(&mut out, &[0.8, 0.8, 0.8, 1.0, 5.0, 0.1, 0.1, 0.1, 0.4, 0.4, 0.4]); // diffuse RGBA, specular power, specular, ambient
    out.push(0); // toon index 0: toon01.bmp
    out.push(1); // edge
    out.extend_from_slice(&3u32.to_le_bytes()); // its indices
    out.extend(field(b"golden_tex.bmp", 20));
    out.extend_from_slice(&1u16.to_le_bytes()); // bones, 39 bytes each
    out.extend(field(CENTRE_SJIS, 20));
    out.extend_from_slice(&0xFFFFu16.to_le_bytes()); // no parent
    out.extend_from_slice(&0u16.to_le_bytes()); // no tail
    out.push(1); // rotates and moves
    out.extend_from_slice(&0u16.to_le_bytes()); // IK field
    f(&mut out, &[0.0, 8.0, 0.0]);
    out.extend_from_slice(&0u16.to_le_bytes()); // IK chains
    out.extend_from_slice(&0u16.to_le_bytes()); // morphs
    out.push(0); // morph display list
    out.push(0); // bone display frame names
    out.extend_from_slice(&0u32.to_le_bytes()); // bone display list
    out
}

/// A dance VMD of our own for the model above: two keys of センター (frame 0 at rest, frame 30
/// one unit up and turned a little about Y), linear, 111 bytes a key.
pub fn tiny_dance_vmd() -> Vec<u8> {
    let mut out = field(b"Vocaloid Motion Data 0002", 30);
    out.extend(field(b"golden", 20));
    out.extend_from_slice(&2u32.to_le_bytes()); // bone keys
    let (s, c) = (0.2f32.sin(), 0.2f32.cos());
    for (frame, pos, rot) in [(0u32, [0.0f32, 0.0, 0.0], [0.0f32, 0.0, 0.0, 1.0]), (30, [0.0, 1.0, 0.0], [0.0, s, 0.0, c])] {
        out.extend(field(CENTRE_SJIS, 15));
        out.extend_from_slice(&frame.to_le_bytes());
        pos.iter().chain(&rot).for_each(|x| out.extend_from_slice(&x.to_le_bytes()));
        for _ in 0..4 {
            out.extend_from_slice(&[20, 20, 20, 20, 20, 20, 20, 20, 107, 107, 107, 107, 107, 107, 107, 107]); // linear
        }
    }
    out.extend_from_slice(&0u32.to_le_bytes()); // morph keys
    out.extend_from_slice(&0u32.to_le_bytes()); // camera keys
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
    // Schema 7: a VMD dance posed on an MMD model kept with the files it draws with (its texture
    // and MMD's shared toon ramp 1), one blob each.
    let drawn = vec![("golden_tex.bmp".to_string(), "golden/golden_tex.bmp".to_string(), tiny_bmp(GOLDEN_TEXTURE)), ("toon01.bmp".to_string(), "golden/toon01.bmp".to_string(), tiny_bmp(GOLDEN_TOON))];
    let model = project::GivenModel { file_name: "golden/golden.pmd", bytes: &tiny_model_pmd(), drawn: &drawn };
    p.add_source_with_model("golden_dance.vmd", &tiny_dance_vmd(), ImportOptions::default(), model).expect("a VMD dance on its model");
    // ... and a Generate under *my moves* that leaves bars built-in, each keeping why: the
    // person's moves are four bars of the engine's own dance (written as a BVH), and a join goal
    // no join of theirs meets opens bars to built-in moves ("no move of yours joins smoothly").
    let dance = p.render_dance(&RenderOptions::default()).expect("render");
    let per_bar = dance.frame_count() / p.doc().dance.bars.len().max(1);
    let mine = odori_core::export::bvh::bvh(&dance.slice(0, 4 * per_bar + 1, "golden mine")).expect("bvh");
    p.add_source("golden_mine.bvh", &mine, ImportOptions::default()).expect("a humanoid BVH");
    p.set_moves_source(MovesSource::Mine).expect("my moves");
    p.generate_with(&GenerateOptions { join_jump_goal: 0.05, ..GenerateOptions::default() }).expect("generate");
    let why = p.builtin_why().iter().filter(|w| w.is_some()).count();
    assert!(why > 0, "no bar is built-in with a why: {:?}", p.doc().dance.bars.iter().map(|b| b.builtin_why).collect::<Vec<_>>());
    let bytes = project::save(&p).expect("save");
    std::fs::write(&out, &bytes).unwrap_or_else(|e| panic!("{out}: {e}"));
    println!("{out}: {} bytes, {} bars ({why} built-in with a why), {} undo steps", bytes.len(), p.doc().dance.bars.len(), p.undo_history().len());
}
