//! The bilingual lexicon of action words: Japanese verbs with their conjugated forms,
//! English verbs with their inflections, body-part words, connectives and delays.
//!
//! Japanese verbs are stored in dictionary form with their conjugation class; every surface
//! form the parser accepts is generated from it (走る → 走って, 走り, 走りながら, 走った,
//! 走っている...), each labelled with what it says about the next action: the て form
//! continues with overlap (Transition), the 連用形 with ながら/つつ runs in parallel
//! (Composition), てから waits for the end (Connection). 「〜する」 verbs (ガッツポーズする,
//! ガッツポーズをする, お辞儀する) are nouns followed by a form of する. English verbs are
//! stored as lemmas (one or more words) and inflected (runs, running, ran, kicked).

use serde::{Deserialize, Serialize};

use crate::actions::{ActionLibrary, BodyPart};

/// What a verb's form says about how the next action follows it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "camelCase")]
pub enum VerbForm {
    /// Dictionary, past, polite, progressive, imperative forms: the next join comes from
    /// punctuation and connectives.
    Plain,
    /// て form (走って): the next action follows with overlap.
    Te,
    /// て form + から (走ってから): the next action follows after this one ends.
    TeKara,
    /// 連用形 + ながら / つつ, or English -ing after "while": in parallel.
    Parallel,
    /// Bare 連用形 (走り、): continues like て when followed by a comma or full stop.
    Stem,
}

/// Conjugation class of a Japanese verb.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum JaClass {
    /// 五段: the dictionary form ends in one of うくぐすつぬぶむる.
    Godan,
    /// 一段: 〜える / 〜いる verbs (跳ねる, 腰掛ける).
    Ichidan,
    /// A noun with する (ガッツポーズ, お辞儀); the stored word is the noun.
    Suru,
}

/// A surface form of a verb and the motion it names.
#[derive(Clone, Debug, PartialEq)]
pub struct Surface {
    pub chars: Vec<char>,
    pub motion: String,
    pub form: VerbForm,
}

/// An English verb phrase: lower-case words of one inflected form.
#[derive(Clone, Debug, PartialEq)]
pub struct EnglishForm {
    pub words: Vec<String>,
    pub motion: String,
    pub form: VerbForm,
}

/// The words the parser knows.
#[derive(Clone, Debug, Default)]
pub struct Lexicon {
    /// Japanese surface forms, longest first.
    pub ja: Vec<Surface>,
    /// English forms, most words first.
    pub en: Vec<EnglishForm>,
    /// The body part each motion mainly moves, for Composition.
    pub parts: std::collections::HashMap<String, BodyPart>,
    /// Every surface form already added (Japanese and English), so a form names one motion.
    seen: std::collections::HashSet<String>,
}

/// Motion tags the built-in library carries, with their Japanese verbs and English lemmas.
/// A Japanese verb is (dictionary form or noun, class); English lemmas may be several words,
/// and `*` marks a lemma whose final consonant doubles (run → running).
const ENTRIES: &[(&str, &[(&str, JaClass)], &[&str])] = {
    use JaClass::*;
    &[
        ("walk", &[("歩く", Godan), ("あるく", Godan), ("歩行", Suru), ("散歩", Suru), ("ウォーキング", Suru)], &["walk", "stroll", "march"]),
        ("run", &[("走る", Godan), ("はしる", Godan), ("駆ける", Ichidan), ("ランニング", Suru), ("ダッシュ", Suru), ("走り出す", Godan)], &["run*", "jog*", "sprint", "dash"]),
        ("kick", &[("蹴る", Godan), ("蹴飛ばす", Godan), ("キック", Suru)], &["kick"]),
        ("jump", &[("跳ぶ", Godan), ("飛ぶ", Godan), ("とぶ", Godan), ("跳ねる", Ichidan), ("はねる", Ichidan), ("飛び跳ねる", Ichidan), ("飛び上がる", Godan), ("ジャンプ", Suru)], &["jump", "hop*", "leap"]),
        ("wave", &[("振る", Godan)], &["wave"]),
        ("clap", &[("叩く", Godan), ("たたく", Godan), ("拍手", Suru)], &["clap*", "applaud"]),
        ("rejoice", &[("喜ぶ", Godan), ("よろこぶ", Godan), ("はしゃぐ", Godan), ("歓喜", Suru), ("バンザイ", Suru), ("万歳", Suru)], &["rejoice", "cheer", "celebrate"]),
        ("gutsy pose", &[("ガッツポーズ", Suru), ("ガッツポーズを", Suru)], &["fist pump", "fist-pump", "pump a fist", "pump his fist", "pump her fist", "pump their fist", "pump my fist", "pump your fist", "gutsy pose", "guts pose", "victory pose"]),
        ("turn", &[("回る", Godan), ("振り向く", Godan), ("ふりむく", Godan), ("振り返る", Godan), ("回転", Suru), ("ターン", Suru)], &["turn around", "turn round", "turn", "spin*", "look back"]),
        ("bow", &[("お辞儀", Suru), ("お辞儀を", Suru), ("おじぎ", Suru), ("おじぎを", Suru), ("礼", Suru), ("礼を", Suru), ("会釈", Suru)], &["bow"]),
        ("sit", &[("座る", Godan), ("すわる", Godan), ("腰掛ける", Ichidan), ("腰かける", Ichidan), ("着席", Suru)], &["sit* down", "sit*", "take a seat"]),
        ("stand", &[("立ち上がる", Godan), ("たちあがる", Godan), ("立つ", Godan), ("起立", Suru)], &["stand up", "stand", "get* up", "rise"]),
        ("nod", &[("うなずく", Godan), ("頷く", Godan), ("首を縦に振る", Godan)], &["nod*"]),
        ("point", &[("指差す", Godan), ("指さす", Godan), ("ゆびさす", Godan), ("指を差す", Godan), ("指をさす", Godan)], &["point"]),
    ]
};

