//! The app's built-in demo song, "Odori Demo" (the project's own work, synthesised here so the
//! product works with no file): 120 BPM, 4/4, A minor (Am–F–C–G), 34 bars plus a ring-out,
//! with drums, bass, pads, an arpeggio and a lead melody, and sections of clearly different
//! intensity: intro (4 bars), verse (8), chorus (8), break (4), chorus (8), outro (2).
//!
//! Rendering is deterministic (a fixed-seed noise generator, no clocks) and takes a few hundred
//! milliseconds natively. Its true grid is exact by construction: a beat every 0.5 s from 0,
//! a downbeat every 2 s from 0, so tests can check that analysis recovers it.
//!
//! [`demo_song_with`] renders variants for testing the grid analysis: another metre (3/4, an
//! "oom-pah-pah" waltz pattern: kick on the one, snare and hats on two and three) and a tempo
//! that ramps linearly per beat from `bpm` to `end_bpm`, whose true beats are then uneven but
//! still exact by construction. The default options give the demo song itself, sample for
//! sample.

use crate::fmath;
use serde::{Deserialize, Serialize};

use super::MusicError;

/// Tempo of the demo song, BPM.
pub const DEMO_BPM: f32 = 120.0;
/// Beats per bar of the demo song.
pub const DEMO_BEATS_PER_BAR: u32 = 4;
/// Highest sample rate [`demo_song`] renders at, Hz.
pub const MAX_DEMO_SAMPLE_RATE_HZ: f32 = 192_000.0;

/// One section of the demo song.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct DemoSection {
    /// "intro", "verse", "chorus", "break" or "outro".
    pub name: String,
    /// First bar (0-based) and number of bars.
    pub start_bar: usize,
    pub bar_count: usize,
    pub start_secs: f32,
    pub end_secs: f32,
}

/// The rendered demo song and its true grid. `samples` is large (about 3 M values at
/// 44.1 kHz): the web layer should hand it to JavaScript as a `Float32Array`, not through serde.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct DemoSong {
    pub sample_rate_hz: f32,
    /// Mono PCM, full scale ±1 (peak 0.9).
    pub samples: Vec<f32>,
    /// Tempo at the first beat, BPM.
    pub bpm: f32,
    /// Tempo at the last beat, BPM (equal to `bpm` for a steady tempo; in between, the tempo
    /// changes linearly per beat).
    pub end_bpm: f32,
    pub beats_per_bar: u32,
    /// The true first downbeat (0: the song starts on the one).
    pub first_downbeat_secs: f32,
    /// Number of bars with music (the ring-out after them is not a bar).
    pub bar_count: usize,
    pub sections: Vec<DemoSection>,
}

impl DemoSong {
    /// Length of the rendered audio, seconds.
    pub fn duration_secs(&self) -> f32 {
        self.samples.len() as f32 / self.sample_rate_hz
    }

    /// The true beat times: every `60 / bpm` seconds through the last bar (with a ramp, each
    /// beat lasts `60 / tempo` at its own tempo).
    pub fn beat_times_secs(&self) -> Vec<f32> {
        let n = self.bar_count * self.beats_per_bar as usize;
        if self.end_bpm == self.bpm {
            return (0..n).map(|k| self.first_downbeat_secs + k as f32 * 60.0 / self.bpm).collect();
        }
        let map = TimeMap::ramp(self.bpm, self.end_bpm, n);
        (0..n).map(|k| self.first_downbeat_secs + map.at(k as f32)).collect()
    }

    /// The true downbeat times, one per bar.
    pub fn downbeat_times_secs(&self) -> Vec<f32> {
        let bpb = self.beats_per_bar as usize;
        self.beat_times_secs().into_iter().step_by(bpb.max(1)).collect()
    }

    /// The true tempo at each beat, BPM (`60 / ` the beat's length).
    pub fn tempo_at_beats_bpm(&self) -> Vec<f32> {
        let n = self.bar_count * self.beats_per_bar as usize;
        (0..n).map(|k| ramp_bpm(self.bpm, self.end_bpm, k, n)).collect()
    }
}

/// The variant of the demo song [`demo_song_with`] renders.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DemoSongOptions {
    /// 4 (the demo song) or 3 (a waltz pattern).
    pub beats_per_bar: u32,
    /// Tempo at the first beat, BPM.
    pub bpm: f32,
    /// Tempo at the last beat, BPM.
    pub end_bpm: f32,
}

