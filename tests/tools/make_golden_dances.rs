//! Records the generated dances of the bit-for-bit fixture (`tests/golden/dances.json`, checked
//! by `tests/native/dance_fixture.rs`; what it holds: `tests/native/dance_fixture_common.rs`).
//! Run when a change of behaviour is meant (and say so in the commit), review the difference,
//! commit the file; the test run only reads it:
//!
//! ```sh
//! cargo run -p odori-tests --example make_golden_dances -- tests/golden/dances.json
//! ```

#[path = "../native/dance_fixture_common.rs"]
mod dance_fixture_common;

fn main() {
    let Some(out) = std::env::args().nth(1) else {
        eprintln!("usage: make_golden_dances OUT.json");
        std::process::exit(2);
    };
    let t = std::time::Instant::now();
    let dances = dance_fixture_common::all_dances();
    let text = serde_json::to_string(&dances).expect("JSON");
    std::fs::write(&out, text + "\n").unwrap_or_else(|e| panic!("cannot write {out}: {e}"));
    println!("wrote {out} in {:.1} s", t.elapsed().as_secs_f32());
}
