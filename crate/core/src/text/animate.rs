//! From a time table to one animation: look the motions up, compose the parallel ones, join
//! the serial ones, and write the start times back into the table.
//!
//! Each group — a base element and the Composition elements on it — becomes one segment: the
//! base clip (a cycle is repeated to outlast its overlays) with each overlay's body part
//! composed in (spec §I, [`crate::actions::compose()`]). Segments are joined in order by
//! Connection or Transition ([`crate::actions::join_serial`]), with any stated delay. Only the
//! last few seconds of the animation so far take part in a join, so long texts stay linear in
//! time.

use serde::{Deserialize, Serialize};

use crate::actions::{compose, join_serial, ActionLibrary, BodyPart, ComposeOptions, CompositionReport, JoinKind, JoinOptions, JoinReport};
use crate::clip::{Clip, TranslationTrack};
use crate::text::lexicon::Lexicon;
use crate::text::parser::parse;
use crate::text::{Diagnostic, DiagnosticKind, JoinType, TextError, TimeTableElement};

/// The animation made from a text.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct TextAnimation {
    /// The motion time table, with clips, start times and durations filled in.
    pub elements: Vec<TimeTableElement>,
    /// Words not understood, skipped motions, truncation.
    pub diagnostics: Vec<Diagnostic>,
    /// The joined, composed motion on the canonical skeleton.
    pub clip: Clip,
    /// One report per serial join (foot-skate figures, switch frames).
    pub joins: Vec<JoinReport>,
    /// One report per Composition (switch times, blend lengths, effector jumps).
    pub compositions: Vec<CompositionReport>,
}

/// Seconds of the animation so far that a join may reach back into.
const JOIN_TAIL_SECS: f32 = 3.0;
/// A cycle (walk, run) on its own plays at least this long, seconds.
const CYCLE_MIN_SECS: f32 = 2.2;
/// Longest stated delay honoured, seconds: 「99999秒後に」 waits this long, with a notice. A
/// negative or non-finite delay is not a wait at all: it is dropped, with a notice.
pub const MAX_DELAY_SECS: f32 = 30.0;
/// Shortest one-shot that can carry a Composition (the overlay is cut to its length), seconds.
const MIN_COMPOSITION_BASE_SECS: f32 = 0.5;

/// Text → animation: [`parse`] with the library's tags, then [`animate_table`].
pub fn animate_text(text: &str, library: &ActionLibrary) -> Result<TextAnimation, TextError> {
    animate_text_with_progress(text, library, &mut |_, _| true)
}

/// [`animate_text`] reporting progress: `progress(done, total)` is called after each group of
/// the table is placed (total = number of groups); returning `false` cancels with
/// [`TextError::Cancelled`]. For long texts in the browser.
pub fn animate_text_with_progress(text: &str, library: &ActionLibrary, progress: &mut dyn FnMut(usize, usize) -> bool) -> Result<TextAnimation, TextError> {
    if text.trim().is_empty() {
        return Err(TextError::Empty);
    }
    let lex = Lexicon::for_library(library);
    let parsed = parse(text, &lex);
    animate_table_with_progress(&parsed.elements, library, parsed.diagnostics, progress)
}

/// A time table → animation. Elements whose `clip` is set play that library entry (the UI's
/// swap); others are looked up by motion tag (with "left"/"right" from the body part).
/// `diagnostics` are passed through, with any new ones added.
pub fn animate_table(elements: &[TimeTableElement], library: &ActionLibrary, diagnostics: Vec<Diagnostic>) -> Result<TextAnimation, TextError> {
    animate_table_with_progress(elements, library, diagnostics, &mut |_, _| true)
}

