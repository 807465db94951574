//! Importers: BVH and glTF/GLB, from bytes (no filesystem), into [`Clip`]s on their own
//! skeleton, plus the skinned meshes a glTF character carries for rendering.
//!
//! Every importer returns a typed [`ImportError`] naming the file and, where it can, the line,
//! joint or accessor at fault; no input makes it panic.
//!
//! The rule at this boundary: options are validated before a byte is read ([`ImportOptions::validate`],
//! out-of-range values are refused with the value, never clamped), and a file that declares more
//! data than a browser tab can hold (a BVH claiming 10⁹ frames, a 1 KB GLB whose accessor claims
//! two billion elements) is refused with [`ImportError::TooLarge`] *before* anything is allocated
//! for it ([`MAX_SAMPLES`], [`MAX_VIEWLESS_ACCESSOR_ELEMENTS`]). What is read but doubtful (a figure
//! of implausible height for its unit guess) is kept and reported in [`Imported::warnings`].

pub mod bvh;
pub mod gltf;
pub mod mmd_bytes;
pub mod mmd_model;
pub mod mmd_text;
pub mod pmd;
pub mod pmx;
pub mod skinned_bounds;
pub mod vmd;

use std::sync::Arc;

use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::clip::Clip;
use crate::canon::humanoid::{HumanoidMap, HumanoidStatus};
use crate::skeleton::Skeleton;

pub use self::gltf::{MeshPart, MeshTexture, Sampler, SkinnedMesh, ToonLook, UvTransform};
pub use self::skinned_bounds::SkinnedBounds;

/// What the person (or the caller) can say about a file before it is read.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct ImportOptions {
    /// Play the file at this frame rate instead of the one its header states (the CMU salsa
    /// BVH files say 120 fps but were recorded at 60). `None`: trust the file.
    pub fps_override: Option<f32>,
    /// Metres per file unit for BVH. `None`: guess from the rig's joint naming and bone
    /// lengths against human proportions (see [`bvh::units::guess`]).
    pub unit_scale: Option<f32>,
    /// Rate glTF animations are resampled to, frames per second. Default 30.
    pub gltf_fps: f32,
    /// VMD only: the motion frame that is song time 0 (WAVEFILE's is 160): the clip starts
    /// there. Left out of a saved project when `None`, so older projects save unchanged.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub song_offset_frames: Option<u32>,
}

impl Default for ImportOptions {
    fn default() -> Self {
        Self { fps_override: None, unit_scale: None, gltf_fps: 30.0, song_offset_frames: None }
    }
}

/// Valid range of [`ImportOptions::unit_scale`], metres per file unit: from tenths of a
/// millimetre to ten metres. Outside it no motion file is meaningful (0 collapses the figure,
/// a negative scale mirrors it, 1e30 overflows).
pub const UNIT_SCALE_RANGE: std::ops::RangeInclusive<f32> = 1e-4..=10.0;
/// Valid range of frame rates (`fps_override`, `gltf_fps`), frames per second.
pub const FPS_RANGE: std::ops::RangeInclusive<f32> = 0.1..=1000.0;
/// Most joint-rotation samples (frames × joints) one clip may hold: 2²⁴ quaternions, 256 MB.
/// A file declaring more is refused before allocation.
pub const MAX_SAMPLES: usize = 1 << 24;
/// Most elements an accessor without a buffer view (all zeros, or sparse) may declare. With a
/// buffer view the accessor is bounded by the bytes actually present; without one a 1 KB file
/// could claim billions.
pub const MAX_VIEWLESS_ACCESSOR_ELEMENTS: usize = 1 << 22;

impl ImportOptions {
    /// Checks every option against its documented range; the error names the option and value.
    pub fn validate(&self, file: &str) -> Result<(), ImportError> {
        let bad = |option: &'static str, value: f32, expected: String| ImportError::BadOption { file: file.to_string(), option, value, expected };
        if let Some(s) = self.unit_scale.filter(|s| !UNIT_SCALE_RANGE.contains(s)) {
            return Err(bad("unitScale", s, format!("metres per file unit, {} to {}", UNIT_SCALE_RANGE.start(), UNIT_SCALE_RANGE.end())));
        }
        if let Some(f) = self.fps_override.filter(|f| !FPS_RANGE.contains(f)) {
            return Err(bad("fpsOverride", f, format!("frames per second, {} to {}", FPS_RANGE.start(), FPS_RANGE.end())));
        }
        if !FPS_RANGE.contains(&self.gltf_fps) {
            return Err(bad("gltfFps", self.gltf_fps, format!("frames per second, {} to {}", FPS_RANGE.start(), FPS_RANGE.end())));
        }
        Ok(())
    }
}

