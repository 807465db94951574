#![no_main]
//! libFuzzer target: [`entries::project_open`] on arbitrary bytes (see fuzz/entries.rs).

#[path = "../entries.rs"]
mod entries;

libfuzzer_sys::fuzz_target!(|data: &[u8]| entries::project_open(data));
