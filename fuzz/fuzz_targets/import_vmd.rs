#![no_main]
//! libFuzzer target: [`entries::import_vmd`] on arbitrary bytes (the VMD reader; see fuzz/entries.rs).

#[path = "../entries.rs"]
mod entries;

libfuzzer_sys::fuzz_target!(|data: &[u8]| entries::import_vmd(data));
