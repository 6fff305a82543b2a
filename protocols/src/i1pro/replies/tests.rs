//! Replies against the byte strings of the documented layouts.

use super::*;

#[test]
fn misc_reply_of_a_rev_b_in_high_power() {
    let m = Misc::parse(&[0x01, 0x2E, 0x00, 0x00, 0xFF, 0xFF, 0x01, 0x00]).unwrap();
    assert_eq!(m.firmware, 302);
    assert_eq!(m.max_positive, 0xFFFF);
    assert_eq!(m.unknown3, 1);
    assert!(m.high_power());
    assert!(m.has_clock_modes());
    let low = Misc { power: 8, ..m };
    assert!(!low.high_power());
    assert_eq!(Misc::parse(&low.encode()).unwrap(), low);
    assert_eq!(
        Misc::parse(&[1, 2, 3]).unwrap_err(),
        ReplyError::Length {
            reply: "get misc (0xC9)",
            expected: 8,
            got: 3
        }
    );
}

#[test]
fn clock_mode_1_is_68_us_by_130() {
    let c = ClockMode::parse(&[0x03, 0x01, 0x00, 0x82, 0x44, 0x00]).unwrap();
    assert_eq!(
        (c.max, c.current, c.sub_clock_divider, c.clock_us),
        (3, 1, 130, 68)
    );
    // 68 µs × 130 = 8.84 ms.
    assert!((c.sub_clock_s() - 8.84e-3).abs() < 1e-15);
    assert!(!c.subtract_mode());
    assert_eq!(ClockMode::parse(&c.encode()).unwrap(), c);
}

#[test]
fn rev_e_characteristics() {
    let b = [0, 0, 0, 0x24, 0, 0, 0, 6, 0, 0, 0, 0x80, 0, 0, 0, 0x88];
    let m = MeasChar::parse(&b).unwrap();
    assert_eq!(m, MeasChar::KNOWN);
    assert_eq!(m.encode(), b);
    let mut odd = b;
    odd[11] = 0x40;
    assert_eq!(
        MeasChar::parse(&odd).unwrap_err(),
        ReplyError::UnexpectedMeasChar {
            clock_us: 36,
            shielded: 6,
            cells: 64,
            divider: 136
        }
    );
}

#[test]
fn small_replies() {
    assert_eq!(parse_eeprom_size(&[0, 0, 0x40, 0]).unwrap(), 16384);
    assert_eq!(
        parse_chip_id(&[1, 2, 3, 4, 5, 6, 7, 8]).unwrap(),
        [1, 2, 3, 4, 5, 6, 7, 8]
    );
    assert_eq!(
        parse_uv_volts(&[0x01, 0x00, 0x00, 0xFF]).unwrap(),
        (256, 255)
    );
    assert!(parse_eeprom_size(&[0; 5]).is_err());
}

proptest::proptest! {
    #[test]
    fn arbitrary_replies_never_panic(bytes in proptest::collection::vec(proptest::prelude::any::<u8>(), 0..24)) {
        let _ = Misc::parse(&bytes);
        let _ = crate::i1pro::commands::MeasParams::parse(&bytes);
        let _ = crate::i1pro::commands::MeasParamsE::parse(&bytes);
        let _ = ClockMode::parse(&bytes);
        let _ = MeasChar::parse(&bytes);
        let _ = parse_eeprom_size(&bytes);
        let _ = parse_chip_id(&bytes);
        let _ = parse_uv_volts(&bytes);
    }
}
