//! The parser: sentences → motion time table (spec §H), without start times.
//!
//! One pass turns the text into tokens — verbs (with their form), body parts, punctuation,
//! connectives, stated delays and leftover words — for Japanese and English alike, so mixed
//! text reads too. A second pass builds the table: every recognised verb is an element, and
//! what stands between it and the previous verb decides the join, strongest first:
//! parallel (ながら/つつ, 同時に, "while", "as", "at the same time") → Composition; a full
//! stop, "after that", それから, てから or a stated delay → Connection; て, a comma, "then",
//! "and" → Transition. A clause with content but no known verb is reported with the position
//! of its likely verb and skipped. Parallel elements are ordered with the whole-body motion
//! first (the base) and the part motions after it, so 「歩きながら右手を振る」 and
//! "wave the right hand while walking" give the same table.

use std::collections::HashMap;

use serde::{Deserialize, Serialize};

use crate::actions::BodyPart;
use crate::text::lexicon::{Lexicon, VerbForm, EN_PARTS, JA_PARTS};
use crate::text::{Diagnostic, DiagnosticKind, JoinType, TextSpan, TimeTableElement};

/// Longest text read, in characters; the rest is ignored with a diagnostic.
pub const MAX_TEXT_CHARS: usize = 20_000;
/// Most elements in one table; the rest is ignored with a diagnostic.
pub const MAX_ELEMENTS: usize = 300;

/// The parser's result: the table (no start times yet) and remarks.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub struct ParsedText {
    pub elements: Vec<TimeTableElement>,
    pub diagnostics: Vec<Diagnostic>,
}

#[derive(Clone, Debug, PartialEq)]
enum Tok {
    Verb { motion: String, form: VerbForm },
    Part(BodyPart),
    Comma,
    Stop,
    Then,
    After,
    /// `lead`: "while"/"as", which may open a clause that comes before its main clause.
    Parallel { lead: bool },
    Delay(f32),
    Word { text: String, ja: bool },
    /// An unknown Japanese word that looks like a conjugated verb (踊って, 踊りながら).
    UnknownVerb { text: String, form: VerbForm },
}

#[derive(Clone, Debug)]
struct Token {
    tok: Tok,
    start: usize,
    end: usize,
}

fn is_boundary_char(c: char) -> bool {
    matches!(c, '、' | '，' | ',' | '。' | '．' | '.' | '!' | '！' | '?' | '？' | ';' | '；' | '\n' | '\r') || c.is_whitespace()
}

fn is_en_char(c: char) -> bool {
    c.is_ascii_alphanumeric() || c == '\'' || c == '-'
}

fn digit_value(c: char) -> Option<u32> {
    match c {
        '0'..='9' => Some(c as u32 - '0' as u32),
        '０'..='９' => Some(c as u32 - '０' as u32),
        _ => None,
    }
}

/// A number at `i` (ASCII or full-width digits with an optional decimal part, or kanji
/// numerals up to 99): value and length in chars.
fn number_at(cs: &[char], i: usize) -> Option<(f32, usize)> {
    let mut k = i;
    let mut v = 0.0f32;
    while k < cs.len() {
        match digit_value(cs[k]) {
            Some(d) => v = v * 10.0 + d as f32,
            None => break,
        }
        k += 1;
    }
    if k > i {
        if k + 1 < cs.len() && matches!(cs[k], '.' | '．') && digit_value(cs[k + 1]).is_some() {
            k += 1;
            let mut scale = 0.1;
            while k < cs.len() {
                match digit_value(cs[k]) {
                    Some(d) => v += d as f32 * scale,
                    None => break,
                }
                scale *= 0.1;
                k += 1;
            }
        }
        return Some((v, k - i));
    }
    let kanji = |c: char| "一二三四五六七八九".find(c).map(|p| (p / '一'.len_utf8()) as f32 + 1.0);
    let mut total = 0.0;
    let mut cur = 0.0;
    while k < cs.len() {
        if let Some(d) = kanji(cs[k]) {
            cur = d;
        } else if cs[k] == '十' {
            total += if cur == 0.0 { 10.0 } else { cur * 10.0 };
            cur = 0.0;
        } else {
            break;
        }
        k += 1;
    }
    (k > i).then_some((total + cur, k - i))
}

