//! The project's MikuMikuDance tracks (issue 28, `.odori` schema 7): camera VMDs the video
//! camera can play and lip-sync (face) VMDs — files of morph keys, usually without bone keys —
//! that MMD users load beside a dance onto the same model. Both are kept the same way, so they
//! are one list of [`MmdTrack`]s with a [`TrackKind`] (schemas 4–6 kept two lists of the same
//! fields): the file as given (a blob by hash) with the motion frame that is song time 0, its
//! keys read again from those bytes ([`Project::camera_track`], [`Project::face_track`]), so
//! the `.odori` file holds nothing but the person's file. One add and one remove serve both;
//! `add_camera`/`add_face_track` and their removes stay as thin calls. What a face track means
//! on a model is [`crate::mmd::face_track`]; a camera track, [`crate::mmd::files::CameraTrack`].

use serde::{Deserialize, Serialize};

use super::{BlobHash, Project, ProjectError};
use crate::import::ImportError;
use crate::mmd::face_track::FaceTrack;
use crate::mmd::files::{CameraTrack, MmdFilesError};

/// What an MMD track of the project drives.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub enum TrackKind {
    /// A camera VMD's camera keys: the video camera can play it.
    Camera,
    /// A lip-sync VMD's morph (face) keys: played on the dance's MMD model.
    Face,
}

impl TrackKind {
    /// In words, for messages ("camera motion", "face track").
    pub fn words(self) -> &'static str {
        match self {
            TrackKind::Camera => "camera motion",
            TrackKind::Face => "face track",
        }
    }
}

/// A camera or lip-sync VMD the person imported, as given. Like every MMD file it stays with
/// the person (in the `.odori` file and the browser's store, never in a share link).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct MmdTrack {
    pub kind: TrackKind,
    pub file_name: String,
    /// The file's bytes, exactly as given.
    pub blob: BlobHash,
    /// The motion frame that is song time 0, when one was given (else frame 0 is).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub song_offset_frames: Option<u32>,
}

/// A track's keys as read from its VMD bytes.
#[derive(Clone, Debug, PartialEq)]
pub enum TrackKeys {
    Camera(CameraTrack),
    Face(FaceTrack),
}

/// The VMD's keys of `kind`, or why not (not a VMD, cut short, no keys of that kind).
pub(crate) fn track_of(kind: TrackKind, file_name: &str, bytes: &[u8], song_offset_frames: Option<u32>) -> Result<TrackKeys, ProjectError> {
    let vmd = crate::import::vmd::read(file_name, bytes).map_err(|e| {
        let e = MmdFilesError::from(e);
        ProjectError::Import(ImportError::Mmd { file: file_name.to_string(), kind: e.kind(), message: e.to_string() })
    })?;
    let offset = song_offset_frames.unwrap_or(0);
    let file = file_name.to_string();
    match kind {
        TrackKind::Camera => CameraTrack::from_vmd(file_name, &vmd, offset)
            .map(TrackKeys::Camera)
            .ok_or(ProjectError::NotACamera { file_name: file, bone_keys: vmd.bone_keys.len(), morph_keys: vmd.morph_keys.len() }),
        TrackKind::Face => FaceTrack::from_vmd(file_name, &vmd, offset)
            .map(TrackKeys::Face)
            .ok_or(ProjectError::NotAFaceTrack { file_name: file, bone_keys: vmd.bone_keys.len(), camera_keys: vmd.camera_keys.len() }),
    }
}

fn no_such(kind: TrackKind, index: usize, count: usize) -> ProjectError {
    match kind {
        TrackKind::Camera => ProjectError::NoSuchCamera { index, count },
        TrackKind::Face => ProjectError::NoSuchFaceTrack { index, count },
    }
}

impl super::ProjectDoc {
    /// The MMD tracks of `kind`, in the order imported (a camera's or face track's index is
    /// its place here).
    pub fn tracks(&self, kind: TrackKind) -> impl Iterator<Item = &MmdTrack> {
        self.mmd_tracks.iter().filter(move |t| t.kind == kind)
    }

    /// Where the `index`-th track of `kind` sits in [`super::ProjectDoc::mmd_tracks`].
    fn track_position(&self, kind: TrackKind, index: usize) -> Result<usize, ProjectError> {
        let count = self.tracks(kind).count();
        self.mmd_tracks.iter().enumerate().filter(|(_, t)| t.kind == kind).nth(index).map(|(i, _)| i).ok_or_else(|| no_such(kind, index, count))
    }
}