/// Irregular English forms (lemma → past forms).
const IRREGULAR_PAST: &[(&str, &[&str])] = &[("run", &["ran"]), ("sit", &["sat"]), ("stand", &["stood"]), ("get", &["got"]), ("spin", &["spun", "span"]), ("leap", &["leapt", "leaped"]), ("rise", &["rose", "risen"]), ("take", &["took", "taken"])];

/// Japanese body-part words (longest first when matching).
pub const JA_PARTS: &[(&str, BodyPart)] = &[
    ("右手", BodyPart::RightArm),
    ("右腕", BodyPart::RightArm),
    ("みぎて", BodyPart::RightArm),
    ("左手", BodyPart::LeftArm),
    ("左腕", BodyPart::LeftArm),
    ("ひだりて", BodyPart::LeftArm),
    ("両手", BodyPart::BothArms),
    ("両腕", BodyPart::BothArms),
    ("右足", BodyPart::RightLeg),
    ("右脚", BodyPart::RightLeg),
    ("左足", BodyPart::LeftLeg),
    ("左脚", BodyPart::LeftLeg),
    ("頭", BodyPart::Head),
];

/// English body-part phrases.
pub const EN_PARTS: &[(&[&str], BodyPart)] = &[
    (&["right", "hand"], BodyPart::RightArm),
    (&["right", "arm"], BodyPart::RightArm),
    (&["left", "hand"], BodyPart::LeftArm),
    (&["left", "arm"], BodyPart::LeftArm),
    (&["both", "hands"], BodyPart::BothArms),
    (&["both", "arms"], BodyPart::BothArms),
    (&["right", "leg"], BodyPart::RightLeg),
    (&["right", "foot"], BodyPart::RightLeg),
    (&["left", "leg"], BodyPart::LeftLeg),
    (&["left", "foot"], BodyPart::LeftLeg),
];

fn godan_row(last: char) -> Option<(char, char, char, char, &'static str)> {
    // (a-row, i-row, e-row, o-row, te ending)
    Some(match last {
        'う' => ('わ', 'い', 'え', 'お', "って"),
        'く' => ('か', 'き', 'け', 'こ', "いて"),
        'ぐ' => ('が', 'ぎ', 'げ', 'ご', "いで"),
        'す' => ('さ', 'し', 'せ', 'そ', "して"),
        'つ' => ('た', 'ち', 'て', 'と', "って"),
        'ぬ' => ('な', 'に', 'ね', 'の', "んで"),
        'ぶ' => ('ば', 'び', 'べ', 'ぼ', "んで"),
        'む' => ('ま', 'み', 'め', 'も', "んで"),
        'る' => ('ら', 'り', 'れ', 'ろ', "って"),
        _ => return None,
    })
}

