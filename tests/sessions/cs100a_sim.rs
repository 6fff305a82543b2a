//! The simulated CS-100A's default light is what its documentation says it is.

use metamer::color::{illuminant_white, Illuminant, ObserverKind};
use metamer_drivers::DEFAULT_STIMULUS_XYZ;

#[test]
fn default_light_is_100_cd_m2_of_led_rgb1() {
    let white = illuminant_white(&Illuminant::LedRgb1.spectrum(), ObserverKind::Cie1931);
    let want = [white.x, white.y, white.z];
    for (got, want) in DEFAULT_STIMULUS_XYZ.iter().zip(want) {
        assert!(
            (got - want).abs() < 1e-6,
            "{DEFAULT_STIMULUS_XYZ:?} vs {want}"
        );
    }
    // CIE 15:2018 lists LED-RGB1 at (x, y) = (0.4557, 0.4211).
    let sum: f64 = DEFAULT_STIMULUS_XYZ.iter().sum();
    assert!((DEFAULT_STIMULUS_XYZ[0] / sum - 0.4557).abs() < 1e-4);
    assert!((DEFAULT_STIMULUS_XYZ[1] / sum - 0.4211).abs() < 1e-4);
}