/// A number as a person reads it: 1e30 rather than thirty-one digits, 0.01 as it is.
pub(crate) fn readable(v: f32) -> String {
    if v != 0.0 && v.is_finite() && !(1e-3..1e6).contains(&v.abs()) {
        format!("{v:e}")
    } else {
        v.to_string()
    }
}

/// The file formats the engine reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Format {
    Bvh,
    Gltf,
    /// MikuMikuDance's VMD motion, posed on the standard MMD skeleton ([`crate::mmd::files::import_vmd_source`]).
    Vmd,
}

impl Format {
    /// Every format [`import_bytes`] reads, each told from the others by its first bytes: the
    /// one list [`sniff`] tries and the "not a … file" error names ([`import_format_names!`]
    /// spells it out for compile-time text, a test holds the two equal).
    pub const ALL: [Format; 3] = [Format::Bvh, Format::Gltf, Format::Vmd];

    /// The names a person knows the format's files by.
    pub fn names(self) -> &'static [&'static str] {
        match self {
            Format::Bvh => &["BVH"],
            Format::Gltf => &["glTF", "GLB"],
            Format::Vmd => &["VMD"],
        }
    }

    /// The file extension (lower case, no dot) of each of [`Format::names`], in the same order:
    /// what a page's file chooser takes the format's files by (the web crate's
    /// `importFormats()`; the importer itself sniffs the bytes).
    pub fn extensions(self) -> &'static [&'static str] {
        match self {
            Format::Bvh => &["bvh"],
            Format::Gltf => &["gltf", "glb"],
            Format::Vmd => &["vmd"],
        }
    }

    /// Whether `bytes` start as this format's files do.
    fn starts(self, bytes: &[u8]) -> bool {
        // Text formats may open with a byte-order mark or blank lines.
        let text_start = || -> Vec<u8> {
            bytes.iter().copied().skip_while(|b| b.is_ascii_whitespace() || *b == 0xEF || *b == 0xBB || *b == 0xBF).take(16).collect()
        };
        match self {
            Format::Gltf => bytes.starts_with(b"glTF") || text_start().starts_with(b"{"),
            Format::Vmd => bytes.starts_with(vmd::MAGIC_V1) || bytes.starts_with(vmd::MAGIC_V2),
            Format::Bvh => text_start().starts_with(b"HIERARCHY"),
        }
    }
}

/// The names of [`Format::ALL`] as one literal ("BVH, glTF, GLB or VMD"), for text that must be
/// known at compile time: the `unknown-format` error and the JS error kinds' documentation.
#[macro_export]
macro_rules! import_format_names {
    () => {
        "BVH, glTF, GLB or VMD"
    };
}

/// Everything one file gave.
#[derive(Clone, Debug)]
pub struct Imported {
    pub format: Format,
    pub skeleton: Arc<Skeleton>,
    /// One clip per animation (BVH: one). A glTF file without animations gives one
    /// single-frame clip in its rest pose.
    pub clips: Vec<Clip>,
    /// Drawable character parts (glTF only).
    pub mesh: Option<SkinnedMesh>,
    pub humanoid: HumanoidMap,
    pub status: HumanoidStatus,
    /// Things that were read but not used (morph weights, textures, ...).
    pub warnings: Vec<String>,
}

