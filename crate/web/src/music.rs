//! `Song`: a song's analysis (tempo, beats, downbeats, bars) and the person's corrections of
//! its grid; and the built-in demo song. The host computes the RMS envelope with WebAudio
//! (www/audio/rms.js) or hands decoded samples to `Song.fromSamples`, which computes the same
//! envelope in Rust.

use js_sys::{Array, Float32Array};
use odori_core::music::{self, AnalysisOptions, GridCorrection, RmsEnvelope, SongGrid};
use wasm_bindgen::prelude::*;

use crate::error::{from_js, to_js, OdoriError};

fn music_err(e: music::MusicError) -> OdoriError {
    OdoriError::new("music", e.to_string())
}

fn arrays(value: &Array, what: &str) -> Result<Vec<Vec<f32>>, OdoriError> {
    value
        .iter()
        .enumerate()
        .map(|(i, v)| {
            v.dyn_into::<Float32Array>()
                .map(|a| a.to_vec())
                .map_err(|_| OdoriError::new("bad-argument", format!("{what}[{i}] must be a Float32Array")))
        })
        .collect()
}

const OPTION_KEYS: [&str; 7] = ["beatsPerBar", "minBpm", "maxBpm", "priorBpm", "priorOctaves", "tightness", "followTempo"];

/// A song's beat grid, analysed once and corrected by the person.
#[wasm_bindgen]
pub struct Song {
    analysed: SongGrid,
    grid: SongGrid,
}

#[wasm_bindgen]
impl Song {
    /// Analyses an RMS envelope: `hopSecs` between frames and one `Float32Array` per band
    /// (the four bands of www/audio/rms.js, or a single loudness band).
    #[wasm_bindgen(js_name = fromEnvelope)]
    pub fn from_envelope(
        hop_secs: f32,
        bands: Array,
        #[wasm_bindgen(unchecked_param_type = "AnalysisOptions | undefined")] options: JsValue,
    ) -> Result<Song, OdoriError> {
        let options: AnalysisOptions = from_js(options, "analysis options", &OPTION_KEYS)?;
        let envelope = RmsEnvelope { hop_secs, bands: arrays(&bands, "bands")? };
        let grid = music::analyze(&envelope, &options).map_err(music_err)?;
        Ok(Song { analysed: grid.clone(), grid })
    }

    /// Analyses decoded audio (one `Float32Array` per channel): the envelope is computed in
    /// Rust with the same definition the browser host uses.
    #[wasm_bindgen(js_name = fromSamples)]
    pub fn from_samples(
        channels: Array,
        sample_rate_hz: f32,
        #[wasm_bindgen(unchecked_param_type = "AnalysisOptions | undefined")] options: JsValue,
    ) -> Result<Song, OdoriError> {
        let options: AnalysisOptions = from_js(options, "analysis options", &OPTION_KEYS)?;
        let chans = arrays(&channels, "channels")?;
        let refs: Vec<&[f32]> = chans.iter().map(Vec::as_slice).collect();
        let envelope = music::rms::envelope(&refs, sample_rate_hz).map_err(music_err)?;
        let grid = music::analyze(&envelope, &options).map_err(music_err)?;
        Ok(Song { analysed: grid.clone(), grid })
    }

    /// The current grid (`SongGrid`: bpm, beats, downbeats, bars with intensity, loudness).
    #[wasm_bindgen(unchecked_return_type = "SongGrid")]
    pub fn grid(&self) -> JsValue {
        to_js(&self.grid)
    }

    /// Applies a correction (`{ bpm?, tapTimesSecs?, beatsPerBar?, firstDownbeatSecs?,
    /// nudgeSecs? }`) to the current grid and returns the new grid; on a bad value throws and
    /// keeps the grid as it was: fewer than 4 taps, or a nudge of more than one bar (a nudge
    /// corrects the phase; use `firstDownbeatSecs` or `bpm` for more).
    #[wasm_bindgen(unchecked_return_type = "SongGrid")]
    pub fn correct(
        &mut self,
        #[wasm_bindgen(unchecked_param_type = "GridCorrection")] correction: JsValue,
    ) -> Result<JsValue, OdoriError> {
        let c: GridCorrection =
            from_js(correction, "grid correction", &["bpm", "tapTimesSecs", "beatsPerBar", "firstDownbeatSecs", "nudgeSecs"])?;
        self.grid = self.grid.corrected(&c).map_err(music_err)?;
        Ok(to_js(&self.grid))
    }

    /// Back to the grid the analysis found.
    #[wasm_bindgen(unchecked_return_type = "SongGrid")]
    pub fn reset(&mut self) -> JsValue {
        self.grid = self.analysed.clone();
        to_js(&self.grid)
    }

    #[wasm_bindgen(getter, js_name = durationSecs)]
    pub fn duration_secs(&self) -> f32 {
        self.grid.duration_secs
    }
}

