#![no_main]
//! libFuzzer target: [`entries::import_files`] on arbitrary bytes (MMD files as a set: the zip path, the VMD posed on a rig; see fuzz/entries.rs).

#[path = "../entries.rs"]
mod entries;

libfuzzer_sys::fuzz_target!(|data: &[u8]| entries::import_files(data));