/// Every surface form of a Japanese verb, with what each form says about the next action.
pub fn conjugate(word: &str, class: JaClass) -> Vec<(String, VerbForm)> {
    let mut out: Vec<(String, VerbForm)> = Vec::new();
    let (stem, renyou, te, past): (String, String, String, String);
    match class {
        JaClass::Suru => {
            stem = word.to_string();
            renyou = format!("{word}し");
            te = format!("{word}して");
            past = format!("{word}した");
            for s in ["する", "します", "しました", "しよう", "しろ", "すれば", "しましょう"] {
                out.push((format!("{word}{s}"), VerbForm::Plain));
            }
        }
        JaClass::Ichidan => {
            let base: String = word.chars().take(word.chars().count().saturating_sub(1)).collect();
            stem = base.clone();
            renyou = base.clone();
            te = format!("{base}て");
            past = format!("{base}た");
            out.push((word.to_string(), VerbForm::Plain));
            for s in ["ます", "ました", "よう", "ろ", "れば", "ましょう"] {
                out.push((format!("{base}{s}"), VerbForm::Plain));
            }
        }
        JaClass::Godan => {
            let chars: Vec<char> = word.chars().collect();
            let Some(&last) = chars.last() else { return out };
            let Some((_a, i, e, o, te_end)) = godan_row(last) else { return out };
            let base: String = chars[..chars.len() - 1].iter().collect();
            stem = base.clone();
            renyou = format!("{base}{i}");
            // 行く is the one く verb with って; none of ours, but keep the rule honest.
            te = format!("{base}{te_end}");
            let past_end = te_end.replace('て', "た").replace('で', "だ");
            past = format!("{base}{past_end}");
            out.push((word.to_string(), VerbForm::Plain));
            for s in ["ます", "ました", "ましょう"] {
                out.push((format!("{renyou}{s}"), VerbForm::Plain));
            }
            out.push((format!("{base}{e}"), VerbForm::Plain)); // imperative
            out.push((format!("{base}{e}ば"), VerbForm::Plain));
            out.push((format!("{base}{o}う"), VerbForm::Plain)); // volitional
        }
    }
    let _ = stem;
    out.push((past.clone(), VerbForm::Plain));
    out.push((format!("{past}ら"), VerbForm::Te));
    out.push((te.clone(), VerbForm::Te));
    out.push((format!("{te}から"), VerbForm::TeKara));
    for s in ["いる", "いた", "います", "いました", "る", "た"] {
        out.push((format!("{te}{s}"), VerbForm::Plain));
    }
    out.push((format!("{te}いて"), VerbForm::Te));
    out.push((format!("{te}いながら"), VerbForm::Parallel));
    out.push((format!("{renyou}ながら"), VerbForm::Parallel));
    out.push((format!("{renyou}つつ"), VerbForm::Parallel));
    out.push((renyou, VerbForm::Stem));
    out
}

/// Inflections of an English lemma (`*` at the end: the final consonant doubles).
pub fn inflect(lemma: &str) -> Vec<(String, VerbForm)> {
    let mut words: Vec<&str> = lemma.split(' ').collect();
    let Some(first) = words.first().copied() else { return Vec::new() };
    let (head, double) = match first.strip_suffix('*') {
        Some(h) => (h, true),
        None => (first, false),
    };
    let rest = words.split_off(1).join(" ");
    let join = |w: String| if rest.is_empty() { w } else { format!("{w} {rest}") };
    let mut out = vec![(join(head.to_string()), VerbForm::Plain)];
    let third = if head.ends_with('s') || head.ends_with("sh") || head.ends_with("ch") || head.ends_with('x') { format!("{head}es") } else { format!("{head}s") };
    out.push((join(third), VerbForm::Plain));
    let last = head.chars().last().unwrap_or('x');
    let (ing, ed) = if double {
        (format!("{head}{last}ing"), format!("{head}{last}ed"))
    } else if let Some(b) = head.strip_suffix('e') {
        (format!("{b}ing"), format!("{head}d"))
    } else {
        (format!("{head}ing"), format!("{head}ed"))
    };
    out.push((join(ing), VerbForm::Plain));
    let irregular = IRREGULAR_PAST.iter().find(|(l, _)| *l == head);
    match irregular {
        Some((_, pasts)) => out.extend(pasts.iter().map(|p| (join(p.to_string()), VerbForm::Plain))),
        None => out.push((join(ed), VerbForm::Plain)),
    }
    out
}

impl Lexicon {
    /// The built-in lexicon for the built-in actions.
    pub fn builtin() -> Lexicon {
        let mut lex = Lexicon { parts: crate::text::parser::builtin_parts(), ..Lexicon::default() };
        for (motion, ja, en) in ENTRIES {
            for (word, class) in *ja {
                lex.add_japanese(word, *class, motion);
            }
            for lemma in *en {
                lex.add_english(lemma, motion);
            }
        }
        lex.sort();
        lex
    }

