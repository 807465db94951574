//! BVH (Biovision Hierarchy) reader: any channel order per joint, 3- and 6-channel joints,
//! end sites, frame time, a frame-rate override and unit scaling to metres.
//!
//! The unit, when not given, is guessed from the rig (joint naming and bone lengths against
//! human proportions, [`units`]).
//!
//! Rotation channels compose in the order they are listed: `Zrotation Xrotation Yrotation`
//! means `R = Rz · Rx · Ry` applied to the child's offset, the usual BVH convention.

use std::sync::Arc;

use glam::{Quat, Vec3};

use super::{finish, stem, Format, ImportError, ImportOptions, Imported};
use crate::clip::{Clip, TranslationTrack};
use crate::skeleton::{Joint, Skeleton};

pub mod units;

#[derive(Clone, Copy, Debug, PartialEq)]
enum Channel {
    Pos(usize),
    Rot(usize),
}

struct Token<'a> {
    text: &'a str,
    line: usize,
    column: usize,
}

struct Lexer<'a> {
    src: &'a str,
    pos: usize,
    line: usize,
    line_start: usize,
    file: &'a str,
}

impl<'a> Lexer<'a> {
    fn next(&mut self) -> Option<Token<'a>> {
        let bytes = self.src.as_bytes();
        while self.pos < bytes.len() && bytes[self.pos].is_ascii_whitespace() {
            if bytes[self.pos] == b'\n' {
                self.line += 1;
                self.line_start = self.pos + 1;
            }
            self.pos += 1;
        }
        if self.pos >= bytes.len() {
            return None;
        }
        let start = self.pos;
        while self.pos < bytes.len() && !bytes[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        Some(Token { text: &self.src[start..self.pos], line: self.line, column: start - self.line_start + 1 })
    }

    fn err(&self, line: usize, column: usize, message: impl Into<String>) -> ImportError {
        ImportError::Bvh { file: self.file.to_string(), line, column, message: message.into() }
    }

    fn here(&self, message: impl Into<String>) -> ImportError {
        self.err(self.line, self.pos.saturating_sub(self.line_start) + 1, message)
    }

    fn expect_any(&mut self, what: &str) -> Result<Token<'a>, ImportError> {
        self.next().ok_or_else(|| self.here(format!("the file ends where {what} was expected")))
    }

    fn expect(&mut self, word: &str) -> Result<Token<'a>, ImportError> {
        let t = self.expect_any(&format!("'{word}'"))?;
        if t.text.eq_ignore_ascii_case(word) {
            Ok(t)
        } else {
            Err(self.err(t.line, t.column, format!("expected '{word}', found '{}'", t.text)))
        }
    }

    fn number(&mut self, what: &str) -> Result<f32, ImportError> {
        let t = self.expect_any(what)?;
        parse_number(t.text).ok_or_else(|| self.err(t.line, t.column, format!("{what}: '{}' is not a number", t.text)))
    }
}

fn parse_number(s: &str) -> Option<f32> {
    let v: f64 = s.parse().ok()?;
    if v.is_finite() {
        Some(v as f32)
    } else {
        None
    }
}

struct Raw {
    joints: Vec<Joint>,
    /// Channels per joint, in file order.
    channels: Vec<Vec<Channel>>,
}