impl Default for DemoSongOptions {
    fn default() -> Self {
        Self { beats_per_bar: DEMO_BEATS_PER_BAR, bpm: DEMO_BPM, end_bpm: DEMO_BPM }
    }
}

/// The tempo of beat `k` of `n` on a ramp from `start_bpm` to `end_bpm`.
fn ramp_bpm(start_bpm: f32, end_bpm: f32, k: usize, n: usize) -> f32 {
    start_bpm + (end_bpm - start_bpm) * k as f32 / (n.max(2) - 1) as f32
}

/// Song time of a position counted in beats: beat `k` lasts `60 / tempo_k` seconds, and a
/// position within a beat is linear in it.
struct TimeMap {
    /// Start of every beat, plus the end of the last (and one more beat for the ring-out).
    starts_secs: Vec<f32>,
}

impl TimeMap {
    fn ramp(start_bpm: f32, end_bpm: f32, beats: usize) -> Self {
        let mut starts_secs = vec![0.0f32];
        let mut t = 0.0f64;
        for k in 0..beats + 8 {
            t += 60.0 / f64::from(ramp_bpm(start_bpm, end_bpm, k.min(beats.saturating_sub(1)), beats));
            starts_secs.push(t as f32);
        }
        Self { starts_secs }
    }

    fn at(&self, beat: f32) -> f32 {
        let last = self.starts_secs.len() - 2;
        let k = (beat.max(0.0).floor() as usize).min(last);
        let f = beat - k as f32;
        self.starts_secs[k] + f * (self.starts_secs[k + 1] - self.starts_secs[k])
    }
}

/// Sections: (name, bars).
const SECTIONS: [(&str, usize); 6] = [("intro", 4), ("verse", 8), ("chorus", 8), ("break", 4), ("chorus", 8), ("outro", 2)];
/// Seconds of ring-out after the last bar.
const RING_OUT_SECS: f32 = 2.0;

/// Chord per bar of the four-bar cycle (MIDI notes) and its bass root.
const CHORDS: [[u8; 3]; 4] = [[57, 60, 64], [57, 60, 65], [55, 60, 64], [55, 59, 62]];
const ROOTS: [u8; 4] = [45, 41, 48, 43];

/// Chorus melody over one 4-bar cycle: (bar, start beat, length in beats, MIDI note).
const MELODY: [(usize, f32, f32, u8); 18] = [
    (0, 0.0, 1.0, 76),
    (0, 1.0, 0.5, 74),
    (0, 1.5, 0.5, 72),
    (0, 2.0, 1.5, 69),
    (0, 3.5, 0.5, 72),
    (1, 0.0, 1.0, 72),
    (1, 1.0, 0.5, 69),
    (1, 1.5, 0.5, 72),
    (1, 2.0, 1.0, 74),
    (1, 3.0, 1.0, 72),
    (2, 0.0, 1.5, 76),
    (2, 1.5, 0.5, 79),
    (2, 2.0, 1.0, 76),
    (2, 3.0, 1.0, 74),
    (3, 0.0, 1.0, 74),
    (3, 1.0, 1.0, 71),
    (3, 2.0, 1.5, 67),
    (3, 3.5, 0.5, 69),
];

fn midi_hz(note: u8) -> f32 {
    440.0 * fmath::powf(2f32, (f32::from(note) - 69.0) / 12.0)
}

/// Deterministic white noise (xorshift32), values in [-1, 1).
struct Noise(u32);

impl Noise {
    fn next(&mut self) -> f32 {
        let mut x = self.0;
        x ^= x << 13;
        x ^= x >> 17;
        x ^= x << 5;
        self.0 = x;
        (x as f32 / u32::MAX as f32) * 2.0 - 1.0
    }
}

/// PolyBLEP correction for a band-limited sawtooth.
fn poly_blep(phase: f32, dt: f32) -> f32 {
    if phase < dt {
        let t = phase / dt;
        t + t - t * t - 1.0
    } else if phase > 1.0 - dt {
        let t = (phase - 1.0) / dt;
        t * t + t + t + 1.0
    } else {
        0.0
    }
}