    /// The built-in lexicon plus the tags the person gave imported clips: an English tag
    /// becomes a verb (with inflections), a Japanese tag in dictionary form (〜る, 〜く,
    /// 〜する ...) becomes a verb with its conjugations.
    pub fn for_library(library: &ActionLibrary) -> Lexicon {
        let mut lex = Lexicon::builtin();
        for e in library.entries.iter().filter(|e| !e.builtin) {
            let motion = e.tags.first().cloned().unwrap_or_else(|| e.name.clone());
            if let Some(p) = e.part {
                lex.parts.entry(motion.clone()).or_insert(p);
            }
            for tag in e.tags.iter().chain(std::iter::once(&e.name)) {
                let tag = tag.trim();
                if tag.is_empty() || lex.knows(tag) {
                    continue;
                }
                if tag.chars().all(|c| c.is_ascii_alphabetic() || c == ' ' || c == '-') {
                    lex.add_english(&tag.to_lowercase(), &motion);
                } else if let Some(noun) = tag.strip_suffix("する") {
                    lex.add_japanese(noun, JaClass::Suru, &motion);
                } else if tag.ends_with("える") || tag.ends_with("ける") || tag.ends_with("べる") || tag.ends_with("める") || tag.ends_with("れる") || tag.ends_with("げる") || tag.ends_with("てる") || tag.ends_with("ねる") {
                    lex.add_japanese(tag, JaClass::Ichidan, &motion);
                    lex.add_japanese(tag, JaClass::Godan, &motion);
                } else if tag.chars().last().and_then(godan_row).is_some() {
                    lex.add_japanese(tag, JaClass::Godan, &motion);
                } else {
                    // A noun tag (ダンス): "ダンスする".
                    lex.add_japanese(tag, JaClass::Suru, &motion);
                }
            }
        }
        lex.sort();
        lex
    }

    fn knows(&self, word: &str) -> bool {
        self.seen.contains(word) || self.seen.contains(&word.to_lowercase())
    }

    /// Adds a Japanese verb (all its forms).
    pub fn add_japanese(&mut self, word: &str, class: JaClass, motion: &str) {
        // 「〜する」 nouns also take the object particle: ジャンプをする, お辞儀をして.
        if class == JaClass::Suru && !word.ends_with('を') {
            self.add_japanese(&format!("{word}を"), class, motion);
        }
        for (s, form) in conjugate(word, class) {
            if self.seen.insert(s.clone()) {
                self.ja.push(Surface { chars: s.chars().collect(), motion: motion.to_string(), form });
            }
        }
    }

    /// Adds an English lemma (all its inflections).
    pub fn add_english(&mut self, lemma: &str, motion: &str) {
        for (s, form) in inflect(lemma) {
            if self.seen.insert(s.clone()) {
                self.en.push(EnglishForm { words: s.split(' ').map(str::to_string).collect(), motion: motion.to_string(), form });
            }
        }
    }

    fn sort(&mut self) {
        self.ja.sort_by_key(|s| std::cmp::Reverse(s.chars.len()));
        self.en.sort_by_key(|e| std::cmp::Reverse(e.words.len()));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn forms(word: &str, class: JaClass) -> Vec<String> {
        conjugate(word, class).into_iter().map(|f| f.0).collect()
    }

    #[test]
    fn japanese_conjugations() {
        let run = forms("走る", JaClass::Godan);
        for f in ["走る", "走って", "走り", "走りながら", "走った", "走っている", "走ってから", "走ります"] {
            assert!(run.contains(&f.to_string()), "{f} in {run:?}");
        }
        assert!(forms("歩く", JaClass::Godan).contains(&"歩いて".to_string()));
        assert!(forms("喜ぶ", JaClass::Godan).contains(&"喜んで".to_string()));
        assert!(forms("指差す", JaClass::Godan).contains(&"指差して".to_string()));
        assert!(forms("はしゃぐ", JaClass::Godan).contains(&"はしゃいで".to_string()));
        assert!(forms("跳ねる", JaClass::Ichidan).contains(&"跳ねて".to_string()));
        let g = forms("ガッツポーズ", JaClass::Suru);
        assert!(g.contains(&"ガッツポーズする".to_string()) && g.contains(&"ガッツポーズしながら".to_string()));
        let te = conjugate("振る", JaClass::Godan);
        assert!(te.contains(&("振りながら".to_string(), VerbForm::Parallel)));
        assert!(te.contains(&("振って".to_string(), VerbForm::Te)));
    }

    #[test]
    fn english_inflections() {
        let run: Vec<String> = inflect("run*").into_iter().map(|f| f.0).collect();
        assert_eq!(run, ["run", "runs", "running", "ran"]);
        let wave: Vec<String> = inflect("wave").into_iter().map(|f| f.0).collect();
        assert_eq!(wave, ["wave", "waves", "waving", "waved"]);
        let sit: Vec<String> = inflect("sit* down").into_iter().map(|f| f.0).collect();
        assert!(sit.contains(&"sitting down".to_string()) && sit.contains(&"sat down".to_string()));
        let lex = Lexicon::builtin();
        assert!(lex.en.iter().any(|e| e.words == ["kicked"] && e.motion == "kick"));
        let jump: Vec<char> = "ジャンプをして".chars().collect();
        assert!(lex.ja.iter().any(|s| s.chars == jump && s.motion == "jump" && s.form == VerbForm::Te));
    }
}