#[derive(Debug, Error, Clone, PartialEq)]
pub enum ImportError {
    #[error("{file}: the file is empty")]
    Empty { file: String },
    #[error("{file}: not a {} file (it starts with {start:?})", crate::import_format_names!())]
    UnknownFormat { file: String, start: String },
    #[error("{file}:{line}:{column}: {message}")]
    Bvh { file: String, line: usize, column: usize, message: String },
    #[error("{file}: invalid glTF: {message}")]
    Gltf { file: String, message: String },
    #[error("{file}: {message}")]
    Unsupported { file: String, message: String },
    #[error("{file}: {message}")]
    Invalid { file: String, message: String },
    #[error("{file}: import option {option} = {} is out of range (expected {expected})", readable(*.value))]
    BadOption { file: String, option: &'static str, value: f32, expected: String },
    #[error("{file}: {what} is more than this tab can hold (limit {limit}); the file was not read")]
    TooLarge { file: String, what: String, limit: String },
    /// A VMD that cannot be read or posed: `kind` is [`crate::mmd::files::MmdFilesError::kind`]
    /// ("mmd-truncated", "mmd-no-matching-bones" …), `message` names the file.
    #[error("{message}")]
    Mmd { file: String, kind: &'static str, message: String },
}

impl ImportError {
    /// A short machine-readable kind, stable for the JS API ("empty", "bvh-syntax", ...).
    pub fn kind(&self) -> &'static str {
        match self {
            ImportError::Empty { .. } => "empty",
            ImportError::UnknownFormat { .. } => "unknown-format",
            ImportError::Bvh { .. } => "bvh",
            ImportError::Gltf { .. } => "gltf",
            ImportError::Unsupported { .. } => "unsupported",
            ImportError::Invalid { .. } => "invalid",
            ImportError::BadOption { .. } => "bad-argument",
            ImportError::TooLarge { .. } => "too-large",
            ImportError::Mmd { kind, .. } => kind,
        }
    }
}

/// Which format the bytes are, from their first bytes (not the file name, which may lie).
pub fn sniff(bytes: &[u8]) -> Option<Format> {
    Format::ALL.into_iter().find(|f| f.starts(bytes))
}

/// Reads a motion file of any supported format.
pub fn import_bytes(file: &str, bytes: &[u8], options: &ImportOptions) -> Result<Imported, ImportError> {
    options.validate(file)?;
    if bytes.iter().all(|b| b.is_ascii_whitespace()) {
        return Err(ImportError::Empty { file: file.to_string() });
    }
    match sniff(bytes) {
        Some(Format::Bvh) => bvh::import(file, bytes, options),
        Some(Format::Gltf) => gltf::import(file, bytes, options),
        #[cfg(feature = "vmd-source")]
        Some(Format::Vmd) => crate::mmd::files::import_vmd_source(file, bytes, options.song_offset_frames),
        #[cfg(not(feature = "vmd-source"))]
        Some(Format::Vmd) => Err(ImportError::Unsupported { file: file.to_string(), message: "a VMD dance needs the full engine (odori), not the player".into() }),
        None => {
            let start: String = bytes
                .iter()
                .take(12)
                .map(|&b| if b.is_ascii_graphic() || b == b' ' { b as char } else { '.' })
                .collect();
            Err(ImportError::UnknownFormat { file: file.to_string(), start })
        }
    }
}

/// Fills in the humanoid mapping and the clip validation shared by every importer.
pub(crate) fn finish(
    format: Format,
    file: &str,
    skeleton: Arc<Skeleton>,
    clips: Vec<Clip>,
    mesh: Option<SkinnedMesh>,
    warnings: Vec<String>,
) -> Result<Imported, ImportError> {
    for c in &clips {
        c.validate().map_err(|e| ImportError::Invalid { file: file.to_string(), message: e.to_string() })?;
    }
    let humanoid = HumanoidMap::from_skeleton(&skeleton);
    let status = humanoid.status(&skeleton, clips.first());
    Ok(Imported { format, skeleton, clips, mesh, humanoid, status, warnings })
}

/// File name without directories or extension ("salsa_01" from "a/b/salsa_01.bvh").
pub fn stem(file: &str) -> &str {
    let base = file.rsplit(['/', '\\']).next().unwrap_or(file);
    match base.rfind('.') {
        Some(i) if i > 0 => &base[..i],
        _ => base,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The literal the error and the JS kinds' docs print names exactly the formats sniffing
    /// tells apart, so neither can drift from what the importer reads.
    #[test]
    fn the_unknown_format_text_names_every_format_sniff_reads() {
        let names: Vec<&str> = Format::ALL.iter().flat_map(|f| f.names().iter().copied()).collect();
        let (last, rest) = names.split_last().expect("formats");
        // One extension per name, in the same order.
        for f in Format::ALL {
            assert_eq!(f.extensions().len(), f.names().len(), "{f:?}");
        }
        assert_eq!(crate::import_format_names!(), format!("{} or {last}", rest.join(", ")));
        // Each format's own first bytes are sniffed as it, and only as it.
        let starts: [(&[u8], Format); 5] = [
            (b"HIERARCHY\nROOT hip", Format::Bvh),
            (b"\xEF\xBB\xBF\n HIERARCHY", Format::Bvh),
            (b"glTF\x02\0\0\0", Format::Gltf),
            (b"  {\"asset\":{}}", Format::Gltf),
            (vmd::MAGIC_V2, Format::Vmd),
        ];
        for (bytes, format) in starts {
            assert_eq!(sniff(bytes), Some(format), "{bytes:?}");
            assert_eq!(Format::ALL.iter().filter(|f| f.starts(bytes)).count(), 1, "{bytes:?}");
        }
        let e = import_bytes("noise.bin", &[1, 2, 3, 4], &ImportOptions::default()).unwrap_err();
        assert_eq!(e.to_string(), "noise.bin: not a BVH, glTF, GLB or VMD file (it starts with \"....\")");
    }
}
