//! Issue #14, API boundary in the core: a bar's intensity is a fraction of the song's loudness
//! range, so a bar claiming intensity 5 (or NaN) is refused with its index and value, and a
//! bar generation is asked to fill is checked the same way.

use odori_core::bars::Bar;
use odori_core::choreo::{check_bars, generate_states, ChoreoError, FillWeights, GenerateOptions, SegmentLibrary};

fn bars(intensity_of_bar_2: f32) -> Vec<Bar> {
    (0..4).map(|i| Bar { index: i, start_secs: i as f32 * 2.0, end_secs: i as f32 * 2.0 + 2.0, intensity: if i == 2 { intensity_of_bar_2 } else { 0.5 }, beats: 4 }).collect()
}

#[test]
fn bar_intensity_outside_0_to_1_is_refused() {
    for bad in [5.0f32, -0.1, f32::NAN, f32::INFINITY] {
        let e = check_bars(&bars(bad)).unwrap_err();
        assert!(matches!(e, ChoreoError::BadBarIntensity { index: 2, .. }), "{bad}: {e:?}");
        assert!(e.to_string().contains(&format!("intensity {bad}")), "{e}");
    }
    // Control: the ends of the range are bars.
    for ok in [0.0f32, 1.0] {
        check_bars(&bars(ok)).unwrap();
    }
    // Generate refuses such bars too (it is a pure function of what it is given).
    let lib = SegmentLibrary::builtin();
    let e = generate_states(&lib, &bars(5.0), &[], FillWeights::default(), &GenerateOptions::default()).unwrap_err();
    assert!(matches!(e, ChoreoError::BadBarIntensity { index: 2, .. }), "{e:?}");
    generate_states(&lib, &bars(0.2), &[], FillWeights::default(), &GenerateOptions::default()).unwrap();
}