/// The renderer: a mono mix buffer and the sample rate.
struct Mix {
    fs: f32,
    out: Vec<f32>,
    noise: Noise,
}

impl Mix {
    fn span(&self, start_secs: f32, len_secs: f32) -> (usize, usize) {
        let a = (start_secs * self.fs).round().max(0.0) as usize;
        let b = (((start_secs + len_secs) * self.fs).round().max(0.0) as usize).min(self.out.len());
        (a.min(b), b)
    }

    fn kick(&mut self, t0: f32, gain: f32) {
        let (a, b) = self.span(t0, 0.45);
        let mut phase = 0.0f32;
        let (mut sweep, mut amp) = (Decay::new(0.035, self.fs), Decay::new(0.22, self.fs));
        let click_n = 0.004 * self.fs;
        for (j, i) in (a..b).enumerate() {
            let f = 48.0 + 110.0 * sweep.next();
            phase = (phase + f / self.fs).fract();
            let click = if (j as f32) < click_n { 0.3 * (1.0 - j as f32 / click_n) } else { 0.0 };
            self.out[i] += gain * (fmath::sin(2.0 * std::f32::consts::PI * phase) * amp.next() + click);
        }
    }

    fn snare(&mut self, t0: f32, gain: f32) {
        let (a, b) = self.span(t0, 0.3);
        let mut prev = 0.0f32;
        let mut tone = Phasor::new(185.0, self.fs);
        let (mut tone_amp, mut noise_amp) = (Decay::new(0.06, self.fs), Decay::new(0.1, self.fs));
        for i in a..b {
            let n = self.noise.next();
            let hp = n - prev;
            prev = n;
            self.out[i] += gain * (0.55 * hp * noise_amp.next() + 0.6 * tone.next() * tone_amp.next());
        }
    }

    fn hat(&mut self, t0: f32, gain: f32, decay_secs: f32) {
        let (a, b) = self.span(t0, decay_secs * 5.0);
        let (mut p1, mut p2) = (0.0f32, 0.0f32);
        let mut amp = Decay::new(decay_secs, self.fs);
        for i in a..b {
            let n = self.noise.next();
            // Second difference: a steep high-pass, the metallic hiss of a hat.
            let hp = n - 2.0 * p1 + p2;
            p2 = p1;
            p1 = n;
            self.out[i] += gain * 0.25 * hp * amp.next();
        }
    }

    /// A band-limited saw voice (two detuned oscillators) through a one-pole low-pass, with an
    /// attack / decay-to-sustain / release envelope. `cutoff_hz` sets the brightness.
    #[allow(clippy::too_many_arguments)]
    fn saw(&mut self, t0: f32, len_secs: f32, hz: f32, gain: f32, attack: f32, release: f32, cutoff_hz: f32, detune: f32) {
        let (a, b) = self.span(t0, len_secs + release);
        let k = 1.0 - fmath::exp(-2.0 * std::f32::consts::PI * cutoff_hz / self.fs);
        let mut lp = 0.0f32;
        let mut phases = [0.0f32, 0.37];
        let dts = [hz * (1.0 + detune) / self.fs, hz * (1.0 - detune) / self.fs];
        let attack_n = (attack * self.fs) as usize;
        let len_n = (len_secs * self.fs) as usize;
        let (mut decay, mut rel) = (Decay::new(0.15, self.fs), Decay::new(release / 4.0, self.fs));
        let mut level = 0.0f32;
        for (j, i) in (a..b).enumerate() {
            let mut s = 0.0;
            for (p, &dt) in phases.iter_mut().zip(&dts) {
                s += 2.0 * *p - 1.0 - poly_blep(*p, dt);
                *p = (*p + dt).fract();
            }
            lp += k * (0.5 * s - lp);
            let env = if j < attack_n {
                level = j as f32 / attack_n as f32;
                level
            } else if j < len_n {
                level = 0.75 + 0.25 * decay.next();
                level
            } else {
                // The release starts from wherever the envelope is: no click.
                level * rel.next()
            };
            self.out[i] += gain * env * lp;
        }
    }

