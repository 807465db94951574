//! The MMD model a project's VMD dance is posed on (issue 28): the PMX/PMD file as given
//! (schema 4) and, from schema 7, the files it is drawn with — its textures and the MMD shared
//! toon ramps (`toonNN.bmp`) it uses — each a blob by hash like every kept file, so two dances on
//! one model (or a texture two models share) keep the bytes once. A reopened project then poses
//! the dance on its model and draws it textured on any machine, without the model in the
//! library. Like every MMD file they stay with the person: in the `.odori` file and the browser's
//! store, never in a share link (a link holds built-in moves only).

use std::sync::Arc;

use serde::{Deserialize, Serialize};

use super::{derive, BlobHash, BlobStore, Project, ProjectError, Source, SourceId, SourceReport};
use crate::import::{ImportError, ImportOptions};

/// A PMX/PMD model file a VMD dance is posed on, as given, with the files it is drawn with.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct ModelFile {
    pub file_name: String,
    pub blob: BlobHash,
    /// The textures and shared toon ramps the model draws with, as given with it (schema 7;
    /// absent when none: drawn in its materials' colours).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub textures: Vec<ModelTexture>,
}

/// One file a model draws with.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct ModelTexture {
    /// The path the model names it by (`toonNN.bmp` for a shared toon ramp): what its materials
    /// find it by.
    pub name: String,
    /// The file's path as it was given (its extension tells the decoder the format).
    pub path: String,
    pub blob: BlobHash,
}

impl ModelFile {
    /// The kept files as the mesh maker takes them (name, path, bytes); a file whose bytes are
    /// missing is left out (its materials are drawn in their colour).
    pub fn drawn_files(&self, blobs: &BlobStore) -> Vec<(String, String, Vec<u8>)> {
        self.textures.iter().filter_map(|t| blobs.get(&t.blob).map(|b| (t.name.clone(), t.path.clone(), b.to_vec()))).collect()
    }
}

/// A model given with a VMD dance ([`Project::add_source_with_model`]): its file name and bytes,
/// and the files it draws with (name the model gives, path, bytes), as
/// [`crate::mmd::files::ImportedModel::drawn_files`] lists them.
#[derive(Clone, Copy, Debug)]
pub struct GivenModel<'a> {
    pub file_name: &'a str,
    pub bytes: &'a [u8],
    pub drawn: &'a [(String, String, Vec<u8>)],
}

/// A kept model as the derived state imports it.
pub(crate) struct ModelIn<'a> {
    pub file: &'a str,
    pub hash: &'a BlobHash,
    /// `None`: named but missing from the project.
    pub bytes: Option<&'a [u8]>,
    pub drawn: Drawn<'a>,
}

/// The files a model draws with: given with it, or kept in the project (read only when the
/// import is not cached, so an import found again copies and hashes nothing).
pub(crate) enum Drawn<'a> {
    Given(&'a [(String, String, Vec<u8>)]),
    Kept(&'a ModelFile, &'a BlobStore),
}

impl Drawn<'_> {
    /// What the import is cached by: each file's name and hash (those present).
    pub fn key(&self) -> String {
        match self {
            Drawn::Given(files) => files.iter().map(|(n, _, b)| format!("{n}={}", BlobHash::of(b))).collect::<Vec<_>>().join(","),
            Drawn::Kept(m, blobs) => m.textures.iter().filter(|t| blobs.contains(&t.blob)).map(|t| format!("{}={}", t.name, t.blob)).collect::<Vec<_>>().join(","),
        }
    }

    pub fn files(&self) -> Vec<(String, String, Vec<u8>)> {
        match self {
            Drawn::Given(files) => files.to_vec(),
            Drawn::Kept(m, blobs) => m.drawn_files(blobs),
        }
    }
}

impl Project {
    /// [`Project::add_source`] of a VMD dance posed on an MMD model file (`model`: its name and
    /// bytes, kept in the project with the dance; `None`: the standard MMD skeleton). The model's
    /// textures are not kept: see [`Project::add_source_with_model`]. A model with any other file,
    /// or one that cannot be read, is a typed error and nothing changes.
    pub fn add_source_on(&mut self, file_name: &str, bytes: &[u8], options: ImportOptions, model: Option<(&str, &[u8])>) -> Result<SourceReport, ProjectError> {
        let given = model.map(|(file_name, bytes)| GivenModel { file_name, bytes, drawn: &[] });
        self.add_source_model(file_name, bytes, options, given)
    }