/// [`animate_table`] with a progress / cancel callback (see [`animate_text_with_progress`]).
pub fn animate_table_with_progress(elements: &[TimeTableElement], library: &ActionLibrary, mut diagnostics: Vec<Diagnostic>, progress: &mut dyn FnMut(usize, usize) -> bool) -> Result<TextAnimation, TextError> {
    if library.is_empty() {
        return Err(TextError::EmptyLibrary);
    }
    // An element's clip set by the caller must exist: a swap to a clip that is not there is
    // refused, not silently replaced by the default.
    if let Some(e) = elements.iter().find(|e| e.clip.is_some_and(|c| c >= library.len())) {
        return Err(TextError::NoSuchClip { index: e.index, clip: e.clip.unwrap_or(0), clips: library.len() });
    }
    // Resolve clips; drop elements without one (re-pointing references).
    let mut table: Vec<TimeTableElement> = Vec::new();
    let mut remap: Vec<Option<usize>> = Vec::with_capacity(elements.len());
    for e in elements {
        let side = match e.switched_part.or(e.body_part) {
            Some(BodyPart::LeftArm) | Some(BodyPart::LeftLeg) => Some("left"),
            Some(BodyPart::RightArm) | Some(BodyPart::RightLeg) => Some("right"),
            _ => None,
        };
        let extra: Vec<&str> = side.into_iter().collect();
        let clip = e.clip.filter(|&c| c < library.len()).or_else(|| library.find(&e.motion, &extra));
        match clip {
            Some(c) => {
                let mut e = e.clone();
                // Clamp the stated delay, with a notice (the person asked for something else).
                let asked = e.delay_secs;
                if !(asked.is_finite() && (0.0..=MAX_DELAY_SECS).contains(&asked)) {
                    e.delay_secs = if asked.is_finite() && asked > 0.0 { MAX_DELAY_SECS } else { 0.0 };
                    diagnostics.push(Diagnostic {
                        kind: DiagnosticKind::DelayClamped,
                        text: e.verb.clone(),
                        span: e.span,
                        message: if asked.is_finite() && asked > 0.0 {
                            format!("a wait of {asked} s before '{}' is longer than the {MAX_DELAY_SECS} s an animation waits; it waits {MAX_DELAY_SECS} s", e.verb)
                        } else {
                            format!("a wait of {asked} s before '{}' is not a wait; '{}' follows without one", e.verb, e.verb)
                        },
                    });
                }
                e.clip = Some(c);
                e.clip_name = library.entries[c].name.clone();
                e.alternatives = library.alternatives(c, &e.motion);
                e.previous = e.previous.and_then(|p| remap.get(p).copied().flatten()).or(table.len().checked_sub(1));
                remap.push(Some(table.len()));
                e.index = table.len();
                if e.index == 0 {
                    e.join = JoinType::Initial;
                    e.previous = None;
                } else if e.join == JoinType::Initial {
                    e.join = JoinType::Connection;
                }
                table.push(e);
            }
            None => {
                remap.push(table.len().checked_sub(1));
                diagnostics.push(Diagnostic {
                    kind: DiagnosticKind::NoClip,
                    text: e.verb.clone(),
                    span: e.span,
                    message: format!("no clip in the library is tagged '{}'; '{}' is skipped", e.motion, e.verb),
                });
            }
        }
    }
    if table.is_empty() {
        return Err(TextError::NoActions { diagnostics });
    }
    // A Composition needs a base to run on: a cycle (repeated to outlast the overlay) or a
    // one-shot long enough to carry a part of it (the overlay is then cut to the base's length,
    // below: "clap while jumping" claps during the jump). Otherwise it plays after the previous one.
    let mut base: Option<usize> = None;
    for k in 0..table.len() {
        if table[k].join != JoinType::Composition {
            base = Some(k);
            continue;
        }
        let fits = base.is_some_and(|b| {
            let be = &library.entries[table[b].clip.unwrap_or(0)];
            be.cycle_advance.is_some() || be.clip.duration_secs() >= MIN_COMPOSITION_BASE_SECS
        });
        if !fits {
            if let Some(b) = base {
                diagnostics.push(Diagnostic {
                    kind: DiagnosticKind::JoinFallback,
                    text: table[k].verb.clone(),
                    span: table[k].span,
                    message: format!("'{}' lasts longer than '{}' it should run with; it plays after it instead", table[k].verb, table[b].verb),
                });
            }
            table[k].join = if k == 0 { JoinType::Initial } else { JoinType::Transition };
            table[k].previous = k.checked_sub(1);
            table[k].switched_part = None;
            base = Some(k);
        }
    }

    // Groups: a base and its Composition elements.
    let mut groups: Vec<Vec<usize>> = Vec::new();
    for (k, e) in table.iter().enumerate() {
        match groups.last_mut() {
            Some(g) if e.join == JoinType::Composition => g.push(k),
            _ => groups.push(vec![k]),
        }
    }

    let mut joins = Vec::new();
    let mut compositions = Vec::new();
    let mut out: Option<Clip> = None;
    for (done, g) in groups.iter().enumerate() {
        if !progress(done, groups.len()) {
            return Err(TextError::Cancelled { done, total: groups.len() });
        }
        let base_el = g[0];
        let entry = &library.entries[table[base_el].clip.unwrap_or(0)];
        let overlay_secs: f32 = g[1..].iter().map(|&k| library.entries[table[k].clip.unwrap_or(0)].clip.duration_secs()).fold(0.0, f32::max);
        let mut segment = entry.clip_for(if g.len() > 1 { overlay_secs + 1.2 } else { CYCLE_MIN_SECS });
        if (segment.fps - 60.0).abs() > 1e-3 {
            segment = segment.resampled(60.0);
        }
        // Overlays, in order; each knows where it sits within the segment.
        let mut overlay_spans = Vec::new();
        for &k in &g[1..] {
            let ov = &library.entries[table[k].clip.unwrap_or(0)];
            let part = table[k].switched_part.or(ov.part).unwrap_or(BodyPart::RightArm);
            let mut ov_clip = if (ov.clip.fps - segment.fps).abs() > 1e-3 { ov.clip.resampled(segment.fps) } else { ov.clip.clone() };
            // A one-shot base shorter than the overlay carries as much of it as fits.
            let room = segment.frame_count().saturating_sub(8);
            if ov_clip.frame_count() > room && room >= 8 && ov_clip.frame_count() >= 8 {
                diagnostics.push(Diagnostic {
                    kind: DiagnosticKind::JoinFallback,
                    text: table[k].verb.clone(),
                    span: table[k].span,
                    message: format!(
                        "'{}' ({:.1} s) is longer than '{}' ({:.1} s) it runs with; its first {:.1} s play during it",
                        table[k].verb,
                        ov_clip.duration_secs(),
                        table[base_el].verb,
                        segment.duration_secs(),
                        (room - 1) as f32 / segment.fps
                    ),
                });
                let name = ov_clip.name.clone();
                ov_clip = ov_clip.slice(0, room, name);
            }
            if ov_clip.frame_count() + 8 > segment.frame_count() || ov_clip.frame_count() < 8 {
                // The base cannot carry it (a one-shot shorter than the overlay): play it on
                // its own afterwards instead.
                diagnostics.push(Diagnostic {
                    kind: DiagnosticKind::JoinFallback,
                    text: table[k].verb.clone(),
                    span: table[k].span,
                    message: format!("'{}' is longer than '{}' it should run with; it follows it instead", table[k].verb, table[base_el].verb),
                });
                overlay_spans.push((k, None));
                continue;
            }
            match compose(&segment, &ov_clip, part, &ComposeOptions::default()) {
                Ok((c, rep)) => {
                    overlay_spans.push((k, Some((rep.times.base_start_frame, rep.times.base_end_frame))));
                    segment = c;
                    compositions.push(rep);
                }
                Err(source) => return Err(TextError::Join { index: k, motion: table[k].motion.clone(), source }),
            }
        }
        let seg_frames = segment.frame_count();
        let fps = segment.fps;
        // Join the segment after what is there.
        let (offset, start_frame) = match out.take() {
            None => {
                out = Some(segment);
                (0i64, 0usize)
            }
            Some(mut whole) => {
                let kind = match table[base_el].join {
                    JoinType::Transition if table[base_el].delay_secs <= 0.0 => JoinKind::Transition,
                    _ => JoinKind::Connection,
                };
                let opts = JoinOptions { delay_secs: table[base_el].delay_secs, ..JoinOptions::default() };
                let tail_frames = ((JOIN_TAIL_SECS * fps) as usize).max(8);
                let cut = whole.frame_count().saturating_sub(tail_frames);
                let tail = whole.slice(cut, whole.frame_count(), whole.name.clone());
                let (joined, rep) = join_serial(&tail, &segment, kind, &opts).map_err(|source| TextError::Join { index: base_el, motion: table[base_el].motion.clone(), source })?;
                // Keep the frames before the tail as they are; the join replaces the tail.
                let n = whole.joint_count();
                whole.rotations.truncate(cut * n);
                for t in &mut whole.translations {
                    t.values.truncate(cut);
                }
                append(&mut whole, &joined);
                let offset = cut as i64 + rep.b_frame_offset;
                let start = cut + rep.b_start_frame;
                // The previous group ends where this one starts.
                if let Some(prev_group) = groups.iter().rev().find(|pg| pg[0] < base_el) {
                    let s = table[prev_group[0]].start_secs;
                    table[prev_group[0]].duration_secs = (start as f32 / fps - s).max(0.0);
                }
                let shifted = JoinReport {
                    window_start_frame: rep.window_start_frame + cut,
                    window_end_frame: rep.window_end_frame + cut,
                    b_start_frame: start,
                    b_frame_offset: offset,
                    ..rep
                };
                joins.push(shifted);
                out = Some(whole);
                (offset, start)
            }
        };
        table[base_el].start_secs = start_frame as f32 / fps;
        table[base_el].duration_secs = (offset + seg_frames as i64 - start_frame as i64).max(0) as f32 / fps;
        for (k, span) in overlay_spans {
            match span {
                Some((a, b)) => {
                    table[k].start_secs = ((a as i64 + offset).max(0)) as f32 / fps;
                    table[k].duration_secs = (b.saturating_sub(a)) as f32 / fps;
                }
                None => {
                    table[k].start_secs = table[base_el].start_secs;
                    table[k].duration_secs = 0.0;
                }
            }
        }
    }
    progress(groups.len(), groups.len());
    let mut clip = out.unwrap_or_else(|| library.entries[0].clip.clone());
    // A delay before the first action ("三秒後に座る"): hold its first pose that long.
    let lead_secs = table.first().map(|e| e.delay_secs).filter(|d| d.is_finite() && *d > 0.0).unwrap_or(0.0).min(MAX_DELAY_SECS);
    let hold = (lead_secs * clip.fps).round() as usize;
    if hold > 0 && clip.frame_count() > 0 {
        let n = clip.joint_count();
        let first: Vec<_> = clip.rotations[..n].to_vec();
        let mut rotations = Vec::with_capacity(clip.rotations.len() + hold * n);
        for _ in 0..hold {
            rotations.extend_from_slice(&first);
        }
        rotations.extend_from_slice(&clip.rotations);
        clip.rotations = rotations;
        for t in &mut clip.translations {
            let v0 = t.values[0];
            t.values.splice(0..0, std::iter::repeat_n(v0, hold));
        }
        let secs = hold as f32 / clip.fps;
        for e in &mut table {
            e.start_secs += secs;
        }
        for j in &mut joins {
            j.window_start_frame += hold;
            j.window_end_frame += hold;
            j.b_start_frame += hold;
            j.b_frame_offset += hold as i64;
        }
    }
    clip.name = "text animation".into();
    clip.source = "text".into();
    Ok(TextAnimation { elements: table, diagnostics, clip, joins, compositions })
}

/// Appends `b`'s frames to `a` (same skeleton, root track first).
fn append(a: &mut Clip, b: &Clip) {
    a.rotations.extend_from_slice(&b.rotations);
    if a.translations.is_empty() {
        a.translations.push(TranslationTrack { joint: 0, values: Vec::new() });
    }
    if let (Some(ta), Some(tb)) = (a.translations.first_mut(), b.translations.first()) {
        ta.values.extend_from_slice(&tb.values);
    }
}