fn parse_joint(lx: &mut Lexer, raw: &mut Raw, name: String, parent: Option<usize>) -> Result<(), ImportError> {
    let open = lx.expect_any("'{'")?;
    if open.text != "{" {
        return Err(lx.err(open.line, open.column, format!("expected '{{' after joint '{name}', found '{}'", open.text)));
    }
    lx.expect("OFFSET")?;
    let mut offset = Vec3::ZERO;
    for k in 0..3 {
        offset[k] = lx.number(&format!("offset of joint '{name}'"))?;
    }
    let index = raw.joints.len();
    raw.joints.push(Joint { name: name.clone(), parent, rest_offset: offset, rest_rotation: Quat::IDENTITY, end_site: false });
    raw.channels.push(Vec::new());
    let t = lx.expect("CHANNELS")?;
    let count_tok = lx.expect_any("a channel count")?;
    let count: usize = count_tok
        .text
        .parse()
        .map_err(|_| lx.err(count_tok.line, count_tok.column, format!("channel count of joint '{name}': '{}' is not a whole number", count_tok.text)))?;
    if count > 9 {
        return Err(lx.err(count_tok.line, count_tok.column, format!("joint '{name}' declares {count} channels; at most 6 are meaningful")));
    }
    let _ = t;
    let mut chans = Vec::with_capacity(count);
    for _ in 0..count {
        let c = lx.expect_any("a channel name")?;
        let ch = match c.text.to_ascii_lowercase().as_str() {
            "xposition" => Channel::Pos(0),
            "yposition" => Channel::Pos(1),
            "zposition" => Channel::Pos(2),
            "xrotation" => Channel::Rot(0),
            "yrotation" => Channel::Rot(1),
            "zrotation" => Channel::Rot(2),
            _ => {
                return Err(lx.err(
                    c.line,
                    c.column,
                    format!("joint '{name}' declares {count} channels but '{}' is not a channel name", c.text),
                ))
            }
        };
        chans.push(ch);
    }
    raw.channels[index] = chans;
    loop {
        let t = lx.expect_any("'JOINT', 'End Site' or '}'")?;
        match t.text {
            "}" => return Ok(()),
            s if s.eq_ignore_ascii_case("JOINT") => {
                let n = lx.expect_any("a joint name")?;
                parse_joint(lx, raw, n.text.to_string(), Some(index))?;
            }
            s if s.eq_ignore_ascii_case("End") => {
                lx.expect("Site")?;
                let open = lx.expect_any("'{'")?;
                if open.text != "{" {
                    return Err(lx.err(open.line, open.column, format!("expected '{{' after End Site, found '{}'", open.text)));
                }
                lx.expect("OFFSET")?;
                let mut o = Vec3::ZERO;
                for k in 0..3 {
                    o[k] = lx.number("End Site offset")?;
                }
                let close = lx.expect_any("'}'")?;
                if close.text != "}" {
                    return Err(lx.err(close.line, close.column, format!("expected '}}' closing End Site, found '{}'", close.text)));
                }
                raw.joints.push(Joint {
                    name: format!("{name}_End"),
                    parent: Some(index),
                    rest_offset: o,
                    rest_rotation: Quat::IDENTITY,
                    end_site: true,
                });
                raw.channels.push(Vec::new());
            }
            other => {
                return Err(lx.err(t.line, t.column, format!("expected 'JOINT', 'End Site' or '}}' in joint '{name}', found '{other}'")))
            }
        }
    }
}

/// Metres per file unit guessed from the rig's naming and bone lengths at rest (see
/// [`units::guess`], which the importer calls with the first frame's translations too).
pub fn guess_unit_scale(skeleton: &Skeleton) -> f32 {
    units::guess(skeleton, &[]).unit.metres
}

fn axis_rotation(axis: usize, degrees: f32) -> Quat {
    let r = degrees.to_radians();
    match axis {
        0 => Quat::from_rotation_x(r),
        1 => Quat::from_rotation_y(r),
        _ => Quat::from_rotation_z(r),
    }
}

