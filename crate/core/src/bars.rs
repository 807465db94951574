//! Bars of a song: what song analysis produces and what choreography fills, one segment of
//! dance per bar.

use serde::{Deserialize, Serialize};

/// One bar of the song's grid.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct Bar {
    /// 0-based position in the song.
    pub index: usize,
    pub start_secs: f32,
    pub end_secs: f32,
    /// Music intensity of the bar, the mean RMS over it scaled to the song's range: 0..=1
    /// (spec §D).
    pub intensity: f32,
}

impl Bar {
    pub fn duration_secs(&self) -> f32 {
        self.end_secs - self.start_secs
    }
}
