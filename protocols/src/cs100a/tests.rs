//! Codec tests on bytes: the example exchanges of protocols/cs100a/README.md and property tests.

use super::*;

#[test]
fn commands_encode_to_documented_bytes() {
    assert_eq!(Command::SetMode(Mode::Absolute).encode(), b"MDS,04\r\n");
    assert_eq!(Command::SetMode(Mode::Fast).encode(), b"MDS,06\r\n");
    assert_eq!(Command::SetMode(Mode::Slow).encode(), b"MDS,07\r\n");
    assert_eq!(Command::SetMode(Mode::Preset).encode(), b"MDS,00\r\n");
    assert_eq!(Command::Measure.encode(), b"MES\r\n");
    assert_eq!(Command::Clear.encode(), b"CLE\r\n");
    assert_eq!(Command::SetMode(Mode::Slow).text(), "MDS,07");
}

#[test]
fn ok00_reading_parses() {
    let r = parse_reply(b"OK00,  123.4, .3127, .3290\r\n").unwrap();
    assert_eq!(
        r,
        Reply::Measurement {
            status: Status::Ok00,
            value: Yxy {
                luminance: Some(123.4),
                x: Some(0.3127),
                y: Some(0.3290)
            }
        }
    );
}

#[test]
fn pgl_low_light_example_parses() {
    // The one real-device reply in the sources (PGL comment).
    let line = b"OK13,  10.73, .4795, .4287\r\n";
    assert_eq!(line.len(), MES_REPLY_LEN);
    let Reply::Measurement { status, value } = parse_reply(line).unwrap() else {
        panic!("not a measurement")
    };
    assert_eq!(status, Status::Ok13);
    assert_eq!(value.luminance, Some(10.73));
    assert_eq!((value.x, value.y), (Some(0.4795), Some(0.4287)));
}

#[test]
fn signs_are_read_from_the_sign_column() {
    let Reply::Measurement { value, .. } = parse_reply(b"OK00,+  1.20,-.0031,+.0012\r\n").unwrap()
    else {
        panic!()
    };
    assert_eq!(value.luminance, Some(1.20));
    assert_eq!(value.x, Some(-0.0031));
    assert_eq!(value.y, Some(0.0012));
}

#[test]
fn ok11_and_ok12_placeholders_become_none_and_real_values_stay() {
    let Reply::Measurement { value, .. } = parse_reply(b"OK11,  52.31, .0000, .0000\r\n").unwrap()
    else {
        panic!()
    };
    assert_eq!(
        (value.luminance, value.x, value.y),
        (Some(52.31), None, None)
    );
    let Reply::Measurement { value, .. } = parse_reply(b"OK12,-999999, .3127, .3290\r\n").unwrap()
    else {
        panic!()
    };
    assert_eq!(value.luminance, None);
    assert_eq!(value.x, Some(0.3127));
    // The other reading of the inferred fact: a real value above the display range.
    let Reply::Measurement { value, .. } = parse_reply(b"OK12, 310000, .3127, .3290\r\n").unwrap()
    else {
        panic!()
    };
    assert_eq!(value.luminance, Some(310000.0));
}

#[test]
fn every_code_maps_both_ways_with_its_meaning() {
    for s in Status::ALL {
        let line = encode_code(s);
        assert_eq!(parse_reply(&line).unwrap(), Reply::Code(s));
        assert!(!s.meaning().is_empty());
    }
    assert_eq!(
        Status::Er10.to_string().split(" (").next().unwrap(),
        "ER10: luminance and chromaticity over the measuring range"
    );
    assert!(Status::Er30.to_string().contains("battery"));
    assert!(Status::Er20.to_string().contains("EEPROM"));
}

#[test]
fn malformed_replies_are_named() {
    assert_eq!(
        parse_reply(b"OK00,  123.4, .3127"),
        Err(ReplyError::NoTerminator)
    );
    assert_eq!(
        parse_reply(b"OK00,  12?.4, .3127, .3290\r\n"),
        Err(ReplyError::ParitySubstitute { index: 9 })
    );
    assert_eq!(
        parse_reply(b"OK00,  1\x003.4, .3127, .3290\r\n"),
        Err(ReplyError::NotAscii { index: 8, byte: 0 })
    );
    assert_eq!(
        parse_reply(b"XX99\r\n"),
        Err(ReplyError::UnknownStatus("XX99".into()))
    );
    assert_eq!(
        parse_reply(b"OK00,  123.4\r\n"),
        Err(ReplyError::MissingData {
            status: "OK00",
            fields: 1
        })
    );
    assert_eq!(
        parse_reply(b"ER10,  123.4, .3127, .3290\r\n"),
        Err(ReplyError::UnexpectedData {
            status: "ER10",
            fields: 3
        })
    );
    assert!(matches!(
        parse_reply(b"OK00,  1.2.3, .3127, .3290\r\n"),
        Err(ReplyError::BadNumber { field: "Y", .. })
    ));
    assert!(matches!(
        parse_reply(b"OK00,123.4 , .3127, .3290\r\n"),
        Err(ReplyError::BadNumber { field: "Y", .. })
    ));
    // Rust's float parser takes these; a meter's reply never holds them.
    for reply in [
        &b"OK00,    NaN, .3127, .3290\r\n"[..],
        b"OK00,    inf, .3127, .3290\r\n",
        b"OK00,  1e308, .3127, .3290\r\n",
        b"OK00,  123.4,   NaN, .3290\r\n",
    ] {
        assert!(
            matches!(parse_reply(reply), Err(ReplyError::BadNumber { .. })),
            "{:?}",
            String::from_utf8_lossy(reply)
        );
    }
}

