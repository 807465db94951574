//! Golden motion time tables (spec §H): every sentence of tests/golden/text/sentences.json
//! must parse to its expected table, and sentences marked as one pair (Japanese and English)
//! must give the same table.

use std::collections::HashMap;

use odori_core::text::{parse, JoinType, Lexicon, TimeTableElement};
use serde_json::Value;

fn golden() -> Value {
    let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("golden/text/sentences.json");
    let s = std::fs::read_to_string(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
    serde_json::from_str(&s).expect("golden json")
}

fn join_name(j: JoinType) -> &'static str {
    match j {
        JoinType::Initial => "initial",
        JoinType::Connection => "connection",
        JoinType::Transition => "transition",
        JoinType::Composition => "composition",
    }
}

/// What the languages must agree on (actors are names, written per language).
fn shape(els: &[TimeTableElement]) -> Vec<String> {
    els.iter()
        .map(|e| format!("{}|{}|{:?}|{:?}|{:?}|{}", e.motion, join_name(e.join), e.previous, e.switched_part, e.body_part, e.delay_secs))
        .collect()
}

#[test]
fn golden_sentences_give_their_tables() {
    let g = golden();
    let cases = g["cases"].as_array().expect("cases");
    assert!(cases.len() >= 20, "at least 20 golden sentences");
    let lex = Lexicon::builtin();
    let mut by_pair: HashMap<String, Vec<(String, Vec<String>)>> = HashMap::new();
    let (mut ja, mut en) = (0, 0);
    for case in cases {
        let text = case["text"].as_str().expect("text");
        if text.chars().any(|c| !c.is_ascii()) {
            ja += 1;
        } else {
            en += 1;
        }
        let got = parse(text, &lex);
        let want = case["elements"].as_array().expect("elements");
        assert_eq!(got.elements.len(), want.len(), "{text}: got {:#?}", got.elements);
        for (k, (e, w)) in got.elements.iter().zip(want).enumerate() {
            let ctx = format!("{text} element {k}: {e:?}");
            assert_eq!(e.index, k, "{ctx}");
            assert_eq!(e.motion, w["motion"].as_str().unwrap(), "{ctx}");
            assert_eq!(join_name(e.join), w["join"].as_str().unwrap(), "{ctx}");
            assert_eq!(e.previous, w["previous"].as_u64().map(|v| v as usize), "{ctx}");
            let part = |v: &Value| v.as_str().map(str::to_string);
            assert_eq!(e.switched_part.map(|p| p.name().to_string()), part(&w["switchedPart"]), "{ctx}");
            if !w["bodyPart"].is_null() {
                assert_eq!(e.body_part.map(|p| p.name().to_string()), part(&w["bodyPart"]), "{ctx}");
            }
            assert!((e.delay_secs - w["delaySecs"].as_f64().unwrap_or(0.0) as f32).abs() < 1e-4, "{ctx}");
            if let Some(a) = w["actor"].as_str() {
                assert_eq!(e.actor, a, "{ctx}");
            }
            // The span points at the verb as written.
            let verb: String = text.chars().skip(e.span.start).take(e.span.end - e.span.start).collect();
            assert_eq!(verb, e.verb, "{ctx}");
        }
        let unknown: Vec<String> = got.diagnostics.iter().filter(|d| d.kind == odori_core::text::DiagnosticKind::UnknownVerb).map(|d| d.text.clone()).collect();
        let want_unknown: Vec<String> = case["unknown"].as_array().map(|a| a.iter().filter_map(|v| v.as_str().map(str::to_string)).collect()).unwrap_or_default();
        assert_eq!(unknown, want_unknown, "{text}: {:?}", got.diagnostics);
        for d in &got.diagnostics {
            let at: String = text.chars().skip(d.span.start).take(d.span.end - d.span.start).collect();
            if d.kind == odori_core::text::DiagnosticKind::UnknownVerb {
                assert_eq!(at, d.text, "{text}: diagnostic span");
                let u16: Vec<u16> = text.encode_utf16().collect();
                assert_eq!(String::from_utf16_lossy(&u16[d.span.utf16_start..d.span.utf16_end]), d.text, "UTF-16 span");
            }
        }
        let mixed = got.diagnostics.iter().any(|d| d.kind == odori_core::text::DiagnosticKind::MixedLanguages);
        assert_eq!(mixed, case["mixed"].as_bool().unwrap_or(false), "{text}");
        by_pair.entry(case["pair"].as_str().unwrap_or("").to_string()).or_default().push((text.to_string(), shape(&got.elements)));
    }
    assert!(ja >= 10 && en >= 10, "both languages: {ja} Japanese, {en} English");
    for (pair, texts) in &by_pair {
        for (t, s) in &texts[1..] {
            assert_eq!(s, &texts[0].1, "pair '{pair}': '{t}' differs from '{}'", texts[0].0);
        }
    }
}

#[test]
fn the_papers_example_exactly() {
    let p = parse("太郎は走って，ボールを蹴る．そして喜ぶ．", &Lexicon::builtin());
    let rows: Vec<(&str, JoinType, Option<usize>)> = p.elements.iter().map(|e| (e.motion.as_str(), e.join, e.previous)).collect();
    assert_eq!(rows, [("run", JoinType::Initial, None), ("kick", JoinType::Transition, Some(0)), ("rejoice", JoinType::Connection, Some(1))]);
    assert!(p.diagnostics.is_empty(), "{:?}", p.diagnostics);
}