fn word_number(w: &str) -> Option<f32> {
    Some(match w {
        "a" | "an" | "one" => 1.0,
        "two" => 2.0,
        "three" => 3.0,
        "four" => 4.0,
        "five" => 5.0,
        "six" => 6.0,
        "seven" => 7.0,
        "eight" => 8.0,
        "nine" => 9.0,
        "ten" => 10.0,
        "half" => 0.5,
        _ => return w.parse::<f32>().ok().filter(|v| v.is_finite() && *v >= 0.0),
    })
}

fn starts_with(cs: &[char], i: usize, s: &str) -> bool {
    let mut k = i;
    for c in s.chars() {
        if k >= cs.len() || cs[k] != c {
            return false;
        }
        k += 1;
    }
    true
}

/// "A while" and "a moment", seconds.
const A_WHILE_SECS: f32 = 1.5;
const A_MOMENT_SECS: f32 = 1.0;

/// Japanese delays at `i`: (seconds, length).
fn ja_delay(cs: &[char], i: usize) -> Option<(f32, usize)> {
    for (s, secs) in [("しばらくしてから", A_WHILE_SECS), ("しばらくして", A_WHILE_SECS), ("しばらく後に", A_WHILE_SECS), ("しばらく経って", A_WHILE_SECS), ("しばらくたって", A_WHILE_SECS), ("少ししてから", A_MOMENT_SECS), ("少しして", A_MOMENT_SECS), ("少し後に", A_MOMENT_SECS), ("一瞬後に", 0.3)] {
        if starts_with(cs, i, s) {
            return Some((secs, s.chars().count()));
        }
    }
    // A sign is read, not skipped: 「-5秒後に」 is a negative delay (refused with a notice when
    // animated), not a 5 s one.
    let sign_len = if starts_with(cs, i, "マイナス") { 4 } else if matches!(cs.get(i), Some('-' | '−' | '－')) { 1 } else { 0 };
    let (v, n) = number_at(cs, i + sign_len)?;
    let v = if sign_len > 0 { -v } else { v };
    let n = n + sign_len;
    let mut k = i + n;
    if k < cs.len() && cs[k] == '秒' {
        k += 1;
        if k < cs.len() && cs[k] == '間' {
            k += 1;
        }
        for s in ["後に", "後", "ごに", "ご", "経ってから", "経って", "たってから", "たって", "してから", "して", "待ってから", "待って", "まってから", "まって"] {
            if starts_with(cs, k, s) {
                return Some((v, k + s.chars().count() - i));
            }
        }
    }
    None
}

struct EnWord {
    lower: String,
    raw: String,
    start: usize,
    end: usize,
}

fn en_words(cs: &[char], mut i: usize, max: usize) -> Vec<EnWord> {
    let mut out = Vec::new();
    while out.len() < max && i < cs.len() {
        while i < cs.len() && cs[i] == ' ' {
            i += 1;
        }
        if i >= cs.len() || !is_en_char(cs[i]) {
            break;
        }
        let s = i;
        while i < cs.len() && (is_en_char(cs[i]) || (cs[i] == '.' && i > s && i + 1 < cs.len() && cs[i - 1].is_ascii_digit() && cs[i + 1].is_ascii_digit())) {
            i += 1;
        }
        let raw: String = cs[s..i].iter().collect();
        out.push(EnWord { lower: raw.to_lowercase(), raw, start: s, end: i });
    }
    out
}

fn words_match(ws: &[EnWord], pat: &[&str]) -> bool {
    ws.len() >= pat.len() && ws.iter().zip(pat).all(|(w, p)| w.lower == *p)
}

/// English delay at the start of `ws`: (seconds, words used).
fn en_delay(ws: &[EnWord]) -> Option<(f32, usize)> {
    let secs_word = |w: &str| matches!(w, "second" | "seconds" | "sec" | "secs" | "s");
    for (pat, secs) in [(&["after", "a", "while"][..], A_WHILE_SECS), (&["a", "while", "later"], A_WHILE_SECS), (&["after", "a", "moment"], A_MOMENT_SECS), (&["a", "moment", "later"], A_MOMENT_SECS), (&["after", "a", "pause"], A_MOMENT_SECS)] {
        if words_match(ws, pat) {
            return Some((secs, pat.len()));
        }
    }
    let get = |k: usize| ws.get(k).map(|w| w.lower.as_str()).unwrap_or("");
    // after [half a | N] second(s)
    if get(0) == "after" || matches!(get(0), "wait" | "waits" | "waited" | "waiting") {
        if get(1) == "half" && get(2) == "a" && secs_word(get(3)) {
            return Some((0.5, 4));
        }
        if let Some(v) = word_number(get(1)) {
            if secs_word(get(2)) {
                return Some((v, 3));
            }
        }
    }
    // N second(s) later
    if let Some(v) = word_number(get(0)) {
        if secs_word(get(1)) && get(2) == "later" {
            return Some((v, 3));
        }
    }
    None
}

