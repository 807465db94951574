//! Issue #14, text: parallel actions on a short one-shot stay a Composition, stated delays
//! outside what an animation waits are clamped or dropped with a notice, a time table naming a
//! clip that does not exist is refused, error messages stay short whatever the text, and a
//! refusal to tag a clip says why in words.

use odori_core::actions::ActionLibrary;
use odori_core::import::{import_bytes, ImportOptions};
use odori_core::text::{animate_table, animate_text, parse, DiagnosticKind, JoinType, Lexicon, TextError, MAX_DELAY_SECS};

fn lib() -> ActionLibrary {
    ActionLibrary::builtin()
}

#[test]
fn clap_while_jumping_is_a_composition() {
    let lib = lib();
    for text in ["Clap while jumping.", "ジャンプしながら拍手する。", "Jump while clapping."] {
        let a = animate_text(text, &lib).unwrap_or_else(|e| panic!("{text}: {e}"));
        let rows: Vec<(&str, JoinType)> = a.elements.iter().map(|e| (e.motion.as_str(), e.join)).collect();
        assert_eq!(rows, [("jump", JoinType::Initial), ("clap", JoinType::Composition)], "{text}: {:?}", a.diagnostics);
        assert_eq!(a.compositions.len(), 1, "{text}");
        assert!(a.joins.is_empty(), "{text}: a serial join was made");
        // The clap plays during the jump, not after it.
        let (jump, clap) = (&a.elements[0], &a.elements[1]);
        assert!(clap.start_secs >= jump.start_secs && clap.start_secs + clap.duration_secs <= jump.start_secs + jump.duration_secs + 1e-3, "{text}: {jump:?} {clap:?}");
        assert!(clap.duration_secs > 0.3, "{text}: clap lasts {}", clap.duration_secs);
        a.clip.validate().unwrap();
    }
    // Control: a whole-body action before a part action is still serial.
    let a = animate_text("Jump, then clap.", &lib).unwrap();
    assert_eq!(a.elements[1].join, JoinType::Transition);
}

#[test]
fn delays_beyond_the_limit_or_below_zero_come_with_a_notice() {
    let lib = lib();
    // Parsed as written: the sign is not lost.
    let lex = Lexicon::for_library(&lib);
    assert_eq!(parse("走る。-5秒後に座る。", &lex).elements[1].delay_secs, -5.0);
    assert_eq!(parse("走る。マイナス5秒後に座る。", &lex).elements[1].delay_secs, -5.0);
    assert_eq!(parse("走る。99999秒後に座る。", &lex).elements[1].delay_secs, 99999.0);

    let cases = [("走る。99999秒後に座る。", MAX_DELAY_SECS, "99999"), ("走る。-5秒後に座る。", 0.0, "-5"), ("走る。3秒後に座る。", 3.0, "")];
    for (text, delay, said) in cases {
        let a = animate_text(text, &lib).unwrap();
        assert_eq!(a.elements[1].delay_secs, delay, "{text}");
        let notes: Vec<&str> = a.diagnostics.iter().filter(|d| d.kind == DiagnosticKind::DelayClamped).map(|d| d.message.as_str()).collect();
        if said.is_empty() {
            assert!(notes.is_empty(), "{text}: {notes:?}");
        } else {
            assert!(notes.len() == 1 && notes[0].contains(said), "{text}: {notes:?}");
        }
    }
    // The wait is really that long in the animation: 30 s, 27 s more than a 3 s wait; and
    // after -5 s, no wait at all (as long as with no delay stated).
    let secs = |t: &str| animate_text(t, &lib).unwrap().clip.duration_secs();
    let (long, three, none, neg) = (secs("走る。99999秒後に座る。"), secs("走る。3秒後に座る。"), secs("走る。座る。"), secs("走る。-5秒後に座る。"));
    assert!((long - three - (MAX_DELAY_SECS - 3.0)).abs() < 0.5, "99999 s: {long} s, 3 s: {three} s");
    assert!((neg - none).abs() < 0.5, "-5 s: {neg} s, none: {none} s");
}

#[test]
fn a_table_naming_a_missing_clip_is_refused() {
    let lib = lib();
    let a = animate_text("Taro runs, then jumps.", &lib).unwrap();
    // Control: the table as animated re-animates.
    animate_table(&a.elements, &lib, Vec::new()).unwrap();
    let mut table = a.elements.clone();
    table[1].clip = Some(lib.len() + 5);
    let e = animate_table(&table, &lib, Vec::new()).unwrap_err();
    assert!(matches!(e, TextError::NoSuchClip { index: 1, .. }), "{e:?}");
    assert!(e.to_string().contains(&(lib.len() + 5).to_string()), "{e}");
}

#[test]
fn error_about_many_unknown_words_stays_short() {
    let lib = lib();
    let text = "Zork. ".repeat(10_000 / 6);
    assert!(text.len() >= 9_990);
    let e = animate_text(&text, &lib).unwrap_err();
    let TextError::NoActions { diagnostics } = &e else { panic!("{e:?}") };
    // Every word is still reported in the diagnostics; the message lists ten and counts the rest.
    assert_eq!(diagnostics.iter().filter(|d| d.kind == DiagnosticKind::UnknownVerb).count(), 10_000 / 6);
    let msg = e.to_string();
    assert!(msg.len() < 600, "{} characters: {}", msg.len(), &msg[..200]);
    assert!(msg.contains(&format!("and {} more", 10_000 / 6 - 10)), "{msg}");
    // One very long unknown word is quoted cut.
    let e = animate_text(&format!("{}.", "q".repeat(5_000)), &lib).unwrap_err();
    assert!(e.to_string().len() < 200, "{}", e.to_string().len());
}

#[test]
fn tagging_a_non_humanoid_says_why_in_words() {
    let bvh = "HIERARCHY\nROOT tail\n{\n OFFSET 0 0 0\n CHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation Xrotation\n JOINT tip\n {\n  OFFSET 0 0 40\n  CHANNELS 3 Xrotation Zrotation Yrotation\n  End Site\n  {\n   OFFSET 0 0 40\n  }\n }\n}\nMOTION\nFrames: 12\nFrame Time: 0.0333333\n"
        .to_string()
        + &"0 20 0 0 0 0 0 0 0\n".repeat(12);
    let im = import_bytes("tail.bvh", bvh.as_bytes(), &ImportOptions::default()).unwrap();
    assert!(!im.status.is_humanoid());
    let mut lib = lib();
    let e = lib.add_clip(&im.clips[0], &["wag".into()], None).unwrap_err();
    let msg = e.to_string();
    assert!(msg.contains("not a humanoid"), "{msg}");
    assert!(!msg.contains("NotHumanoid") && !msg.contains("reason:") && !msg.contains('{'), "Rust debug text leaks: {msg}");
}