#[test]
fn device_side_encodes_the_28_byte_layout() {
    let v = Yxy {
        luminance: Some(123.4),
        x: Some(0.3127),
        y: Some(0.329),
    };
    let line = encode_measurement(Status::Ok00, &v);
    assert_eq!(line, b"OK00,  123.4, .3127, .3290\r\n");
    let cases: [(f64, &[u8]); 5] = [
        (10.73, b"  10.73"),
        (0.523, b"  0.523"),
        (0.0049, b"  0.005"),
        (1234.4, b"   1234"),
        (299000.0, b" 299000"),
    ];
    for (lum, field) in cases {
        let line = encode_measurement(
            Status::Ok00,
            &Yxy {
                luminance: Some(lum),
                ..v
            },
        );
        assert_eq!(line.len(), MES_REPLY_LEN, "{lum}");
        assert_eq!(&line[5..12], field, "{lum}");
    }
    let over = encode_measurement(
        Status::Ok12,
        &Yxy {
            luminance: None,
            ..v
        },
    );
    assert_eq!(over, b"OK12,-999999, .3127, .3290\r\n");
    let chroma = encode_measurement(
        Status::Ok11,
        &Yxy {
            luminance: Some(52.31),
            x: None,
            y: None,
        },
    );
    assert_eq!(chroma, b"OK11,  52.31, .0000, .0000\r\n");
}

#[test]
fn device_side_parses_commands() {
    assert_eq!(parse_command(b"MES\r\n"), Ok(Command::Measure));
    assert_eq!(parse_command(b"CLE\r\n"), Ok(Command::Clear));
    assert_eq!(
        parse_command(b"MDS,07\r\n"),
        Ok(Command::SetMode(Mode::Slow))
    );
    assert_eq!(
        parse_command(b"MDS,08\r\n"),
        Err(CommandError::BadMode("08".into()))
    );
    assert_eq!(
        parse_command(b"FOO\r\n"),
        Err(CommandError::Unknown("FOO".into()))
    );
}

#[test]
fn encoded_measurements_parse_back() {
    for lum in [0.0123, 0.523, 5.5, 10.73, 123.4, 4567.0, 120000.0] {
        for (x, y) in [(0.3127, 0.329), (0.64, 0.33), (0.15, 0.06)] {
            let v = Yxy {
                luminance: Some(lum),
                x: Some(x),
                y: Some(y),
            };
            let Reply::Measurement { value, .. } =
                parse_reply(&encode_measurement(Status::Ok00, &v)).unwrap()
            else {
                panic!()
            };
            let l = value.luminance.unwrap();
            assert!((l - lum).abs() <= lum * 5e-4 + 5e-4, "{lum} → {l}");
            assert!((value.x.unwrap() - x).abs() < 5e-5);
            assert!((value.y.unwrap() - y).abs() < 5e-5);
        }
    }
}

proptest::proptest! {
    #[test]
    fn arbitrary_bytes_never_panic(bytes in proptest::collection::vec(proptest::prelude::any::<u8>(), 0..40)) {
        let _ = parse_reply(&bytes);
        let _ = parse_command(&bytes);
    }

    #[test]
    fn any_reading_in_range_survives_the_wire(
        lum in 0.001f64..299_000.0,
        x in 0.0001f64..0.9,
        y in 0.0001f64..0.9,
    ) {
        let v = Yxy { luminance: Some(lum), x: Some(x), y: Some(y) };
        let line = encode_measurement(Status::Ok00, &v);
        proptest::prop_assert_eq!(line.len(), MES_REPLY_LEN);
        let Ok(Reply::Measurement { value, .. }) = parse_reply(&line) else {
            return Err(proptest::test_runner::TestCaseError::fail("did not parse"));
        };
        // Four significant digits (≥ 1), three decimals below 10: half a unit of the last.
        let tol = if lum >= 10.0 { lum * 5e-4 } else { 5e-4 } + 1e-9;
        proptest::prop_assert!((value.luminance.unwrap() - lum).abs() <= tol);
        proptest::prop_assert!((value.x.unwrap() - x).abs() <= 5e-5 + 1e-12);
        proptest::prop_assert!((value.y.unwrap() - y).abs() <= 5e-5 + 1e-12);
    }
}

#[test]
fn a_number_too_long_for_a_float_is_not_infinity() {
    let digits = "9".repeat(400);
    let reply = format!("OK00, {digits},.3127,.3290\r\n");
    assert!(matches!(
        parse_reply(reply.as_bytes()),
        Err(ReplyError::BadNumber { field: "Y", .. })
    ));
    // The error quotes at most 80 characters of the field.
    let e = parse_reply(reply.as_bytes()).unwrap_err().to_string();
    assert!(e.contains("(401 characters in all)"), "{e}");
    assert!(e.len() < 200, "{e}");
}
