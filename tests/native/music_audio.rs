//! Audio decoding for the music tests, benches and tools: Ogg Vorbis and FLAC through
//! symphonia, to planar f32 channels, then the envelope exactly as the browser host computes it
//! (`odori_core::music::rms::envelope`). Included with `#[path]` by each target that needs it.

#![allow(dead_code)]

use odori_core::music::{self, RmsEnvelope};
use symphonia::core::audio::SampleBuffer;
use symphonia::core::codecs::DecoderOptions;
use symphonia::core::errors::Error;
use symphonia::core::formats::FormatOptions;
use symphonia::core::io::MediaSourceStream;
use symphonia::core::meta::MetadataOptions;
use symphonia::core::probe::Hint;

/// Decoded PCM: planar channels at a sample rate.
pub struct Decoded {
    pub sample_rate_hz: f32,
    pub channels: Vec<Vec<f32>>,
}

impl Decoded {
    pub fn duration_secs(&self) -> f32 {
        self.channels.first().map_or(0, Vec::len) as f32 / self.sample_rate_hz
    }

    /// The host's RMS envelope of this audio.
    pub fn envelope(&self) -> Result<RmsEnvelope, music::MusicError> {
        let refs: Vec<&[f32]> = self.channels.iter().map(Vec::as_slice).collect();
        music::envelope(&refs, self.sample_rate_hz)
    }
}

/// Decodes a whole file held in memory; `extension` is a hint ("ogg", "flac").
pub fn decode(bytes: Vec<u8>, extension: &str) -> Result<Decoded, String> {
    let mss = MediaSourceStream::new(Box::new(std::io::Cursor::new(bytes)), Default::default());
    let mut hint = Hint::new();
    hint.with_extension(extension);
    let probed = symphonia::default::get_probe()
        .format(&hint, mss, &FormatOptions::default(), &MetadataOptions::default())
        .map_err(|e| format!("cannot open: {e}"))?;
    let mut format = probed.format;
    let track = format.default_track().ok_or("no audio track")?;
    let track_id = track.id;
    let mut sample_rate = track.codec_params.sample_rate;
    let mut decoder = symphonia::default::get_codecs()
        .make(&track.codec_params, &DecoderOptions::default())
        .map_err(|e| format!("no decoder: {e}"))?;
    let mut channels: Vec<Vec<f32>> = Vec::new();
    loop {
        let packet = match format.next_packet() {
            Ok(p) => p,
            Err(Error::IoError(e)) if e.kind() == std::io::ErrorKind::UnexpectedEof => break,
            Err(Error::ResetRequired) => break,
            Err(e) => return Err(format!("read error: {e}")),
        };
        if packet.track_id() != track_id {
            continue;
        }
        let buf = match decoder.decode(&packet) {
            Ok(b) => b,
            Err(Error::DecodeError(_)) => continue,
            Err(e) => return Err(format!("decode error: {e}")),
        };
        let spec = *buf.spec();
        sample_rate = Some(spec.rate);
        let n_ch = spec.channels.count();
        let frames = buf.frames();
        let mut sb = SampleBuffer::<f32>::new(buf.capacity() as u64, spec);
        sb.copy_planar_ref(buf);
        if channels.is_empty() {
            channels = vec![Vec::new(); n_ch];
        }
        for (c, out) in channels.iter_mut().enumerate() {
            out.extend_from_slice(&sb.samples()[c * frames..(c + 1) * frames]);
        }
    }
    let sample_rate_hz = sample_rate.ok_or("unknown sample rate")? as f32;
    if channels.is_empty() {
        return Err("no samples decoded".into());
    }
    Ok(Decoded { sample_rate_hz, channels })
}

/// Decodes a file under ../shared/data.
pub fn decode_data(rel: &str) -> Decoded {
    let ext = rel.rsplit('.').next().unwrap_or("");
    decode(odori_tests::read(rel), ext).unwrap_or_else(|e| panic!("{rel}: {e}"))
}

/// The drum performance with ground truth.
pub const DRUMS: &str = "beats/drummer1_eval_session_1_funk-groove1_138_beat_4-4.FluidR3GM.flac";
pub const DRUMS_BEATS: &str = "beats/drummer1_eval_session_1_funk-groove1_138_beat_4-4.beats";
pub const TRUMPET: &str = "music/sorohanro_-_solo-trumpet-06.hq.ogg";
pub const FULL_TRACKS: [&str; 3] = [
    "music/Kevin_MacLeod_-_Vibe_Ace.hq.ogg",
    "music/Karissa_Hobbs_-_Lets_Go_Fishin.hq.ogg",
    "music/Kevin_MacLeod_-_P_I_Tchaikovsky_Dance_of_the_Sugar_Plum_Fairy.hq.ogg",
];

/// The songs the issue-26 acceptance reads: every song in ../shared/data/music and the drum take.
pub const ACCEPTANCE_TRACKS: [&str; 5] = [FULL_TRACKS[0], FULL_TRACKS[1], FULL_TRACKS[2], TRUMPET, DRUMS];

/// The envelope of a file under ../shared/data (panics naming the file).
pub fn decode_envelope(rel: &str) -> RmsEnvelope {
    decode_data(rel).envelope().unwrap_or_else(|e| panic!("{rel}: {e}"))
}

/// Ground truth from a `.beats` file: (beat times, downbeat times), seconds.
pub fn read_beats(rel: &str) -> (Vec<f32>, Vec<f32>) {
    let text = String::from_utf8(odori_tests::read(rel)).expect("utf-8 .beats");
    let mut beats = Vec::new();
    let mut downbeats = Vec::new();
    for line in text.lines().filter(|l| !l.trim().is_empty()) {
        let mut it = line.split_whitespace();
        let t: f32 = it.next().and_then(|v| v.parse().ok()).unwrap_or_else(|| panic!("bad line {line:?}"));
        let pos: f32 = it.next().and_then(|v| v.parse().ok()).unwrap_or_else(|| panic!("bad line {line:?}"));
        beats.push(t);
        if pos == 1.0 {
            downbeats.push(t);
        }
    }
    (beats, downbeats)
}
