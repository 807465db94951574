//! Writes the product's exports of the real characters to a directory, for looking at them in
//! other tools (Blender, three.js editor, the Khronos validator's web page):
//! `cargo run -p odori-tests --example export_samples -- OUT_DIR`. Files: the built-in demo
//! dance on the built-in body (GLB, BVH), Xbot and RobotExpressive with their animations on
//! their own mesh (GLB).

use odori_core::canon::builtin::demo_clip;
use odori_core::export::{bvh::bvh, gltf::{glb, GlbOptions}};
use odori_core::import::{import_bytes, ImportOptions};
use odori_core::library::body::builtin_body;
use odori_tests::read;

fn main() {
    let out = std::path::PathBuf::from(std::env::args().nth(1).unwrap_or_else(|| "export-samples".into()));
    std::fs::create_dir_all(&out).expect("create the output directory");
    let demo = demo_clip();
    let body = builtin_body(&demo.skeleton);
    let write = |name: &str, bytes: Vec<u8>| {
        std::fs::write(out.join(name), &bytes).expect("write");
        println!("{name}: {} bytes", bytes.len());
    };
    write("builtin.glb", glb(&demo.skeleton, &[&demo], &GlbOptions { mesh: Some(&body) }).expect("export"));
    write("builtin.bvh", bvh(&demo).expect("export"));
    for (file, name) in [("gltf/Xbot.glb", "xbot.glb"), ("gltf/RobotExpressive.glb", "robot.glb")] {
        let src = import_bytes(file, &read(file), &ImportOptions::default()).unwrap_or_else(|e| panic!("{e}"));
        let clips: Vec<&odori_core::Clip> = src.clips.iter().collect();
        write(name, glb(&src.skeleton, &clips, &GlbOptions { mesh: src.mesh.as_ref() }).expect("export"));
    }
}
