//! Clock arithmetic by hand.

use super::*;

#[test]
fn clock_counts_round_and_refuse_what_does_not_fit() {
    // 4.896 ms / 36 µs = 136 exactly.
    assert_eq!(clocks("t", 4.896e-3, 36e-6, u32::MAX as u64).unwrap(), 136);
    // 5 s / 68 µs = 73529 > 65535.
    assert!(matches!(
        clocks("integration time", 5.0, 68e-6, 0xFFFF),
        Err(TimingError::TooManyClocks { clocks: 73529, .. })
    ));
    assert!(clocks("t", f64::NAN, 68e-6, 0xFFFF).is_err());
    assert!(clocks("t", -1.0, 68e-6, 0xFFFF).is_err());
    // 0.25 s lamp / 8.84 ms = 28.3 → 28; 3 s would be 339 → capped at 256.
    assert_eq!(lamp_clocks(0.25, 8.84e-3).unwrap(), 28);
    assert_eq!(lamp_clocks(3.0, 8.84e-3).unwrap(), 256);
}

#[test]
fn read_timeouts_by_hand() {
    // 2 s + 3 × 0.5 s + 0.25 s lamp + 1 s previous integration = 4.75 s.
    assert_eq!(readings_timeout_s(3, 0.5, Some(0.25), Some(1.0)), 4.75);
    assert_eq!(readings_timeout_s(1, 2.0, None, None), 4.0);
    assert!(measures_previous_too(302));
    assert!(measures_previous_too(200));
    assert!(!measures_previous_too(505));
    assert!(!measures_previous_too(101));
    // The documented shortest integrations: 68 µs × 130 and 36 µs × 136.
    let a = f64::from(CLOCK_US_BEFORE_301) * f64::from(SUB_CLOCK_DIVIDER_BEFORE_301) * 1e-6;
    assert!((a - 8.84e-3).abs() < 1e-15);
    let e = f64::from(CLOCK_US_E * SUB_CLOCK_DIVIDER_E) * 1e-6;
    assert!((e - 4.896e-3).abs() < 1e-15);
}