const EN_STOPWORDS: &[&str] = &[
    "the", "a", "an", "his", "her", "their", "my", "your", "its", "our", "with", "to", "at", "of", "in", "on", "he", "she", "they", "it", "i", "we", "you", "him", "them", "me", "us", "up", "down", "again", "slowly", "quickly", "happily", "then", "so", "too", "also", "very", "once", "twice", "there", "here", "is", "are", "was", "were", "be", "been", "will", "would", "can", "could", "does", "do", "did", "not", "ball", "hand", "hands", "arm", "arms", "head", "around", "forward", "back", "while", "as", "and", "after", "that",
];

const PRONOUNS: &[&str] = &[
    "he", "she", "they", "it", "i", "we", "you", "the", "a", "an", "then", "and", "after", "while", "as", "next", "finally", "first", "suddenly", "now", "do", "does", "did", "make", "makes", "strike", "strikes", "give", "gives", "let", "please", "slowly", "quickly", "happily", "someone", "everyone",
];

fn tokenize(cs: &[char], lex: &Lexicon) -> Vec<Token> {
    let mut out: Vec<Token> = Vec::new();
    // The Japanese surface forms by first character, each list in the lexicon's own order
    // (longest first), so the first match below is the one a scan of the whole lexicon finds;
    // a scan at every character made long Japanese text cost ~10 µs a character.
    let mut ja_by_first: std::collections::HashMap<char, Vec<usize>> = std::collections::HashMap::new();
    for (k, s) in lex.ja.iter().enumerate() {
        if let Some(&c) = s.chars.first() {
            ja_by_first.entry(c).or_default().push(k);
        }
    }
    let mut ja_word: Option<(usize, String)> = None;
    let flush = |out: &mut Vec<Token>, ja_word: &mut Option<(usize, String)>, end: usize| {
        if let Some((s, text)) = ja_word.take() {
            let t = text.trim_matches(|c: char| c.is_whitespace() || matches!(c, '「' | '」' | '『' | '』' | '（' | '）' | '(' | ')' | '"' | '“' | '”'));
            if !t.is_empty() {
                out.push(Token { tok: Tok::Word { text: t.to_string(), ja: true }, start: s, end });
            }
        }
    };
    let mut i = 0;
    while i < cs.len() {
        let c = cs[i];
        // Punctuation.
        let punct = match c {
            '、' | '，' | ',' => Some(Tok::Comma),
            '。' | '．' | '!' | '！' | '?' | '？' | ';' | '；' | '\n' => Some(Tok::Stop),
            '.' if !(i > 0 && i + 1 < cs.len() && cs[i - 1].is_ascii_digit() && cs[i + 1].is_ascii_digit()) => Some(Tok::Stop),
            _ => None,
        };
        if let Some(tok) = punct {
            flush(&mut out, &mut ja_word, i);
            out.push(Token { tok, start: i, end: i + 1 });
            i += 1;
            continue;
        }
        if c.is_whitespace() || matches!(c, '「' | '」' | '『' | '』' | '（' | '）' | '(' | ')' | '"' | '“' | '”' | '・' | '…') {
            flush(&mut out, &mut ja_word, i);
            i += 1;
            continue;
        }
        if c.is_ascii_alphanumeric() && !(digit_value(c).is_some() && ja_delay(cs, i).is_some()) {
            flush(&mut out, &mut ja_word, i);
            let ws = en_words(cs, i, 6);
            if ws.is_empty() {
                i += 1;
                continue;
            }
            let span = |n: usize| (ws[0].start, ws[n - 1].end);
            let emit = |tok: Tok, n: usize, out: &mut Vec<Token>| -> usize {
                let (s, e) = span(n);
                out.push(Token { tok, start: s, end: e });
                e
            };
            if let Some((secs, n)) = en_delay(&ws) {
                i = emit(Tok::Delay(secs), n, &mut out);
                continue;
            }
            let conn: Option<(Tok, usize)> = if words_match(&ws, &["and", "then"]) {
                Some((Tok::Then, 2))
            } else if words_match(&ws, &["after", "that"]) || words_match(&ws, &["after", "this"]) {
                Some((Tok::After, 2))
            } else if words_match(&ws, &["at", "the", "same", "time"]) {
                Some((Tok::Parallel { lead: false }, 4))
            } else {
                match ws[0].lower.as_str() {
                    "then" | "and" | "next" => Some((Tok::Then, 1)),
                    "afterwards" | "afterward" | "later" | "finally" => Some((Tok::After, 1)),
                    "while" | "whilst" | "as" => Some((Tok::Parallel { lead: true }, 1)),
                    "meanwhile" | "simultaneously" => Some((Tok::Parallel { lead: false }, 1)),
                    _ => None,
                }
            };
            if let Some((tok, n)) = conn {
                i = emit(tok, n, &mut out);
                continue;
            }
            if let Some((part, n)) = EN_PARTS.iter().find(|(p, _)| words_match(&ws, p)).map(|(p, b)| (*b, p.len())) {
                i = emit(Tok::Part(part), n, &mut out);
                continue;
            }
            let verb = lex.en.iter().find(|e| ws.len() >= e.words.len() && e.words.iter().zip(&ws).all(|(a, b)| *a == b.lower));
            if let Some(v) = verb {
                let (motion, n) = (v.motion.clone(), v.words.len());
                i = emit(Tok::Verb { motion, form: VerbForm::Plain }, n, &mut out);
                continue;
            }
            let w = &ws[0];
            out.push(Token { tok: Tok::Word { text: w.raw.clone(), ja: false }, start: w.start, end: w.end });
            i = w.end;
            continue;
        }
        // Japanese.
        if let Some((secs, n)) = ja_delay(cs, i) {
            flush(&mut out, &mut ja_word, i);
            out.push(Token { tok: Tok::Delay(secs), start: i, end: i + n });
            i += n;
            continue;
        }
        let conn = [("それから", Some(Tok::After)), ("その後", Some(Tok::After)), ("そのあと", Some(Tok::After)), ("続いて", Some(Tok::Then)), ("次に", Some(Tok::Then)), ("と同時に", Some(Tok::Parallel { lead: false })), ("同時に", Some(Tok::Parallel { lead: false })), ("そして", None), ("それで", None)];
        if let Some((s, tok)) = conn.iter().find(|(s, _)| starts_with(cs, i, s)) {
            flush(&mut out, &mut ja_word, i);
            let n = s.chars().count();
            if let Some(t) = tok {
                out.push(Token { tok: t.clone(), start: i, end: i + n });
            }
            i += n;
            continue;
        }
        let verb = ja_by_first.get(&c).and_then(|ks| {
            ks.iter().map(|&k| &lex.ja[k]).find(|s| starts_with_chars(cs, i, &s.chars) && (s.form != VerbForm::Stem || cs.get(i + s.chars.len()).is_none_or(|c| is_boundary_char(*c))))
        });
        if let Some(v) = verb {
            flush(&mut out, &mut ja_word, i);
            let n = v.chars.len();
            out.push(Token { tok: Tok::Verb { motion: v.motion.clone(), form: v.form }, start: i, end: i + n });
            i += n;
            continue;
        }
        if let Some((s, part)) = JA_PARTS.iter().find(|(s, _)| starts_with(cs, i, s)) {
            flush(&mut out, &mut ja_word, i);
            let n = s.chars().count();
            out.push(Token { tok: Tok::Part(*part), start: i, end: i + n });
            i += n;
            continue;
        }
        // An unknown character: part of a Japanese word. Words split after the particles
        // は, が, を, に, へ so "太郎は" and "踊る" come apart.
        match &mut ja_word {
            Some((_, text)) => text.push(c),
            None => ja_word = Some((i, c.to_string())),
        }
        i += 1;
        // (Not the が of ながら.)
        let nagara = c == 'が' && cs.get(i) == Some(&'ら') && i >= 2 && cs[i - 2] == 'な';
        if matches!(c, 'は' | 'が' | 'を' | 'に' | 'へ') && !nagara {
            flush(&mut out, &mut ja_word, i);
        }
        // An unknown conjugated verb ends its own clause: 踊って / 踊りながら.
        if let Some((_, text)) = &ja_word {
            let form = if text.ends_with("ながら") || text.ends_with("つつ") {
                Some(VerbForm::Parallel)
            } else if text.chars().nth(1).is_some() && (text.ends_with("って") || text.ends_with("いて") || text.ends_with("いで") || text.ends_with("んで") || text.ends_with("して") || text.ends_with("えて") || text.ends_with("けて") || text.ends_with("げて") || text.ends_with("べて") || text.ends_with("めて") || text.ends_with("れて")) {
                // Only when a clause boundary or a new word follows (not 走っていた...).
                let next = cs.get(i).copied();
                let ends = next.is_none_or(|n| is_boundary_char(n) || !matches!(n, 'い' | 'お' | 'か' | 'く' | 'ま' | 'し' | 'も' | 'は'));
                ends.then_some(VerbForm::Te)
            } else {
                None
            };
            if let Some(form) = form {
                if let Some((s, text)) = ja_word.take() {
                    out.push(Token { tok: Tok::UnknownVerb { text, form }, start: s, end: i });
                }
            }
        }
    }
    flush(&mut out, &mut ja_word, cs.len());
    out
}

