//! Text to animation (spec §H, paper 003 §2–3): Japanese or English sentences become a motion
//! time table, and the table becomes one joined, composed clip.
//!
//! [`parse`] reads the sentences with a small bilingual lexicon ([`lexicon`]) — no external
//! language tools — and gives the table of spec §H: actor, motion, switched body part, how
//! each element joins the previous one (Connection, Transition, Composition), the previous
//! element, a stated delay. [`animate_text`] looks the motions up in an
//! [`ActionLibrary`](crate::actions::ActionLibrary) by name and tag, composes parallel
//! elements, joins serial ones (spec §I, [`crate::actions`]), and fills in each element's
//! start time in the resulting clip. Words it does not know are reported with their position
//! in the text; everything else still plays.
//!
//! For the web layer: build one [`ActionLibrary::builtin`](crate::actions::ActionLibrary::builtin)
//! (add the person's clips with `add_clip(&clip, &tags, part)`), then call
//! [`animate_text`] (or [`animate_text_with_progress`] for long texts) and hand the
//! [`TextAnimation`] to JavaScript as it is: it serialises in camelCase (`elements[i].join` is
//! `"initial" | "connection" | "transition" | "composition"`, `previous` a 0-based index or
//! null, `span.utf16Start/utf16End` index the JavaScript string, `clip` the joined motion on
//! the canonical skeleton). To swap an element's clip, set its `clip` to another entry carrying
//! the same motion tag (`ActionLibrary::alternatives`) and pass the edited elements to
//! [`animate_table`].

pub mod animate;
pub mod lexicon;
pub mod parser;

use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::actions::{ActionError, BodyPart};

pub use animate::{animate_table, animate_table_with_progress, animate_text, animate_text_with_progress, TextAnimation, MAX_DELAY_SECS};
pub use lexicon::Lexicon;
pub use parser::{parse, ParsedText, MAX_ELEMENTS, MAX_TEXT_CHARS};

/// A stretch of the input text. `start..end` in Unicode scalar values (Rust `chars`), and the
/// same in UTF-16 code units for JavaScript strings (`utf16Start..utf16End`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct TextSpan {
    pub start: usize,
    pub end: usize,
    pub utf16_start: usize,
    pub utf16_end: usize,
}

/// How an element joins the previous one (spec §H).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub enum JoinType {
    /// The first action (the paper's 初期動作).
    Initial,
    /// Follows without overlap, after any stated delay (。, ".", "after that", てから).
    Connection,
    /// Follows with overlap (て, 、, ",", "then", "and").
    Transition,
    /// Runs in parallel with its previous element, replacing a body part (ながら, "while").
    Composition,
}

/// One element of the motion time table.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct TimeTableElement {
    /// 0-based position in the table.
    pub index: usize,
    /// Who moves (太郎, "Taro"); empty when the text does not say.
    pub actor: String,
    /// The motion tag ("run", "wave", "gutsy pose"): what the library is searched for.
    pub motion: String,
    /// The verb as written (走って, "kicks").
    pub verb: String,
    /// Where the verb is in the text.
    pub span: TextSpan,
    pub join: JoinType,
    /// The element this one joins (`None` for the first).
    pub previous: Option<usize>,
    /// A body part the sentence names for this action (右手 → rightArm).
    pub body_part: Option<BodyPart>,
    /// For Composition: the body part switched in from this element's motion.
    pub switched_part: Option<BodyPart>,
    /// A stated delay before this element ("2秒後に", "after 2 seconds"), seconds.
    pub delay_secs: f32,
    /// The library entry playing it (filled when animated; may be set by the UI to swap).
    pub clip: Option<usize>,
    /// That entry's name.
    pub clip_name: String,
    /// Other library entries with the same motion tag, for the UI's swap menu (filled when
    /// animated).
    #[serde(default)]
    pub alternatives: Vec<usize>,
    /// Start in the animation, seconds (filled when animated).
    pub start_secs: f32,
    /// How long it plays in the animation, seconds (filled when animated).
    pub duration_secs: f32,
}

/// What kind of remark a diagnostic is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub enum DiagnosticKind {
    /// A clause whose verb the lexicon does not know; the clause is skipped.
    UnknownVerb,
    /// A known motion the library has no clip for; the element is skipped.
    NoClip,
    /// The text has more sentences or characters than one animation takes; the rest is
    /// ignored.
    Truncated,
    /// Japanese and English in one text: read, but said, in case it was not meant.
    MixedLanguages,
    /// A join could not be made as written and was made another way.
    JoinFallback,
    /// A stated delay outside 0..=MAX_DELAY_SECS was clamped (99999 s) or dropped (−5 s).
    DelayClamped,
}

/// A remark about the text, with where it applies.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct Diagnostic {
    pub kind: DiagnosticKind,
    /// The words concerned, as written.
    pub text: String,
    pub span: TextSpan,
    /// A sentence for the person.
    pub message: String,
}

/// Why no animation could be made at all.
#[derive(Debug, Error, PartialEq)]
pub enum TextError {
    #[error("the text is empty: type a sentence such as 「太郎は走って，ボールを蹴る．」 or \"Taro runs, then kicks the ball.\"")]
    Empty,
    #[error("no known action in the text; not understood: {}", unknown_list(.diagnostics))]
    NoActions { diagnostics: Vec<Diagnostic> },
    #[error("the action library is empty")]
    EmptyLibrary,
    #[error("cancelled after {done} of {total} parts")]
    Cancelled { done: usize, total: usize },
    #[error("element {index} ({motion}): {source}")]
    Join { index: usize, motion: String, source: ActionError },
    #[error("element {index}: clip {clip} does not exist (the action library has {clips}: 0..{clips})")]
    NoSuchClip { index: usize, clip: usize, clips: usize },
}

/// At most this many unknown words are listed in an error message; the rest are counted
/// ("… and 9,990 more"): every word is still in the diagnostics.
pub const MAX_LISTED_WORDS: usize = 10;
/// Longest word quoted in an error message, characters (longer ones are cut with "…").
pub const MAX_QUOTED_CHARS: usize = 40;

/// The unknown words of an error message, bounded: a 10,000-word text gives a message of a
/// few hundred characters, not tens of thousands.
fn unknown_list(d: &[Diagnostic]) -> String {
    let unknown: Vec<&Diagnostic> = d.iter().filter(|x| x.kind == DiagnosticKind::UnknownVerb).collect();
    if unknown.is_empty() {
        return "nothing".into();
    }
    let quote = |t: &str| {
        if t.chars().count() > MAX_QUOTED_CHARS {
            format!("{}…", t.chars().take(MAX_QUOTED_CHARS).collect::<String>())
        } else {
            t.to_string()
        }
    };
    let mut out = unknown.iter().take(MAX_LISTED_WORDS).map(|x| format!("'{}' at {}", quote(&x.text), x.span.start)).collect::<Vec<_>>().join(", ");
    if unknown.len() > MAX_LISTED_WORDS {
        out.push_str(&format!(" and {} more", unknown.len() - MAX_LISTED_WORDS));
    }
    out
}
