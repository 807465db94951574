#![no_main]
//! libFuzzer target: [`entries::import_pmx`] on arbitrary bytes (the PMX/PMD model reader; see fuzz/entries.rs).

#[path = "../entries.rs"]
mod entries;

libfuzzer_sys::fuzz_target!(|data: &[u8]| entries::import_pmx(data));
