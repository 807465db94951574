#![no_main]
//! libFuzzer target: [`entries::import_bvh`] on arbitrary bytes (see fuzz/entries.rs).

#[path = "../entries.rs"]
mod entries;

libfuzzer_sys::fuzz_target!(|data: &[u8]| entries::import_bvh(data));
