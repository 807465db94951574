//! Issue #14, API boundary in the core: a bar's intensity is a fraction of the song's loudness
//! range, so a bar claiming intensity 5 (or NaN) is refused with its index and value, and a
//! refused re-grid leaves the dance as it was.

use odori_core::bars::Bar;
use odori_core::choreo::{ChoreoError, Choreography};

fn bars(intensity_of_bar_2: f32) -> Vec<Bar> {
    (0..4).map(|i| Bar { index: i, start_secs: i as f32 * 2.0, end_secs: i as f32 * 2.0 + 2.0, intensity: if i == 2 { intensity_of_bar_2 } else { 0.5 }, beats: 4 }).collect()
}

#[test]
fn bar_intensity_outside_0_to_1_is_refused() {
    for bad in [5.0f32, -0.1, f32::NAN, f32::INFINITY] {
        let e = Choreography::new(bars(bad)).unwrap_err();
        assert!(matches!(e, ChoreoError::BadBarIntensity { index: 2, .. }), "{bad}: {e:?}");
        assert!(e.to_string().contains(&format!("intensity {bad}")), "{e}");
    }
    // Control: the ends of the range are bars.
    for ok in [0.0f32, 1.0] {
        Choreography::new(bars(ok)).unwrap();
    }
    // A refused re-grid keeps the bars it had.
    let mut doc = Choreography::new(bars(0.2)).unwrap();
    assert!(doc.set_bars(bars(5.0)).is_err());
    assert_eq!(doc.bars()[2].intensity, 0.2);
}