fn starts_with_chars(cs: &[char], i: usize, s: &[char]) -> bool {
    i + s.len() <= cs.len() && cs[i..i + s.len()] == *s
}

/// Char → UTF-16 offsets for spans.
fn utf16_offsets(cs: &[char]) -> Vec<usize> {
    let mut v = Vec::with_capacity(cs.len() + 1);
    let mut u = 0;
    for c in cs {
        v.push(u);
        u += c.len_utf16();
    }
    v.push(u);
    v
}

/// What stands between two verbs.
#[derive(Clone, Copy, Debug, Default)]
struct Link {
    stop: bool,
    serial: bool,
    after: bool,
    parallel: bool,
    delay: Option<f32>,
}

struct RawElement {
    motion: String,
    verb: String,
    start: usize,
    end: usize,
    form: VerbForm,
    join: JoinType,
    delay: f32,
    part: Option<BodyPart>,
    actor: String,
}

/// Parses Japanese and/or English text into a motion time table (spec §H).
/// Never fails: problems are diagnostics, and whatever was understood is in the table.
pub fn parse(text: &str, lex: &Lexicon) -> ParsedText {
    let mut diagnostics = Vec::new();
    let mut cs: Vec<char> = text.chars().collect();
    let u16 = utf16_offsets(&cs);
    let span = |s: usize, e: usize| TextSpan { start: s, end: e, utf16_start: u16[s.min(u16.len() - 1)], utf16_end: u16[e.min(u16.len() - 1)] };
    if cs.len() > MAX_TEXT_CHARS {
        diagnostics.push(Diagnostic {
            kind: DiagnosticKind::Truncated,
            text: String::new(),
            span: span(MAX_TEXT_CHARS, cs.len()),
            message: format!("the text has {} characters; only the first {MAX_TEXT_CHARS} are read", cs.len()),
        });
        cs.truncate(MAX_TEXT_CHARS);
    }
    let tokens = tokenize(&cs, lex);
    let has_ja = tokens.iter().any(|t| matches!(&t.tok, Tok::Word { ja: true, .. } | Tok::UnknownVerb { .. }) || (matches!(t.tok, Tok::Verb { .. }) && !cs[t.start].is_ascii()));
    let has_en = tokens.iter().any(|t| matches!(&t.tok, Tok::Word { ja: false, .. }) || (matches!(t.tok, Tok::Verb { .. }) && cs[t.start].is_ascii()));
    if has_ja && has_en {
        diagnostics.push(Diagnostic { kind: DiagnosticKind::MixedLanguages, text: String::new(), span: span(0, cs.len()), message: "the text mixes Japanese and English; both are read".into() });
    }

    let mut raw: Vec<RawElement> = Vec::new();
    let mut link = Link::default();
    let mut lead_parallel = false;
    let mut actor = String::new();
    let mut pending_part: Option<BodyPart> = None;
    // Clause state: has it a verb, and its leftover words (for unknown-verb reports).
    let mut clause_verb = false;
    let mut sentence_verb = false;
    let mut clause_words: Vec<(String, usize, usize, bool)> = Vec::new();
    let mut sentence_start = true;
    let mut sentence_first = 0usize;

    let close_clause = |clause_verb: &mut bool, words: &mut Vec<(String, usize, usize, bool)>, diags: &mut Vec<Diagnostic>| {
        if !*clause_verb {
            // The likely verb: Japanese — the last word (after its particle); English — the
            // first word that is not a stopword.
            let pick = words.iter().rev().find(|w| w.3).cloned().or_else(|| words.iter().find(|w| !w.3 && !EN_STOPWORDS.contains(&w.0.to_lowercase().as_str())).cloned());
            if let Some((w, s, e, _)) = pick {
                diags.push(Diagnostic {
                    kind: DiagnosticKind::UnknownVerb,
                    message: format!("'{w}' (at {s}) is not an action the library knows; this part is skipped"),
                    text: w,
                    span: TextSpan { start: s, end: e, utf16_start: 0, utf16_end: 0 },
                });
            }
        }
        *clause_verb = false;
        words.clear();
    };

    for (ti, t) in tokens.iter().enumerate() {
        match &t.tok {
            Tok::Verb { motion, form } => {
                let verb: String = cs[t.start..t.end].iter().collect();
                let join = if raw.is_empty() {
                    JoinType::Initial
                } else {
                    let prev_form = raw.last().map(|r| r.form).unwrap_or(VerbForm::Plain);
                    if link.parallel || prev_form == VerbForm::Parallel {
                        JoinType::Composition
                    } else if link.delay.is_some() || link.stop || link.after || prev_form == VerbForm::TeKara {
                        JoinType::Connection
                    } else {
                        JoinType::Transition
                    }
                };
                // English: "wave the right hand" — a part after the verb; Japanese names it
                // before (右手を振る). Pending parts go to this verb.
                raw.push(RawElement {
                    motion: motion.clone(),
                    verb,
                    start: t.start,
                    end: t.end,
                    form: *form,
                    join,
                    delay: if join == JoinType::Composition { 0.0 } else { link.delay.unwrap_or(0.0) },
                    part: pending_part.take(),
                    actor: actor.clone(),
                });
                link = Link::default();
                if lead_parallel {
                    // This verb's clause ran alongside the one that follows.
                    link.parallel = true;
                    lead_parallel = false;
                }
                clause_verb = true;
                sentence_verb = true;
                sentence_start = false;
                if matches!(form, VerbForm::Te | VerbForm::TeKara | VerbForm::Parallel) {
                    close_clause(&mut clause_verb, &mut clause_words, &mut diagnostics);
                }
            }
            Tok::Part(p) => {
                let is_en = cs[t.start].is_ascii();
                match raw.last_mut() {
                    Some(last) if is_en && clause_verb => last.part = Some(*p),
                    _ => pending_part = Some(*p),
                }
            }
            Tok::Comma => {
                close_clause(&mut clause_verb, &mut clause_words, &mut diagnostics);
                link.serial = true;
            }
            Tok::Stop => {
                close_clause(&mut clause_verb, &mut clause_words, &mut diagnostics);
                link.stop = true;
                sentence_verb = false;
                sentence_first = raw.len();
                sentence_start = true;
                pending_part = None;
            }
            Tok::Then => {
                close_clause(&mut clause_verb, &mut clause_words, &mut diagnostics);
                link.serial = true;
                sentence_start = false;
            }
            Tok::After => {
                close_clause(&mut clause_verb, &mut clause_words, &mut diagnostics);
                link.after = true;
                sentence_start = false;
            }
            Tok::Parallel { lead } => {
                close_clause(&mut clause_verb, &mut clause_words, &mut diagnostics);
                if *lead && !sentence_verb {
                    // "While walking, Taro waves": the clause it opens comes first.
                    lead_parallel = true;
                } else {
                    link.parallel = true;
                }
                sentence_start = false;
            }
            Tok::Delay(secs) => {
                link.delay = Some(link.delay.unwrap_or(0.0) + secs);
                sentence_start = false;
            }
            Tok::Word { text, ja } => {
                let lower = text.to_lowercase();
                if *ja && (text.ends_with('は') || text.ends_with('が')) && !sentence_verb && text.chars().count() >= 2 {
                    actor = text.chars().take(text.chars().count() - 1).collect();
                } else if !*ja && text.chars().next().is_some_and(|c| c.is_ascii_uppercase()) && !PRONOUNS.contains(&lower.as_str()) && (!sentence_start || matches!(tokens.get(ti + 1).map(|n| &n.tok), Some(Tok::Verb { .. }) | Some(Tok::Word { ja: false, .. }))) {
                    // A capitalised name: mid-sentence, or opening one before its verb. It is
                    // also the actor of this sentence's earlier verbs that had none.
                    actor = text.clone();
                    for r in raw.iter_mut().skip(sentence_first) {
                        if r.actor.is_empty() {
                            r.actor = actor.clone();
                        }
                    }
                } else if *ja && matches!(text.as_str(), "は" | "が" | "を" | "に" | "へ" | "ボールを" | "手を" | "で" | "と") {
                    // Particles and objects alone say nothing about the verb.
                } else {
                    clause_words.push((text.clone(), t.start, t.end, *ja));
                }
                sentence_start = false;
            }
            Tok::UnknownVerb { text, form } => {
                diagnostics.push(Diagnostic {
                    kind: DiagnosticKind::UnknownVerb,
                    message: format!("'{text}' (at {}) is not an action the library knows; this part is skipped", t.start),
                    text: text.clone(),
                    span: span(t.start, t.end),
                });
                clause_words.clear();
                clause_verb = false;
                if *form == VerbForm::Te {
                    link.serial = true;
                }
                sentence_start = false;
            }
        }
    }
    close_clause(&mut clause_verb, &mut clause_words, &mut diagnostics);
    // Fill UTF-16 offsets of the clause-level reports.
    for d in &mut diagnostics {
        if d.span.utf16_end == 0 && d.span.end > 0 {
            d.span = span(d.span.start, d.span.end);
        }
    }
    if raw.len() > MAX_ELEMENTS {
        let cut = &raw[MAX_ELEMENTS];
        diagnostics.push(Diagnostic {
            kind: DiagnosticKind::Truncated,
            text: cut.verb.clone(),
            span: span(cut.start, cs.len()),
            message: format!("{} actions found; only the first {MAX_ELEMENTS} are animated", raw.len()),
        });
        raw.truncate(MAX_ELEMENTS);
    }
    diagnostics.sort_by_key(|d| d.span.start);
    ParsedText { elements: build_table(raw, lex, &span), diagnostics }
}

