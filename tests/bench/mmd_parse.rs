//! Parse times of the MikuMikuDance readers on the real files (issue 28's speed goals are for
//! wasm: WAVEFILE imported with IK solved < 150 ms, Gene < 300 ms; this measures the parsing
//! share natively): the WAVEFILE dance VMD (14,160 bone keys), its write back, the sampling of
//! all 140 of its tracks at every frame, the Gene PMX (28,646 vertices) and miku_v2 PMD.
//! Best and median of N runs each, with the file's size. `cargo bench -p odori-tests --bench mmd_parse`.

use std::time::Instant;

use odori_core::export;
use odori_core::import::{mmd_model, vmd};
use odori_tests::read;

fn time<T>(runs: usize, mut f: impl FnMut() -> T) -> (f64, f64) {
    let mut ms: Vec<f64> = (0..runs)
        .map(|_| {
            let t = Instant::now();
            std::hint::black_box(f());
            t.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    ms.sort_by(f64::total_cmp);
    (ms[0], ms[runs / 2])
}

fn row(what: &str, bytes: usize, (best, median): (f64, f64)) {
    println!("{what:<44} {:>9.1} KB {best:>9.2} ms {median:>9.2} ms", bytes as f64 / 1024.0);
}

fn main() {
    const RUNS: usize = 15;
    println!("{:<44} {:>12} {:>12} {:>12}", "mmd_parse (native)", "size", "best", "median");
    let wave = read("mmd/motion/wavefile_v2.vmd");
    row("wavefile_v2.vmd read (14,160 bone keys)", wave.len(), time(RUNS, || vmd::read("w.vmd", &wave).unwrap()));
    let v = vmd::read("w.vmd", &wave).unwrap();
    row("wavefile_v2.vmd bone_tracks (140 tracks)", wave.len(), time(RUNS, || v.bone_tracks()));
    let tracks: Vec<odori_core::mmd::BoneSampler> = v
        .bone_tracks()
        .iter()
        .map(|t| odori_core::mmd::BoneSampler::new(&t.keys.iter().map(odori_core::mmd::VmdBoneKey::from_vmd_key).collect::<Vec<_>>()))
        .collect();
    let last = v.last_frame();
    row(
        &format!("wavefile sample 140 tracks x {} frames", last + 1),
        wave.len(),
        time(RUNS, || {
            let mut acc = 0.0f32;
            for f in 0..=last {
                for t in &tracks {
                    acc += t.sample(f as f32).1.x;
                }
            }
            acc
        }),
    );
    let written = export::vmd::write("w.vmd", &v).unwrap();
    row("wavefile_v2.vmd write", written.len(), time(RUNS, || export::vmd::write("w.vmd", &v).unwrap()));
    for rel in ["mmd/gene/Gene_light.pmx", "mmd/miku_v2/miku_v2.pmd"] {
        let b = read(rel);
        let m = mmd_model::read_model(rel, &b).unwrap();
        let name = rel.rsplit('/').next().unwrap_or(rel);
        row(&format!("{name} read ({} vertices, {} bones)", m.vertices.len(), m.bones.len()), b.len(), time(RUNS, || mmd_model::read_model(rel, &b).unwrap()));
    }
}
