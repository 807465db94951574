//! Raw wasm exports (no bindgen) for timing odori-core under a JavaScript engine: the song
//! analysis ([`music`]) and the choreography core ([`choreo`]). `run.sh` builds this crate for
//! wasm32-unknown-unknown (release; `--simd` adds `simd128`) and `run.mjs` times the exports
//! under Node. The native benches (`tests/bench/music_analysis.rs`, `tests/bench/choreo.rs`)
//! time the same inputs, so the figures compare directly.

pub mod choreo;
pub mod music;