/// Groups parallel elements (base first) and numbers the table.
fn build_table(raw: Vec<RawElement>, lex: &Lexicon, span: &dyn Fn(usize, usize) -> TextSpan) -> Vec<TimeTableElement> {
    let mut groups: Vec<Vec<RawElement>> = Vec::new();
    for r in raw {
        match groups.last_mut() {
            Some(g) if r.join == JoinType::Composition => g.push(r),
            _ => groups.push(vec![r]),
        }
    }
    let mut out: Vec<TimeTableElement> = Vec::new();
    let mut last_index: Option<usize> = None;
    for mut g in groups {
        let (first_join, first_delay) = (g[0].join, g[0].delay);
        // Base: the first whole-body motion (no part of its own and none named).
        let base_at = g.iter().position(|r| lex.part_of(&r.motion).is_none() && r.part.is_none()).unwrap_or(0);
        let base = g.remove(base_at);
        let base_index = out.len();
        let element = |r: &RawElement, index: usize, join: JoinType, previous: Option<usize>, delay: f32, switched: Option<BodyPart>| TimeTableElement {
            index,
            actor: r.actor.clone(),
            motion: r.motion.clone(),
            verb: r.verb.clone(),
            span: span(r.start, r.end),
            join,
            previous,
            body_part: r.part,
            switched_part: switched,
            delay_secs: delay,
            clip: None,
            clip_name: String::new(),
            alternatives: Vec::new(),
            start_secs: 0.0,
            duration_secs: 0.0,
        };
        out.push(element(&base, base_index, if last_index.is_none() { JoinType::Initial } else { first_join }, last_index, first_delay, None));
        for r in &g {
            let part = r.part.or_else(|| lex.part_of(&r.motion)).unwrap_or(BodyPart::RightArm);
            let idx = out.len();
            out.push(element(r, idx, JoinType::Composition, Some(base_index), 0.0, Some(part)));
        }
        last_index = Some(out.len() - 1);
    }
    out
}

