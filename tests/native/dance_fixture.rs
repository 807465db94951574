//! Same behaviour, bit for bit (issue 27's acceptance): the dances the engine generates on every
//! song in ../shared/data/music, the drum take and three demo pieces, over the built-in moves
//! plus the shared salsa and Indian clips, at the default settings, at ρ = 0.9 and at music
//! weight 0, equal those recorded in `tests/golden/dances.json` before the core was
//! restructured (`cargo run -p odori-tests --example make_golden_dances -- OUT`; what is
//! recorded: `dance_fixture_common.rs`). Each bar's move is compared by its stable key,
//! exactly; the rendered dance's joint positions at 10 times within 1e-5 m.
//!
//! Why 1e-5 m: a restructuring may reorder floating-point operations (one forward kinematics
//! routine in place of another that associates its products differently), which moves a joint
//! by a few f32 ulps per joint of the chain: about 1e-7 m at a metre, under 1e-6 m over the
//! longest chain. 1e-5 m (a hundredth of a millimetre) is ten times that and far below any
//! change of behaviour: another move, another join or a shifted time moves joints by
//! centimetres. The golden file's numbers are f32 written in their shortest exact form, so an
//! unchanged engine compares equal.

#[path = "dance_fixture_common.rs"]
mod dance_fixture_common;

use serde_json::Value;

const GOLDEN: &str = "golden/dances.json";
const TOLERANCE_M: f64 = 1e-5;

#[test]
fn generated_dances_equal_the_recorded_ones() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(GOLDEN);
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()));
    let golden: Value = serde_json::from_str(&text).expect("golden file is JSON");
    let t = std::time::Instant::now();
    let now = dance_fixture_common::all_dances();
    println!("{} pieces × {} settings generated and rendered in {:.1} s", now["pieces"].as_array().map_or(0, |p| p.len()), dance_fixture_common::SETTINGS.len(), t.elapsed().as_secs_f32());
    assert_eq!(now["sources"], golden["sources"], "the shared dance clips differ from those the fixture was recorded with");
    let (gp, np) = (golden["pieces"].as_array().expect("pieces"), now["pieces"].as_array().expect("pieces"));
    assert_eq!(np.len(), gp.len(), "number of pieces");
    let mut checked_positions = 0usize;
    for (g, n) in gp.iter().zip(np) {
        let piece = g["piece"].as_str().unwrap_or("?");
        assert_eq!(n["piece"], g["piece"], "pieces in another order");
        assert_eq!(n["bars"], g["bars"], "{piece}: number of bars");
        for (gd, nd) in g["dances"].as_array().expect("dances").iter().zip(n["dances"].as_array().expect("dances")) {
            let setting = gd["setting"].as_str().unwrap_or("?");
            let (gm, nm) = (gd["moves"].as_array().expect("moves"), nd["moves"].as_array().expect("moves"));
            assert_eq!(nm.len(), gm.len(), "{piece}, {setting}: number of bars danced");
            for (bar, (a, b)) in gm.iter().zip(nm).enumerate() {
                assert_eq!(b, a, "{piece}, {setting}: bar {bar} took another move");
            }
            assert_eq!(nd["fps"], gd["fps"], "{piece}, {setting}: frame rate");
            assert_eq!(nd["frames"], gd["frames"], "{piece}, {setting}: the dance's frames (its length)");
            let frames = gd["frames"].as_array().expect("frames");
            for (i, (gf, nf)) in gd["positions"].as_array().expect("positions").iter().zip(nd["positions"].as_array().expect("positions")).enumerate() {
                let (gj, nj) = (gf.as_array().expect("joints"), nf.as_array().expect("joints"));
                assert_eq!(nj.len(), gj.len(), "{piece}, {setting}: number of joints");
                for (joint, (a, b)) in gj.iter().zip(nj).enumerate() {
                    for axis in 0..3 {
                        let (x, y) = (a[axis].as_f64().expect("number"), b[axis].as_f64().expect("number"));
                        assert!(
                            (x - y).abs() <= TOLERANCE_M,
                            "{piece}, {setting}: joint {joint} at frame {} (time {i} of {}) axis {axis}: {y} m, recorded {x} m",
                            frames[i],
                            frames.len()
                        );
                        checked_positions += 1;
                    }
                }
            }
        }
    }
    println!("{checked_positions} coordinates within {TOLERANCE_M} m, every bar's move equal");
}