/// Reads a BVH file.
pub fn import(file: &str, bytes: &[u8], options: &ImportOptions) -> Result<Imported, ImportError> {
    let src = std::str::from_utf8(bytes).map_err(|e| ImportError::Bvh {
        file: file.to_string(),
        line: 1 + bytes[..e.valid_up_to()].iter().filter(|&&b| b == b'\n').count(),
        column: 1,
        message: "the file is not text (invalid UTF-8)".into(),
    })?;
    let src = src.trim_start_matches('\u{feff}');
    let mut lx = Lexer { src, pos: 0, line: 1, line_start: 0, file };
    lx.expect("HIERARCHY")?;
    let mut raw = Raw { joints: Vec::new(), channels: Vec::new() };
    loop {
        let t = lx.expect_any("'ROOT' or 'MOTION'")?;
        if t.text.eq_ignore_ascii_case("ROOT") {
            let n = lx.expect_any("a root joint name")?;
            parse_joint(&mut lx, &mut raw, n.text.to_string(), None)?;
        } else if t.text.eq_ignore_ascii_case("MOTION") {
            break;
        } else {
            return Err(lx.err(t.line, t.column, format!("expected 'ROOT' or 'MOTION', found '{}'", t.text)));
        }
    }
    if raw.joints.is_empty() {
        return Err(lx.here("the hierarchy has no ROOT joint"));
    }
    lx.expect("Frames:")?;
    let ft = lx.expect_any("a frame count")?;
    let frames: usize =
        ft.text.parse().map_err(|_| lx.err(ft.line, ft.column, format!("frame count: '{}' is not a whole number", ft.text)))?;
    lx.expect("Frame")?;
    lx.expect("Time:")?;
    let tt = lx.expect_any("a frame time")?;
    let frame_time = parse_number(tt.text)
        .filter(|v| *v > 0.0)
        .ok_or_else(|| lx.err(tt.line, tt.column, format!("frame time: '{}' is not a positive number", tt.text)))?;
    if frames == 0 {
        return Err(lx.err(ft.line, ft.column, "the file declares 0 frames"));
    }

    let n_channels: usize = raw.channels.iter().map(Vec::len).sum();
    let n_joints = raw.joints.len();
    // Refuse a frame count the tab cannot hold before reserving anything for it.
    if frames.saturating_mul(n_joints) > super::MAX_SAMPLES {
        return Err(ImportError::TooLarge {
            file: file.to_string(),
            what: format!("{frames} frames of {n_joints} joints (line {}: 'Frames: {frames}')", ft.line),
            limit: format!("{} joint samples", super::MAX_SAMPLES),
        });
    }
    // A frame needs at least one byte per channel value plus a separator: a count beyond what
    // the remaining bytes can hold is found out while reading, so reserve only what can exist.
    let room_frames = (lx.src.len() - lx.pos) / (2 * n_channels).max(1) + 1;
    let reserve_frames = frames.min(room_frames);
    let guessed = options.unit_scale.is_none();

    // Joints with position channels get a translation track.
    let mut track_of = vec![usize::MAX; n_joints];
    let mut tracks: Vec<TranslationTrack> = Vec::new();
    for (j, ch) in raw.channels.iter().enumerate() {
        if ch.iter().any(|c| matches!(c, Channel::Pos(_))) {
            track_of[j] = tracks.len();
            tracks.push(TranslationTrack { joint: j, values: Vec::with_capacity(reserve_frames) });
        }
    }
    let mut rotations = Vec::with_capacity(reserve_frames * n_joints);
    let mut values = vec![0f32; n_channels];
    for f in 0..frames {
        // A frame is one line of numbers: read it as a line so a short row is caught there.
        let (line_no, row) = next_line(&mut lx);
        let Some(row) = row else {
            return Err(ImportError::Bvh {
                file: file.to_string(),
                line: line_no,
                column: 1,
                message: format!("the file ends after {f} of the {frames} frames it declares (truncated?)"),
            });
        };
        let mut k = 0;
        for (col, tok) in tokens_with_columns(row) {
            if k >= n_channels {
                return Err(ImportError::Bvh {
                    file: file.to_string(),
                    line: line_no,
                    column: col,
                    message: format!("frame {} has more than the {n_channels} values the hierarchy's channels declare", f + 1),
                });
            }
            values[k] = parse_number(tok).ok_or_else(|| ImportError::Bvh {
                file: file.to_string(),
                line: line_no,
                column: col,
                message: format!("frame {}: '{tok}' is not a number", f + 1),
            })?;
            k += 1;
        }
        if k != n_channels {
            return Err(ImportError::Bvh {
                file: file.to_string(),
                line: line_no,
                column: 1,
                message: format!("frame {} has {k} values but the hierarchy declares {n_channels} channels", f + 1),
            });
        }
        let mut v = 0;
        for (j, chans) in raw.channels.iter().enumerate() {
            let mut q = Quat::IDENTITY;
            let mut pos = raw.joints[j].rest_offset;
            for c in chans {
                match *c {
                    Channel::Rot(axis) => q *= axis_rotation(axis, values[v]),
                    Channel::Pos(axis) => pos[axis] = values[v],
                }
                v += 1;
            }
            rotations.push(q.normalize());
            if track_of[j] != usize::MAX {
                tracks[track_of[j]].values.push(pos);
            }
        }
    }
    // Anything after the declared frames other than blank space is suspicious but harmless.
    let mut warnings = Vec::new();
    if let (_, Some(extra)) = next_line(&mut lx) {
        if !extra.trim().is_empty() {
            warnings.push(format!("{file}: data after the {frames} declared frames was ignored"));
        }
    }
    // The unit: as given, or guessed from the rig as the first frame draws it (a joint's
    // position channels, where it has them, stand for its offset). Values were read in file
    // units and are scaled once here.
    let unscaled = Skeleton { joints: raw.joints };
    let guess = guessed.then(|| {
        let mut local: Vec<Vec3> = unscaled.joints.iter().map(|j| j.rest_offset).collect();
        for t in &tracks {
            if let (Some(l), Some(v)) = (local.get_mut(t.joint), t.values.first()) {
                *l = *v;
            }
        }
        units::guess(&unscaled, &local)
    });
    let scale = options.unit_scale.or(guess.map(|g| g.unit.metres)).unwrap_or(1.0);
    for t in &mut tracks {
        for v in &mut t.values {
            *v *= scale;
        }
    }
    let joints: Vec<Joint> =
        unscaled.joints.into_iter().map(|mut j| {
            j.rest_offset *= scale;
            j
        }).collect();
    let skeleton = Arc::new(Skeleton { joints });
    let fps = options.fps_override.unwrap_or(1.0 / frame_time);
    let clip = Clip {
        name: stem(file).to_string(),
        source: file.to_string(),
        fps,
        skeleton: skeleton.clone(),
        rotations,
        translations: tracks,
    };
    let mut imported = finish(Format::Bvh, file, skeleton, vec![clip], None, warnings)?;
    if imported.status.is_humanoid() {
        if let Some(w) = height_warning(file, &imported.clips[0], scale, guess.as_ref()) {
            imported.warnings.push(w);
        }
    }
    Ok(imported)
}

