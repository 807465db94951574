#![no_main]
//! libFuzzer target: [`entries::music_envelope`] on arbitrary bytes (see fuzz/entries.rs).

#[path = "../entries.rs"]
mod entries;

libfuzzer_sys::fuzz_target!(|data: &[u8]| entries::music_envelope(data));
