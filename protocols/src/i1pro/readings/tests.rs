//! Readings against bytes written by hand.

use super::*;
use proptest::prelude::*;

fn a_to_d_bytes(values: &[(usize, u16)]) -> Vec<u8> {
    let mut b = vec![0u8; 256];
    for &(cell, v) in values {
        b[2 * cell..2 * cell + 2].copy_from_slice(&v.to_be_bytes());
    }
    b
}

#[test]
fn rev_a_to_d_cells_are_big_endian_with_the_sign_rule() {
    let b = a_to_d_bytes(&[(0, 0x0005), (1, 0x0102), (2, 0xFFFE), (127, 0xFFFF)]);
    let r = parse(&b, Revision::AToD, 1, 0xFFFF).unwrap();
    assert_eq!(r.len(), 1);
    assert_eq!(r[0].cells[0], 5);
    assert_eq!(r[0].cells[1], 258);
    // 0xFFFE is below max_positive 0xFFFF: positive. 0xFFFF is at it: 65535 − 65536 = −1.
    assert_eq!(r[0].cells[2], 65534);
    assert_eq!(r[0].cells[127], -1);
    assert_eq!(r[0].shielded, None);
    // With max_positive 0x8000, 0x8000 is −32768.
    assert_eq!(signed(0x8000, 0x8000), -32768);
    assert_eq!(signed(0x7FFF, 0x8000), 32767);
}

#[test]
fn rev_e_has_six_shielded_cells_first() {
    let mut b = Vec::new();
    for v in 1..=6u16 {
        b.extend(v.to_be_bytes());
    }
    for j in 0..128u16 {
        b.extend((60000 + j).to_be_bytes());
    }
    assert_eq!(b.len(), 268);
    let r = parse(&b, Revision::E, 1, 0).unwrap();
    assert_eq!(r[0].shielded, Some([1, 2, 3, 4, 5, 6]));
    assert_eq!(r[0].cells[0], 60000);
    assert_eq!(r[0].cells[127], 60127);
}

#[test]
fn wrong_byte_counts_are_errors() {
    let e = parse(&[0; 255], Revision::AToD, 1, 0xFFFF).unwrap_err();
    assert_eq!(
        e,
        ReadingError::Short {
            got: 255,
            expected: 256,
            readings: 1,
            per_reading: 256
        }
    );
    assert_eq!(
        e.to_string(),
        "short read: 255 bytes arrived, 256 expected for 1 readings of 256 bytes"
    );
    assert!(matches!(
        parse(&[0; 3 * 268], Revision::E, 2, 0),
        Err(ReadingError::Long {
            got: 804,
            expected: 536,
            ..
        })
    ));
    assert_eq!(parse(&[], Revision::AToD, 0, 0xFFFF).unwrap(), vec![]);
    // An absurd count is a short read, not an overflow.
    assert!(matches!(
        parse(&[0; 256], Revision::AToD, usize::MAX, 0xFFFF),
        Err(ReadingError::Short { .. })
    ));
    assert_eq!(
        parse_scan(&[0; 3 * 256], Revision::AToD, 0xFFFF)
            .unwrap()
            .len(),
        3
    );
    assert_eq!(
        parse_scan(&[0; 257], Revision::AToD, 0xFFFF).unwrap_err(),
        ReadingError::Partial {
            got: 257,
            per_reading: 256
        }
    );
    assert_eq!(
        parse_scan(&[], Revision::E, 0).unwrap_err(),
        ReadingError::Empty
    );
}

#[test]
fn encoding_checks_shape_and_range() {
    let r = RawReading {
        cells: [0; 128],
        shielded: None,
    };
    assert!(matches!(
        encode(std::slice::from_ref(&r), Revision::E, 0),
        Err(ReadingError::Shape { .. })
    ));
    let mut neg = r.clone();
    neg.cells[5] = -1;
    // −1 is sent as 0xFFFF on Rev A–D …
    let b = encode(&[neg.clone()], Revision::AToD, 0xFFFF).unwrap();
    assert_eq!(&b[10..12], &[0xFF, 0xFF]);
    // … and with max_positive 0x8000 as 0x8000 … 0xFFFF are −32768 … −1.
    assert_eq!(encode(&[neg.clone()], Revision::AToD, 0x8000).unwrap(), b);
    neg.cells[6] = -32769;
    assert!(encode(&[neg.clone()], Revision::AToD, 0x8000).is_err());
    neg.cells[6] = 0;
    // 65535 with max_positive 0xFFFF would read back as −1: refused.
    let mut high = r.clone();
    high.cells[3] = 65535;
    assert_eq!(
        encode(&[high], Revision::AToD, 0xFFFF).unwrap_err(),
        ReadingError::OutOfRange {
            cell: 3,
            value: 65535
        }
    );
    let e = RawReading {
        cells: neg.cells,
        shielded: Some([0; 6]),
    };
    assert!(matches!(
        encode(&[e], Revision::E, 0),
        Err(ReadingError::OutOfRange { cell: 5, value: -1 })
    ));
}

proptest! {
    #[test]
    fn arbitrary_bytes_never_panic(
        bytes in proptest::collection::vec(any::<u8>(), 0..1200),
        n in 0usize..6,
        max_positive in any::<u16>(),
    ) {
        for rev in [Revision::AToD, Revision::E] {
            let _ = parse(&bytes, rev, n, max_positive);
            let _ = parse_scan(&bytes, rev, max_positive);
        }
    }

    #[test]
    fn readings_survive_the_wire(
        values in proptest::collection::vec(any::<u16>(), 134 * 3),
        max_positive in any::<u16>(),
    ) {
        for rev in [Revision::AToD, Revision::E] {
            let bytes: Vec<u8> = values[..3 * rev.values_per_reading()]
                .iter()
                .flat_map(|v| v.to_be_bytes())
                .collect();
            let parsed = parse(&bytes, rev, 3, max_positive).unwrap();
            prop_assert_eq!(encode(&parsed, rev, max_positive).unwrap(), bytes);
        }
    }
}
