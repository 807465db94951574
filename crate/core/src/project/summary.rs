//! What the page shows of a project, as the engine states it: [`ProjectSummary`] names each fact
//! the page needs (the name, the sources, the song, tags, put-on clips, the body, texts, ρ,
//! the music weight, the camera motions and face tracks, the MMD files it keeps) and gives a key for each thing whose change the page must notice, so the
//! page never reads the document's schema ([`super::ProjectDoc`]). The whole document crosses to
//! the page only to be stored and given back unchanged (autosave and restore);
//! [`manifest_blob_hashes`] reads a stored manifest's blob list for the store's collection.

use serde::{Deserialize, Serialize};

use super::{BlobHash, ClipRef, FileError, Project, SourceId, TrackKind};
use crate::music::GridCorrection;

/// The project as the page shows it. See the module doc.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(rename_all = "camelCase")]
pub struct ProjectSummary {
    pub name: String,
    /// Every source in the document, by id.
    pub sources: Vec<SourceId>,
    pub song: Option<SongSummary>,
    /// Each tagged clip and its tags.
    pub tags: Vec<TagSummary>,
    /// The clips put on a character, in order.
    pub worn: Vec<WornSummary>,
    /// The imported character chosen, if any.
    pub character: Option<ClipRef>,
    /// Stick figures chosen (no character: the built-in body unless this is set).
    pub stick_figures: bool,
    pub texts: Vec<String>,
    /// The dance's ρ (0..=1).
    pub rho: f32,
    /// The dance's music weight.
    pub music_weight: f32,
    /// The camera motions (camera VMDs) imported, in order.
    pub cameras: Vec<CameraSummary>,
    /// The face (lip-sync) tracks imported, in order (same shape: file name and key).
    pub face_tracks: Vec<CameraSummary>,
    /// Every MikuMikuDance file the project keeps, by name: VMD dances, the models they are
    /// posed on and those models' textures (and shared toon ramps), camera and face tracks. What
    /// the page names when the project is saved: MMD creators' terms usually forbid passing
    /// these on, so they stay in the person's `.odori` file and never go in a share link.
    pub mmd_files: Vec<String>,
}

/// A camera motion as the page shows it.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(rename_all = "camelCase")]
pub struct CameraSummary {
    pub file_name: String,
    /// Equal for the same file imported the same way: the page shows the cameras again only when a key changes.
    pub key: String,
}

/// The song as the page shows it.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(rename_all = "camelCase")]
pub struct SongSummary {
    pub file_name: String,
    /// Its audio's hash (a blob of the project); none for the built-in demo song.
    pub audio: Option<BlobHash>,
    /// Equal for the same song analysed the same way (file, audio, envelope, options), whatever
    /// its grid corrections: the page loads a song again only when this changes.
    pub key: String,
    /// Every grid correction, in order (each one a `Song.correct` argument).
    pub corrections: Vec<GridCorrection>,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(rename_all = "camelCase")]
pub struct TagSummary {
    pub clip: ClipRef,
    pub tags: Vec<String>,
}

/// A clip put on a character.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(rename_all = "camelCase")]
pub struct WornSummary {
    /// Equal for the same recipe (character and motion): the page rebuilds the clip only when it changes.
    pub key: String,
    pub character: ClipRef,
}

impl Project {
    /// What the page shows of the project ([`ProjectSummary`]).
    pub fn summary(&self) -> ProjectSummary {
        let d = self.doc();
        let key = |v: serde_json::Result<String>| v.unwrap_or_default();
        ProjectSummary {
            name: d.name.clone(),
            sources: d.sources.iter().map(|s| s.id).collect(),
            song: d.song.as_ref().map(|s| SongSummary {
                file_name: s.file_name.clone(),
                audio: s.audio.clone(),
                key: key(serde_json::to_string(&(&s.file_name, &s.audio, &s.envelope, &s.options))),
                corrections: s.corrections.clone(),
            }),
            tags: d.tags.iter().map(|t| TagSummary { clip: t.clip, tags: t.tags.clone() }).collect(),
            worn: d.worn.iter().map(|w| WornSummary { key: key(serde_json::to_string(w)), character: w.character }).collect(),
            character: d.character,
            stick_figures: d.stick_figures,
            texts: d.texts.clone(),
            rho: d.dance.settings.rho,
            music_weight: d.dance.settings.fill.music_weight,
            cameras: d.tracks(TrackKind::Camera).map(|c| CameraSummary { file_name: c.file_name.clone(), key: key(serde_json::to_string(c)) }).collect(),
            face_tracks: d.tracks(TrackKind::Face).map(|f| CameraSummary { file_name: f.file_name.clone(), key: key(serde_json::to_string(f)) }).collect(),
            mmd_files: mmd_files(d),
        }
    }
}

/// [`ProjectSummary::mmd_files`]: each name once, in the document's order.
fn mmd_files(d: &super::ProjectDoc) -> Vec<String> {
    let mmd = |n: &str| [".vmd", ".pmx", ".pmd"].iter().any(|e| n.to_ascii_lowercase().ends_with(e));
    let mut out: Vec<String> = Vec::new();
    let mut add = |n: &str| {
        if !out.iter().any(|o| o == n) {
            out.push(n.to_string());
        }
    };
    for s in &d.sources {
        if mmd(&s.file_name) || s.model.is_some() {
            add(&s.file_name);
        }
        if let Some(m) = &s.model {
            add(&m.file_name);
            for t in &m.textures {
                add(&t.path);
            }
        }
    }
    for t in &d.mmd_tracks {
        add(&t.file_name);
    }
    out
}

/// The blobs a stored manifest (as [`super::file::manifest_json`] writes it) lists, without
/// reading the project it holds.
pub fn manifest_blob_hashes(manifest: &[u8]) -> Result<Vec<BlobHash>, FileError> {
    #[derive(Deserialize)]
    struct Blobs {
        #[serde(default)]
        blobs: std::collections::BTreeMap<BlobHash, serde::de::IgnoredAny>,
    }
    let b: Blobs = serde_json::from_slice(manifest).map_err(|e| FileError::BadManifest { line: e.line(), column: e.column(), message: e.to_string() })?;
    Ok(b.blobs.into_keys().collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn summary_states_the_document_and_its_keys() {
        let mut p = Project::new();
        p.set_name("a dance");
        p.set_texts(vec!["wave".into()]);
        let s = p.summary();
        assert_eq!(s.name, "a dance");
        assert_eq!(s.texts, vec!["wave".to_string()]);
        assert!(s.song.is_none() && s.sources.is_empty() && s.worn.is_empty());
        assert_eq!(s.rho, p.doc().dance.settings.rho);
        let hashes = manifest_blob_hashes(&super::super::file::manifest_json(&p)).unwrap();
        assert_eq!(hashes, p.referenced_blobs().into_iter().collect::<Vec<_>>());
        assert!(matches!(manifest_blob_hashes(b"{not json"), Err(FileError::BadManifest { .. })));
    }
}