/// Plausible standing height of a person, metres (a toddler to a very tall adult, with room).
pub const PLAUSIBLE_HEIGHT_M: std::ops::RangeInclusive<f32> = 0.5..=2.5;

/// The figure's height: the largest vertical extent of its joints over the clip's first
/// frame and its rest pose, metres.
pub fn figure_height_m(clip: &Clip) -> f32 {
    let extent = |p: &[Vec3]| {
        let (lo, hi) = p.iter().fold((f32::MAX, f32::MIN), |(lo, hi), v| (lo.min(v.y), hi.max(v.y)));
        if p.is_empty() { 0.0 } else { hi - lo }
    };
    extent(&clip.skeleton.rest_positions()).max(extent(&clip.world_positions(0)))
}

/// A warning when a humanoid figure's height is implausible for the unit scale used (a file in
/// centimetres read as decimetres stands 10× too tall): the clip is kept as read, and the
/// person is told the height and how to fix it.
fn height_warning(file: &str, clip: &Clip, scale: f32, guess: Option<&units::UnitGuess>) -> Option<String> {
    let h = figure_height_m(clip);
    if PLAUSIBLE_HEIGHT_M.contains(&h) {
        return None;
    }
    let how = guess.map_or_else(|| "as given".to_string(), units::UnitGuess::describe);
    Some(format!(
        "{file}: the figure is {h:.2} m tall at {scale} m per file unit ({how}); a person is {:.1}–{:.1} m: if the unit is wrong, import again with the right unitScale (metres per unit, e.g. 0.01 for centimetres)",
        PLAUSIBLE_HEIGHT_M.start(),
        PLAUSIBLE_HEIGHT_M.end()
    ))
}

