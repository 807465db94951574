#![no_main]
//! libFuzzer target: [`entries::text_parse`] on arbitrary bytes (see fuzz/entries.rs).

#[path = "../entries.rs"]
mod entries;

libfuzzer_sys::fuzz_target!(|data: &[u8]| entries::text_parse(data));
