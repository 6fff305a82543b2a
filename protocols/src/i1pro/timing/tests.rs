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

#[test]
fn the_first_mode_that_fits_a_time_is_picked() {
    // Mode 1 as firmware before 301 has it (68 µs × 130 = 8.84 ms) and a finer second mode
    // of 36 µs × 131 = 4.716 ms, ArgyllCMS's shortest integration on firmware ≥ 301.
    let modes = [
        ClockUnit {
            clock_s: 68e-6,
            divider: 130,
        },
        ClockUnit {
            clock_s: 36e-6,
            divider: 131,
        },
    ];
    let max = u64::from(u16::MAX);
    // 0.1 s / 68 µs = 1470.6 → 1471 clocks in mode 1.
    assert_eq!(pick_mode(&modes, 0.1, max), Some((0, 1471)));
    // 8.84 ms is exactly one sub-clock of mode 1.
    assert_eq!(pick_mode(&modes, 8.84e-3, max), Some((0, 130)));
    // 6 ms is 88 clocks of 68 µs, below mode 1's 130: mode 2, 6 / 0.036 = 166.7 → 167.
    assert_eq!(pick_mode(&modes, 6e-3, max), Some((1, 167)));
    assert_eq!(pick_mode(&modes, 4.716e-3, max), Some((1, 131)));
    // 4.6 ms is 127.8 → 128 clocks of 36 µs: below one sub-clock in every mode.
    assert_eq!(pick_mode(&modes, 4.6e-3, max), None);
    // 4.5 s is 66176 clocks of 68 µs and 125000 of 36 µs: more than a request carries.
    assert_eq!(pick_mode(&modes, 4.5, max), None);
    assert_eq!(pick_mode(&modes, f64::NAN, max), None);
    assert_eq!(pick_mode(&modes[..1], 6e-3, max), None);
    assert!((shortest_s(&modes).unwrap() - 4.716e-3).abs() < 1e-15);
    assert!((shortest_s(&modes[..1]).unwrap() - 8.84e-3).abs() < 1e-15);
    assert_eq!(shortest_s(&[]), None);
}