    /// [`Project::add_source`] of a VMD dance posed on `model` and drawn with the files given
    /// with it (its textures and shared toon ramps), all kept in the project with the dance by
    /// hash: a reopened project draws the dance textured without the model in the library. A
    /// model with any other file, or one that cannot be read, is a typed error and nothing
    /// changes; a texture that does not decode is a warning and its materials keep their colour.
    pub fn add_source_with_model(&mut self, file_name: &str, bytes: &[u8], options: ImportOptions, model: GivenModel<'_>) -> Result<SourceReport, ProjectError> {
        self.add_source_model(file_name, bytes, options, Some(model))
    }

    fn add_source_model(&mut self, file_name: &str, bytes: &[u8], options: ImportOptions, model: Option<GivenModel<'_>>) -> Result<SourceReport, ProjectError> {
        let hash = BlobHash::of(bytes);
        let imported = match model {
            None => self.derived.import(&hash, file_name, bytes, &options)?,
            Some(m) => {
                if !(bytes.starts_with(crate::import::vmd::MAGIC_V1) || bytes.starts_with(crate::import::vmd::MAGIC_V2)) {
                    return Err(ImportError::Invalid { file: file_name.to_string(), message: format!("a model ({}) goes only with a VMD dance", m.file_name) }.into());
                }
                let model_hash = BlobHash::of(m.bytes);
                let on = ModelIn { file: m.file_name, hash: &model_hash, bytes: Some(m.bytes), drawn: Drawn::Given(m.drawn) };
                self.derived.import_on(&hash, file_name, bytes, &options, Some(on))?
            }
        };
        let id = SourceId(self.doc.next_source);
        let clips = derive::clip_infos(id, &imported);
        let warnings = imported.warnings.clone();
        let blob = self.blobs.put(bytes);
        let model = model.map(|m| {
            let mut textures: Vec<ModelTexture> = Vec::with_capacity(m.drawn.len());
            for (name, path, b) in m.drawn {
                // Once per name the model finds it by (a file given twice is kept once).
                if !textures.iter().any(|t| t.name == *name) {
                    textures.push(ModelTexture { name: name.clone(), path: path.clone(), blob: self.blobs.put(b) });
                }
            }
            ModelFile { file_name: m.file_name.to_string(), blob: self.blobs.put(m.bytes), textures }
        });
        let mut doc = self.doc.clone();
        doc.next_source += 1;
        doc.sources.push(Source { id, file_name: file_name.to_string(), blob, options, cut_tempos_bpm: Vec::new(), model });
        self.commit(doc);
        // Report each clip as the dance library has it now (its cut, or why it is refused).
        let d = self.derived();
        let clips = clips.into_iter().map(|c| d.clip(c.clip).cloned().unwrap_or(c)).collect();
        Ok(SourceReport { id, clips, warnings })
    }

    /// The MMD model kept with a VMD source ([`Project::add_source_on`]), read from its bytes:
    /// `Ok(None)` when the source has no model or the project lacks the model's bytes (then the
    /// dance is posed on the standard skeleton). A host links the dance to the model by its name
    /// (drawing with the model's mesh, `exportVmd`'s default model). A model file that does not
    /// read is the reader's error ([`ImportError::Mmd`]).
    pub fn source_model(&self, source: SourceId) -> Result<Option<crate::import::mmd_model::MmdModel>, ProjectError> {
        let src = self.doc.source(source).ok_or(ProjectError::NoSuchSource { source_id: source.0 })?;
        let Some(m) = &src.model else { return Ok(None) };
        let Some(bytes) = self.blobs.get(&m.blob) else { return Ok(None) };
        let model = crate::import::mmd_model::read_model(&m.file_name, bytes).map_err(|e| {
            let e = crate::mmd::files::MmdFilesError::from(e);
            ImportError::Mmd { file: e.file().to_string(), kind: e.kind(), message: e.to_string() }
        })?;
        Ok(Some(model))
    }

    /// The files kept with a VMD source's model (name the model gives, path, bytes), those whose
    /// bytes the project holds; empty for a source without a model.
    pub fn source_model_files(&self, source: SourceId) -> Vec<(String, String, Arc<[u8]>)> {
        let Some(m) = self.doc.source(source).and_then(|s| s.model.as_ref()) else { return Vec::new() };
        m.textures.iter().filter_map(|t| self.blobs.get(&t.blob).map(|b| (t.name.clone(), t.path.clone(), b.clone()))).collect()
    }
}
