//! Prints what the importer makes of a motion file: `cargo run -p odori-core --example inspect FILE [fps]`.
use odori_core::canon::humanoid::Canon;
use odori_core::import::{import_bytes, ImportOptions};

fn main() {
    let mut args = std::env::args().skip(1);
    let path = args.next().expect("usage: inspect FILE [fps]");
    let fps_override = args.next().and_then(|s| s.parse().ok());
    let bytes = std::fs::read(&path).expect("readable file");
    match import_bytes(&path, &bytes, &ImportOptions { fps_override, ..Default::default() }) {
        Err(e) => println!("error [{}]: {e}", e.kind()),
        Ok(im) => {
            println!("{:?}, {} joints, status {:?}", im.format, im.skeleton.len(), im.status);
            for c in Canon::ALL {
                let j = im.humanoid.get(c);
                println!("  {:>14} -> {}", c.name(), j.map(|j| im.skeleton.joints[j].name.clone()).unwrap_or("-".into()));
            }
            for c in &im.clips {
                println!("  clip {:?}: {} frames at {} fps = {:.2} s", c.name, c.frame_count(), c.fps, c.duration_secs());
            }
            for w in &im.warnings {
                println!("  warning: {w}");
            }
        }
    }
}