impl Lexicon {
    /// The body part a motion mainly moves (its default switched part).
    pub fn part_of(&self, motion: &str) -> Option<BodyPart> {
        self.parts.get(motion).copied()
    }
}

/// Default switched parts of the built-in motions.
pub fn builtin_parts() -> HashMap<String, BodyPart> {
    [("wave", BodyPart::RightArm), ("clap", BodyPart::BothArms), ("point", BodyPart::RightArm), ("nod", BodyPart::Head), ("gutsy pose", BodyPart::RightArm), ("kick", BodyPart::RightLeg)]
        .into_iter()
        .map(|(k, v)| (k.to_string(), v))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn table(text: &str) -> Vec<(String, JoinType, f32)> {
        parse(text, &Lexicon::builtin()).elements.into_iter().map(|e| (e.motion, e.join, e.delay_secs)).collect()
    }

    fn unknown(text: &str) -> Vec<(String, usize)> {
        parse(text, &Lexicon::builtin()).diagnostics.into_iter().filter(|d| d.kind == DiagnosticKind::UnknownVerb).map(|d| (d.text, d.span.start)).collect()
    }

    #[test]
    fn empty_and_punctuation_only_give_nothing() {
        for t in ["", "   ", "。。。", "、,.!?", "\n\n"] {
            let p = parse(t, &Lexicon::builtin());
            assert!(p.elements.is_empty() && p.diagnostics.is_empty(), "{t:?}: {p:?}");
        }
    }

    #[test]
    fn forms_decide_the_join() {
        use JoinType::*;
        assert_eq!(table("走ってからジャンプする。"), [("run".into(), Initial, 0.0), ("jump".into(), Connection, 0.0)]);
        assert_eq!(table("花子は歩いている。"), [("walk".into(), Initial, 0.0)]);
        assert_eq!(table("走り、蹴り、喜ぶ。").iter().map(|r| r.1).collect::<Vec<_>>(), [Initial, Transition, Transition]);
        assert_eq!(table("走る。三秒後に座る。")[1], ("sit".into(), Connection, 3.0));
        assert_eq!(table("走る。１０秒後に座る。")[1].2, 10.0);
        assert_eq!(table("Run. After 1.5 seconds, sit down.")[1], ("sit".into(), Connection, 1.5));
        assert_eq!(table("Sit down, wait 2 seconds and stand up.")[1], ("stand".into(), Connection, 2.0));
        assert_eq!(table("歩く。同時に右手を振る。")[1].1, Composition);
        assert_eq!(table("Taro walks. Meanwhile he waves.")[1].1, Composition);
        assert_eq!(table("She walked slowly and then jumped.")[1], ("jump".into(), Transition, 0.0));
    }

    #[test]
    fn unknown_verbs_are_located_and_do_not_become_actors() {
        assert_eq!(unknown("太郎と花子は踊りながら歩く。"), [("踊りながら".to_string(), 6)]);
        assert_eq!(unknown("踊る、走る、歌う。"), [("踊る".to_string(), 0), ("歌う".to_string(), 6)]);
        assert_eq!(unknown("Taro sings, then runs."), [("sings".to_string(), 5)]);
        let p = parse("太郎と花子は踊りながら歩く。", &Lexicon::builtin());
        assert_eq!(p.elements[0].actor, "太郎と花子");
    }

    #[test]
    fn limits_truncate_with_a_diagnostic() {
        let long = "走る。".repeat(MAX_ELEMENTS + 5);
        let p = parse(&long, &Lexicon::builtin());
        assert_eq!(p.elements.len(), MAX_ELEMENTS);
        assert!(p.diagnostics.iter().any(|d| d.kind == DiagnosticKind::Truncated));
        let huge = "あ".repeat(MAX_TEXT_CHARS + 10);
        let p = parse(&huge, &Lexicon::builtin());
        assert!(p.diagnostics.iter().any(|d| d.kind == DiagnosticKind::Truncated));
    }
}