/// The RMS envelope of decoded audio (one `Float32Array` per channel), computed in Rust with
/// the definition the browser host uses (`envelopeDefinition()`): `{ hopSecs, bands }`, what
/// `Project.setSong` and `Song.fromEnvelope` take. For hosts without WebAudio (Node).
#[wasm_bindgen(js_name = rmsEnvelope, unchecked_return_type = "{ hopSecs: number; bands: Float32Array[] }")]
pub fn rms_envelope(channels: Array, sample_rate_hz: f32) -> Result<JsValue, OdoriError> {
    let chans = arrays(&channels, "channels")?;
    let refs: Vec<&[f32]> = chans.iter().map(Vec::as_slice).collect();
    let env = music::rms::envelope(&refs, sample_rate_hz).map_err(music_err)?;
    let out = js_sys::Object::new();
    let bands: Array = env.bands.iter().map(|b| JsValue::from(Float32Array::from(b.as_slice()))).collect();
    js_sys::Reflect::set(&out, &JsValue::from_str("hopSecs"), &JsValue::from(env.hop_secs)).map_err(|_| OdoriError::new("bad-argument", "envelope"))?;
    js_sys::Reflect::set(&out, &JsValue::from_str("bands"), &bands).map_err(|_| OdoriError::new("bad-argument", "envelope"))?;
    Ok(out.into())
}

/// How the song's loudness envelope is defined, from the one place the engine keeps it
/// (crate/core music/rms.rs): `{ bands: { name, kind, frequencyHz, q, stages }[], hopTargetSecs,
/// minSampleRateHz }`. `kind` is a `BiquadFilterNode` type ("lowpass", "bandpass",
/// "highpass") or "full" (the mono mix, no filter); `q` in WebAudio's units for the type. The
/// browser host (www/audio/rms.js) builds its WebAudio graph and frames from it.
#[wasm_bindgen(js_name = envelopeDefinition, unchecked_return_type = "EnvelopeDefinition")]
pub fn envelope_definition() -> JsValue {
    to_js(&music::rms::envelope_definition())
}

/// The built-in demo song, rendered at a sample rate: mono samples and its true grid.
#[wasm_bindgen]
pub struct DemoSong {
    inner: music::demo_song::DemoSong,
}

#[wasm_bindgen]
impl DemoSong {
    /// Renders the demo song (about a minute of music in sections of different intensity).
    pub fn render(sample_rate_hz: f32) -> Result<DemoSong, OdoriError> {
        Ok(DemoSong { inner: music::demo_song::demo_song(sample_rate_hz).map_err(music_err)? })
    }

    /// Mono PCM, ±1.
    #[wasm_bindgen(getter)]
    pub fn samples(&self) -> Float32Array {
        Float32Array::from(self.inner.samples.as_slice())
    }

    #[wasm_bindgen(getter, js_name = sampleRateHz)]
    pub fn sample_rate_hz(&self) -> f32 {
        self.inner.sample_rate_hz
    }

    /// `{ bpm, beatsPerBar, firstDownbeatSecs, barCount, sections }` (no samples).
    #[wasm_bindgen(unchecked_return_type = "DemoSongInfo")]
    pub fn info(&self) -> JsValue {
        let mut meta = self.inner.clone();
        meta.samples = Vec::new();
        to_js(&meta)
    }
}

#[wasm_bindgen(typescript_custom_section)]
const TS_MUSIC: &'static str = r#"
export interface Bar { index: number; startSecs: number; endSecs: number; /** 0..1 */ intensity: number; /** beats in the bar (3 in 3/4) */ beats: number; }
export interface SongGrid {
  durationSecs: number; bpm: number; beatsPerBar: number;
  beatTimesSecs: number[]; firstDownbeatIndex: number; firstDownbeatSecs: number;
  downbeatTimesSecs: number[]; bars: Bar[]; regular: boolean;
  /** Analysed grids: how clearly the song beats at this tempo (z-score vs its onsets shuffled); null for typed/tapped grids. */
  beatClarity: number | null;
  /** False when analysis found no clear beat (beatClarity < 5): the grid is a guess; say so and offer typing or tapping. */
  clearBeat: boolean;
  loudness: { hopSecs: number; values: number[] };
}
export interface EnvelopeBand { name: string; kind: "full" | "lowpass" | "bandpass" | "highpass"; frequencyHz: number; q: number; stages: number; }
export interface EnvelopeDefinition { bands: EnvelopeBand[]; hopTargetSecs: number; minSampleRateHz: number; }
export interface GridCorrection { bpm?: number; tapTimesSecs?: number[]; beatsPerBar?: number; firstDownbeatSecs?: number; nudgeSecs?: number; }
export interface AnalysisOptions { beatsPerBar?: number; minBpm?: number; maxBpm?: number; priorBpm?: number; priorOctaves?: number; tightness?: number; followTempo?: boolean; }
export interface DemoSongInfo { bpm: number; beatsPerBar: number; firstDownbeatSecs: number; barCount: number; sampleRateHz: number; sections: { name: string; startBar: number; barCount: number; startSecs: number; endSecs: number }[]; }
"#;