/// The next non-empty line after the lexer's position, with its 1-based line number.
fn next_line<'a>(lx: &mut Lexer<'a>) -> (usize, Option<&'a str>) {
    let bytes = lx.src.as_bytes();
    loop {
        // Finish the current line if we are in the middle of one.
        if lx.pos >= bytes.len() {
            return (lx.line, None);
        }
        let start = lx.pos;
        let end = lx.src[start..].find('\n').map(|i| start + i).unwrap_or(bytes.len());
        let line = &lx.src[start..end];
        let line_no = lx.line;
        lx.pos = (end + 1).min(bytes.len().max(end));
        if end < bytes.len() {
            lx.line += 1;
            lx.line_start = end + 1;
        }
        if !line.trim().is_empty() {
            return (line_no, Some(line));
        }
    }
}

fn tokens_with_columns(line: &str) -> impl Iterator<Item = (usize, &str)> {
    line.split_ascii_whitespace().map(move |t| (t.as_ptr() as usize - line.as_ptr() as usize + 1, t))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::import::import_bytes;

    const TWO: &str = "HIERARCHY\nROOT hip\n{\n OFFSET 0 0 0\n CHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation Xrotation\n JOINT knee\n {\n  OFFSET 0 -40 0\n  CHANNELS 3 Xrotation Zrotation Yrotation\n  End Site\n  {\n   OFFSET 0 -40 0\n  }\n }\n}\nMOTION\nFrames: 2\nFrame Time: 0.0333333\n0 90 0 0 0 0 0 0 0\n10 90 0 0 0 0 90 0 0\n";

    #[test]
    fn reads_hierarchy_channels_and_units() {
        let im = import_bytes("two.bvh", TWO.as_bytes(), &ImportOptions::default()).unwrap();
        let c = &im.clips[0];
        assert_eq!(c.frame_count(), 2);
        assert_eq!(im.skeleton.len(), 3);
        assert_eq!(im.skeleton.animated_joint_count(), 2);
        assert!((c.fps - 30.0).abs() < 0.01);
        // 90 cm tall figure: centimetres.
        let p = c.world_positions(0);
        assert!((p[0].y - 0.9).abs() < 1e-5);
        assert!((p[2].y - 0.1).abs() < 1e-5);
        // Frame 2: knee rotated 90 deg about X: the shin points along -Z... (+/-) horizontally.
        let p = c.world_positions(1);
        assert!((p[0].x - 0.1).abs() < 1e-5);
        assert!((p[2].y - 0.5).abs() < 1e-4, "{:?}", p[2]);
        assert!((p[2].z.abs() - 0.4).abs() < 1e-4, "{:?}", p[2]);
    }

    #[test]
    fn fps_override() {
        let o = ImportOptions { fps_override: Some(60.0), ..Default::default() };
        let im = import_bytes("two.bvh", TWO.as_bytes(), &o).unwrap();
        assert_eq!(im.clips[0].fps, 60.0);
    }

    #[test]
    fn channel_order_matters() {
        // ZXY vs XYZ of the same numbers give different poses.
        let zxy = TWO.replace("Xrotation Zrotation Yrotation", "Zrotation Xrotation Yrotation");
        let row = "0 90 0 0 0 0 0 0 0\n";
        let a = import_bytes("a.bvh", TWO.replacen(row, "0 90 0 0 0 0 30 40 0\n", 1).as_bytes(), &Default::default()).unwrap();
        let b = import_bytes("b.bvh", zxy.replacen(row, "0 90 0 0 0 0 30 40 0\n", 1).as_bytes(), &Default::default()).unwrap();
        let pa = a.clips[0].world_positions(0);
        let pb = b.clips[0].world_positions(0);
        assert!((pa[2] - pb[2]).length() > 1e-3);
    }
}
