//! The project's face tracks (issue 28, `.odori` schema 6): lip-sync VMDs — files of morph
//! (face) keys, usually without bone keys — that MMD users load beside a dance onto the same
//! model. Like a camera VMD the file is kept as given (a blob by hash) with the motion frame
//! that is song time 0, and its keys are read again from those bytes
//! ([`Project::face_track`]), so the `.odori` file holds nothing but the person's file. What a
//! track means on a model (its weights at a song time over the dance's own face keys, its keys
//! in an exported VMD) is [`crate::mmd::face_track`].

use serde::{Deserialize, Serialize};

use super::{BlobHash, Project, ProjectError};
use crate::import::ImportError;
use crate::mmd::face_track::FaceTrack;

/// A lip-sync VMD the person imported, as given. Like every MMD file it stays with the person
/// (in the `.odori` file and the browser's store, never in a share link).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct FaceSource {
    pub file_name: String,
    /// The file's bytes, exactly as given.
    pub blob: BlobHash,
    /// The motion frame that is song time 0, when one was given (else frame 0 is).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub song_offset_frames: Option<u32>,
}

/// A VMD's morph keys as a face track, or why not (not a VMD, cut short, no morph keys).
pub(crate) fn face_track_of(file_name: &str, bytes: &[u8], song_offset_frames: Option<u32>) -> Result<FaceTrack, ProjectError> {
    use crate::mmd::files::MmdFilesError;
    let vmd = crate::import::vmd::read(file_name, bytes).map_err(|e| {
        let e = MmdFilesError::from(e);
        ProjectError::Import(ImportError::Mmd { file: file_name.to_string(), kind: e.kind(), message: e.to_string() })
    })?;
    FaceTrack::from_vmd(file_name, &vmd, song_offset_frames.unwrap_or(0)).ok_or_else(|| ProjectError::NotAFaceTrack {
        file_name: file_name.to_string(),
        bone_keys: vmd.bone_keys.len(),
        camera_keys: vmd.camera_keys.len(),
    })
}

impl Project {
    /// Keeps a lip-sync VMD's morph (face) keys as a face track of the project: its bytes as
    /// given, with `song_offset_frames` (the motion frame that is song time 0). A dance VMD's
    /// face keys are taken the same way (its bone keys are not used here). Returns the track as
    /// read. A file that is not a VMD, is cut short or has no morph keys is a typed error naming
    /// the file, and the project is unchanged. Undoable.
    pub fn add_face_track(&mut self, file_name: &str, bytes: &[u8], song_offset_frames: Option<u32>) -> Result<FaceTrack, ProjectError> {
        let track = face_track_of(file_name, bytes, song_offset_frames)?;
        let blob = self.blobs.put(bytes);
        let mut doc = self.doc.clone();
        doc.faces.push(FaceSource { file_name: file_name.to_string(), blob, song_offset_frames });
        self.commit(doc);
        Ok(track)
    }

    /// Removes face track `index` from the document. Undoable.
    pub fn remove_face_track(&mut self, index: usize) -> Result<(), ProjectError> {
        let count = self.doc.faces.len();
        if index >= count {
            return Err(ProjectError::NoSuchFaceTrack { index, count });
        }
        let mut doc = self.doc.clone();
        doc.faces.remove(index);
        self.commit(doc);
        Ok(())
    }

    /// Face track `index` of the document, read from its kept bytes (refused with
    /// [`ProjectError::Incomplete`] when they were missing from the opened file).
    pub fn face_track(&self, index: usize) -> Result<FaceTrack, ProjectError> {
        let count = self.doc.faces.len();
        let f = self.doc.faces.get(index).ok_or(ProjectError::NoSuchFaceTrack { index, count })?;
        let bytes = self.blobs.get(&f.blob).ok_or_else(|| ProjectError::Incomplete { count: 1, first: format!("face track {}", f.file_name) })?;
        face_track_of(&f.file_name, bytes, f.song_offset_frames)
    }
}