    /// A soft lead: sine plus a little second and third harmonic, with vibrato that sets in
    /// after the attack.
    fn lead(&mut self, t0: f32, len_secs: f32, hz: f32, gain: f32) {
        let (a, b) = self.span(t0, len_secs + 0.15);
        let mut phase = 0.0f32;
        let mut vibrato = Phasor::new(5.5, self.fs);
        let (attack_n, len_n, fade_n) = (0.012 * self.fs, len_secs * self.fs, 0.3 * self.fs);
        let mut rel = Decay::new(0.04, self.fs);
        let mut level = 0.0f32;
        for (j, i) in (a..b).enumerate() {
            let jf = j as f32;
            let vib = 1.0 + 0.004 * vibrato.next() * (jf / fade_n).min(1.0);
            phase = (phase + hz * vib / self.fs).fract();
            let (s1, c1) = fmath::sin_cos(2.0 * std::f32::consts::PI * phase);
            let (s2, s3) = (2.0 * s1 * c1, s1 * (3.0 - 4.0 * s1 * s1));
            let env = if jf < len_n {
                level = (jf / attack_n).min(1.0) * (1.0 - 0.3 * jf / len_n);
                level
            } else {
                level * rel.next()
            };
            self.out[i] += gain * env * (s1 + 0.1 * s2 + 0.25 * s3);
        }
    }
}

/// An exponential decay from 1 with time constant `tau_secs`, one sample per `next`.
struct Decay {
    value: f32,
    factor: f32,
}

impl Decay {
    fn new(tau_secs: f32, fs: f32) -> Self {
        Self { value: 1.0, factor: fmath::exp(-1.0 / (tau_secs.max(1e-4) * fs)) }
    }

    fn next(&mut self) -> f32 {
        let v = self.value;
        self.value *= self.factor;
        v
    }
}

/// A sine oscillator by rotation (one complex multiply per sample, in f64 so it stays on the
/// unit circle for seconds).
struct Phasor {
    re: f64,
    im: f64,
    step_re: f64,
    step_im: f64,
}

impl Phasor {
    fn new(hz: f32, fs: f32) -> Self {
        let w = 2.0 * std::f64::consts::PI * f64::from(hz) / f64::from(fs);
        Self { re: 1.0, im: 0.0, step_re: fmath::cos(w), step_im: fmath::sin(w) }
    }

    /// The sine, then one step on.
    fn next(&mut self) -> f32 {
        let v = self.im as f32;
        let re = self.re * self.step_re - self.im * self.step_im;
        self.im = self.im * self.step_re + self.re * self.step_im;
        self.re = re;
        v
    }
}

/// Renders the demo song at `sample_rate_hz` (8 kHz to 192 kHz).
pub fn demo_song(sample_rate_hz: f32) -> Result<DemoSong, MusicError> {
    demo_song_with(sample_rate_hz, &DemoSongOptions::default())
}

