//! Odori core: everything the dance engine computes, in pure Rust.
//!
//! This crate must stay free of web crates (wasm-bindgen, web-sys, js-sys, wgpu): it builds and
//! tests natively, and the same code is compiled to wasm by `crate/web`. Coordinates inside the
//! core are right-handed, Y up, in metres; angles are radians; time is in seconds or frames, and
//! names say which.

pub mod actions;
pub mod bars;
pub mod camera;
pub mod canon;
pub mod choreo;
pub mod clip;
pub mod export;
pub mod fmath;
pub mod history;
pub mod import;
pub mod library;
pub mod mmd;
pub mod motion;
pub mod music;
pub mod project;
pub mod search;
pub mod skeleton;
pub mod text;

pub use canon::humanoid::{Canon, HumanoidMap, HumanoidStatus};
pub use clip::{Clip, ClipError, TranslationTrack};

pub use import::{ImportError, ImportOptions, Imported};
pub use skeleton::{Joint, Skeleton};