impl Project {
    /// Keeps an MMD track of `kind`: the VMD's bytes as given, with `song_offset_frames` (the
    /// motion frame that is song time 0). Returns its keys as read. A file that is not a VMD,
    /// is cut short or has no keys of that kind (camera keys for a camera, morph keys for a
    /// face track: a dance VMD's face keys are taken, its bone keys not used here) is a typed
    /// error naming the file, and the project is unchanged. Undoable.
    pub fn add_track(&mut self, kind: TrackKind, file_name: &str, bytes: &[u8], song_offset_frames: Option<u32>) -> Result<TrackKeys, ProjectError> {
        let keys = track_of(kind, file_name, bytes, song_offset_frames)?;
        let blob = self.blobs.put(bytes);
        let mut doc = self.doc.clone();
        doc.mmd_tracks.push(MmdTrack { kind, file_name: file_name.to_string(), blob, song_offset_frames });
        self.commit(doc);
        Ok(keys)
    }

    /// Removes the `index`-th track of `kind` (its place in [`super::ProjectDoc::tracks`]).
    /// Undoable.
    pub fn remove_track(&mut self, kind: TrackKind, index: usize) -> Result<(), ProjectError> {
        let at = self.doc.track_position(kind, index)?;
        let mut doc = self.doc.clone();
        doc.mmd_tracks.remove(at);
        self.commit(doc);
        Ok(())
    }

    /// The `index`-th track of `kind`, read from its kept bytes (refused with
    /// [`ProjectError::Incomplete`] when they were missing from the opened file).
    pub fn track(&self, kind: TrackKind, index: usize) -> Result<TrackKeys, ProjectError> {
        let t = &self.doc.mmd_tracks[self.doc.track_position(kind, index)?];
        let bytes = self.blobs.get(&t.blob).ok_or_else(|| ProjectError::Incomplete { count: 1, first: format!("{} {}", kind.words(), t.file_name) })?;
        track_of(kind, &t.file_name, bytes, t.song_offset_frames)
    }

    /// [`Project::add_track`] of a camera motion (a MikuMikuDance camera VMD): the video camera
    /// can play it. "mmd-no-camera-keys" for a VMD without camera keys.
    pub fn add_camera(&mut self, file_name: &str, bytes: &[u8], song_offset_frames: Option<u32>) -> Result<CameraTrack, ProjectError> {
        match self.add_track(TrackKind::Camera, file_name, bytes, song_offset_frames)? {
            TrackKeys::Camera(t) => Ok(t),
            TrackKeys::Face(_) => Err(no_such(TrackKind::Camera, 0, 0)),
        }
    }

    /// Removes camera motion `index`. Undoable.
    pub fn remove_camera(&mut self, index: usize) -> Result<(), ProjectError> {
        self.remove_track(TrackKind::Camera, index)
    }

    /// Camera motion `index` as the camera plays it, read from its kept bytes.
    pub fn camera_track(&self, index: usize) -> Result<CameraTrack, ProjectError> {
        match self.track(TrackKind::Camera, index)? {
            TrackKeys::Camera(t) => Ok(t),
            TrackKeys::Face(_) => Err(no_such(TrackKind::Camera, index, 0)),
        }
    }

    /// [`Project::add_track`] of a lip-sync VMD's morph (face) keys: played on the dance's MMD
    /// model. "mmd-no-morph-keys" for a VMD without morph keys.
    pub fn add_face_track(&mut self, file_name: &str, bytes: &[u8], song_offset_frames: Option<u32>) -> Result<FaceTrack, ProjectError> {
        match self.add_track(TrackKind::Face, file_name, bytes, song_offset_frames)? {
            TrackKeys::Face(t) => Ok(t),
            TrackKeys::Camera(_) => Err(no_such(TrackKind::Face, 0, 0)),
        }
    }

    /// Removes face track `index`. Undoable.
    pub fn remove_face_track(&mut self, index: usize) -> Result<(), ProjectError> {
        self.remove_track(TrackKind::Face, index)
    }

    /// Face track `index`, read from its kept bytes.
    pub fn face_track(&self, index: usize) -> Result<FaceTrack, ProjectError> {
        match self.track(TrackKind::Face, index)? {
            TrackKeys::Face(t) => Ok(t),
            TrackKeys::Camera(_) => Err(no_such(TrackKind::Face, index, 0)),
        }
    }
}