/// Renders a variant of the demo song (another metre, a tempo ramp) at `sample_rate_hz`: same
/// sections, instruments and chords; a 3/4 bar keeps the first three beats of each 4/4 part
/// with a waltz drum pattern.
///
/// Errors: a sample rate outside 8 kHz..=192 kHz, beats per bar other than 3 or 4, or a tempo
/// outside 40..=240 BPM.
pub fn demo_song_with(sample_rate_hz: f32, options: &DemoSongOptions) -> Result<DemoSong, MusicError> {
    if !(sample_rate_hz.is_finite() && (super::rms::MIN_SAMPLE_RATE_HZ..=MAX_DEMO_SAMPLE_RATE_HZ).contains(&sample_rate_hz)) {
        return Err(MusicError::BadSampleRate { sample_rate_hz, min_hz: super::rms::MIN_SAMPLE_RATE_HZ });
    }
    if !(3..=4).contains(&options.beats_per_bar) {
        return Err(MusicError::BadBeatsPerBar { beats_per_bar: options.beats_per_bar, max: 4 });
    }
    for bpm in [options.bpm, options.end_bpm] {
        if !(bpm.is_finite() && (40.0..=240.0).contains(&bpm)) {
            return Err(MusicError::BpmOutOfRange { bpm, min_bpm: 40.0, max_bpm: 240.0 });
        }
    }
    let bpb = options.beats_per_bar as usize;
    let waltz = bpb == 3;
    let steady = options.end_bpm == options.bpm;
    let beat = 60.0 / options.bpm;
    let bar_secs = beat * options.beats_per_bar as f32;
    let bar_count: usize = SECTIONS.iter().map(|s| s.1).sum();
    let map = TimeMap::ramp(options.bpm, options.end_bpm, bar_count * bpb);
    // Song time of beat `b` of bar `bar` (the steady case keeps the demo song's own arithmetic).
    let time_of = |bar: usize, b: f32| {
        if steady {
            bar as f32 * bar_secs + b * beat
        } else {
            map.at((bar * bpb) as f32 + b)
        }
    };
    let total_secs = time_of(bar_count, 0.0) + RING_OUT_SECS;
    let mut mix = Mix { fs: sample_rate_hz, out: vec![0.0; (total_secs * sample_rate_hz) as usize], noise: Noise(0x0D0_121) };
    let mut sections = Vec::new();
    let mut bar0 = 0usize;
    for (name, bars) in SECTIONS {
        sections.push(DemoSection {
            name: name.to_string(),
            start_bar: bar0,
            bar_count: bars,
            start_secs: time_of(bar0, 0.0),
            end_secs: time_of(bar0 + bars, 0.0),
        });
        for local in 0..bars {
            let bar = bar0 + local;
            let t = time_of(bar, 0.0);
            let (bar_secs, beat) = if steady {
                (bar_secs, beat)
            } else {
                let secs = time_of(bar + 1, 0.0) - t;
                (secs, secs / bpb as f32)
            };
            let cycle = bar % 4;
            let chord = CHORDS[cycle];
            let root = ROOTS[cycle];
            let at = |b: f32| time_of(bar, b);
            let eighths = 2 * bpb;
            match name {
                "intro" => {
                    for &n in &chord {
                        mix.saw(t, bar_secs, midi_hz(n), 0.05, 0.4, 0.6, 1200.0, 0.004);
                    }
                    for e in 0..eighths {
                        mix.hat(at(e as f32 * 0.5), if e % 2 == 0 { 0.22 } else { 0.12 }, 0.025);
                    }
                    mix.kick(t, 0.25);
                }
                "verse" => {
                    for &n in &chord {
                        mix.saw(t, bar_secs, midi_hz(n), 0.035, 0.3, 0.5, 1500.0, 0.004);
                    }
                    let (kicks, snares): (&[f32], &[f32]) = if waltz { (&[0.0], &[1.0, 2.0]) } else { (&[0.0, 2.0, 2.5], &[1.0, 3.0]) };
                    for &b in kicks {
                        mix.kick(at(b), if b == 0.0 { 0.75 } else { 0.55 });
                    }
                    for &b in snares {
                        mix.snare(at(b), if waltz { 0.22 } else { 0.32 });
                    }
                    for e in 0..eighths {
                        mix.hat(at(e as f32 * 0.5), if e % 2 == 0 { 0.35 } else { 0.2 }, 0.03);
                    }
                    // Bass on eighths, root with a fifth on the last one.
                    for e in 0..eighths {
                        let n = if e == eighths - 1 { root + 7 } else { root };
                        mix.saw(at(e as f32 * 0.5), beat * 0.4, midi_hz(n), 0.22, 0.005, 0.04, 700.0, 0.0);
                    }
                    // Arpeggio through the chord tones, an octave up.
                    for e in 0..eighths {
                        let n = chord[[0, 1, 2, 1][e % 4]] + 12;
                        mix.saw(at(e as f32 * 0.5), beat * 0.3, midi_hz(n), 0.05, 0.003, 0.08, 2500.0, 0.0);
                    }
                }
                "chorus" => {
                    for &n in &chord {
                        mix.saw(t, bar_secs, midi_hz(n), 0.06, 0.05, 0.4, 3000.0, 0.006);
                        mix.saw(t, bar_secs, midi_hz(n + 12), 0.025, 0.05, 0.4, 3000.0, 0.006);
                    }
                    if local == 0 {
                        mix.hat(t, 0.5, 0.4);
                    }
                    // The waltz keeps its kick on the one only: "oom-pah-pah".
                    for b in 0..if waltz { 1 } else { 4 } {
                        mix.kick(at(b as f32), if b == 0 { 0.95 } else { 0.7 });
                    }
                    let snares: &[f32] = if waltz { &[1.0, 2.0] } else { &[1.0, 3.0] };
                    for &b in snares {
                        mix.snare(at(b), if waltz { 0.3 } else { 0.42 });
                    }
                    for e in 0..eighths {
                        let off = e % 2 == 1;
                        mix.hat(at(e as f32 * 0.5), if off { 0.4 } else { 0.25 }, if off { 0.09 } else { 0.03 });
                    }
                    for e in 0..eighths {
                        let n = if e % 2 == 1 { root + 12 } else { root };
                        mix.saw(at(e as f32 * 0.5), beat * 0.42, midi_hz(n), 0.26, 0.004, 0.04, 900.0, 0.0);
                    }
                    for &(mb, start, len, note) in MELODY.iter().filter(|m| m.0 == cycle && m.1 < bpb as f32) {
                        let _ = mb;
                        let len = len.min(bpb as f32 - start);
                        mix.lead(at(start), len * beat * 0.95, midi_hz(note), 0.16);
                    }
                }
                "break" => {
                    for &n in &chord {
                        mix.saw(t, bar_secs, midi_hz(n), 0.045, 0.5, 0.8, 900.0, 0.005);
                    }
                    // The melody's first note of each beat, softly, on quarters.
                    for b in 0..bpb {
                        let note = MELODY
                            .iter()
                            .rfind(|m| m.0 == cycle && m.1 <= b as f32)
                            .map_or(chord[2] + 12, |m| m.3);
                        mix.lead(at(b as f32), beat * 0.8, midi_hz(note), 0.09);
                    }
                    // The last bar builds up with a snare roll into the chorus.
                    if local == bars - 1 {
                        let rolls = 4 * bpb;
                        for s in 0..rolls {
                            mix.snare(at(s as f32 * 0.25), 0.08 + 0.3 * s as f32 / rolls as f32);
                        }
                    }
                }
                _ => {
                    // Outro: the tonic rings out over a last downbeat.
                    if local == 0 {
                        for &n in &CHORDS[0] {
                            mix.saw(t, bar_secs * 2.0, midi_hz(n), 0.06, 0.02, 1.5, 2000.0, 0.006);
                        }
                        mix.saw(t, bar_secs * 1.5, midi_hz(ROOTS[0]), 0.25, 0.005, 0.5, 600.0, 0.0);
                        mix.hat(t, 0.5, 0.5);
                    }
                    mix.kick(t, 0.8);
                    if !waltz {
                        mix.kick(at(2.0), 0.5);
                    }
                }
            }
        }
        bar0 += bars;
    }
    // Gentle saturation, then a fixed peak of 0.9.
    mix.out.iter_mut().for_each(|s| *s = fmath::tanh(1.2 * *s));
    let peak = mix.out.iter().fold(0.0f32, |m, s| m.max(s.abs()));
    if peak > 0.0 {
        mix.out.iter_mut().for_each(|s| *s *= 0.9 / peak);
    }
    Ok(DemoSong {
        sample_rate_hz,
        samples: mix.out,
        bpm: options.bpm,
        end_bpm: options.end_bpm,
        beats_per_bar: options.beats_per_bar,
        first_downbeat_secs: 0.0,
        bar_count,
        sections,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn renders_deterministically_with_sections_of_different_loudness() {
        let fs = 8000.0;
        let a = demo_song(fs).unwrap();
        let b = demo_song(fs).unwrap();
        assert_eq!(a.samples, b.samples);
        assert_eq!(a.bar_count, 34);
        assert!((a.duration_secs() - 70.0).abs() < 0.01);
        assert!(a.samples.iter().all(|s| s.is_finite() && s.abs() <= 0.9001));
        let rms = |s: &DemoSection| {
            let x = &a.samples[(s.start_secs * fs) as usize..(s.end_secs * fs) as usize];
            (x.iter().map(|v| v * v).sum::<f32>() / x.len() as f32).sqrt()
        };
        let by_name = |n: &str| a.sections.iter().find(|s| s.name == n).map(rms).unwrap();
        let (intro, verse, chorus, brk) = (by_name("intro"), by_name("verse"), by_name("chorus"), by_name("break"));
        assert!(chorus > 1.3 * verse && verse > 1.3 * intro && chorus > 2.0 * brk, "{intro} {verse} {chorus} {brk}");
        assert_eq!(a.beat_times_secs().len(), 136);
        assert_eq!(a.downbeat_times_secs()[1], 2.0);
        assert!(demo_song(1000.0).is_err());
    }
}
