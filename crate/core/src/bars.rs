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
    /// Beats in the bar, its metre's count (3 in a waltz, 4 in 4/4): a bar of n beats is filled
    /// by a segment of n counts, count k on its k-th beat (spec §E; [`crate::choreo::segment`]).
    /// 4 in documents saved before bars kept it.
    #[serde(default = "four")]
    pub beats: u32,
}

fn four() -> u32 {
    4
}

impl Bar {
    pub fn duration_secs(&self) -> f32 {
        self.end_secs - self.start_secs
    }

    /// Its beats as a count of at least 1 (a bar deserialised with 0 beats has 4).
    pub fn beat_count(&self) -> usize {
        if self.beats == 0 { 4 } else { self.beats as usize }
    }
}
