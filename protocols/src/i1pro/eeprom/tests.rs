//! The container against an image laid out by hand, its errors, and build → parse.

use super::*;

/// A Rev A–D image written byte by byte: four items, then 46 closing markers (50 entries,
/// 4 + 6·50 = 304 directory bytes).
fn hand_image() -> Vec<u8> {
    let mut im = vec![0xFFu8; SIZE_A_TO_D];
    im[0x1000..0x1004].copy_from_slice(&[0x00, 0x01, 0x01, 0x30]);
    let entries: [(u16, u32); 5] = [
        (0x04BB, 0x1200),
        (0x03E8, 0x1204),
        (0x2F58, 0x120C),
        (0x1234, 0x1210),
        (0x0001, 0x1212),
    ];
    for i in 0..50 {
        let (k, a) = entries.get(i).copied().unwrap_or((0x00FF, 0x1212));
        let at = 0x1004 + 6 * i;
        im[at..at + 2].copy_from_slice(&k.to_be_bytes());
        im[at + 2..at + 6].copy_from_slice(&a.to_be_bytes());
    }
    // serial 1234567 = 0x0012D687; floats 1.0 and −2.0; shorts −2 and 3; two unknown bytes.
    let data = [
        0x00, 0x12, 0xD6, 0x87, 0x3F, 0x80, 0x00, 0x00, 0xC0, 0x00, 0x00, 0x00, 0xFF, 0xFE, 0x00,
        0x03, 0xAA, 0xBB,
    ];
    im[0x1200..0x1212].copy_from_slice(&data);
    im
}

fn set_entry(im: &mut [u8], i: usize, key: u16, addr: u32) {
    let at = 0x1004 + 6 * i;
    im[at..at + 2].copy_from_slice(&key.to_be_bytes());
    im[at + 2..at + 6].copy_from_slice(&addr.to_be_bytes());
}

#[test]
fn hand_made_image_parses_to_its_items() {
    let e = Eeprom::parse(&hand_image(), Revision::AToD).unwrap();
    assert_eq!(e.get(0x04BB), Some(&Value::Ints(vec![1_234_567])));
    assert_eq!(e.get(0x03E8), Some(&Value::Floats(vec![1.0, -2.0])));
    assert_eq!(e.get(0x2F58), Some(&Value::Shorts(vec![-2, 3])));
    assert_eq!(e.get(0x1234), Some(&Value::Bytes(vec![0xAA, 0xBB])));
    assert_eq!(e.keys().count(), 4);
    assert_eq!(key_name(0x04BB), "serial number");
    assert_eq!(key_name(0x2715 + 1000), "log measurement count");
    assert_eq!(kind_of(0x271D + 1000), ItemKind::Float);
}

#[test]
fn a_key_listed_twice_keeps_its_last_item() {
    let mut im = hand_image();
    // Entry 2 (bytes FF FE 00 03) now also claims the serial: 0xFFFE0003 as i32 = −131069.
    set_entry(&mut im, 2, 0x04BB, 0x120C);
    let e = Eeprom::parse(&im, Revision::AToD).unwrap();
    assert_eq!(e.get(0x04BB), Some(&Value::Ints(vec![-131_069])));
    assert!(e.get(0x2F58).is_none());
}

#[test]
fn broken_directories_are_named() {
    let mut im = hand_image();
    im[0x1001] = 7;
    assert_eq!(
        Eeprom::parse(&im, Revision::AToD).unwrap_err(),
        EepromError::BlockId { table: 1, found: 7 }
    );

    let mut im = hand_image();
    im[0x1002..0x1004].copy_from_slice(&[0x01, 0x00]);
    assert!(matches!(
        Eeprom::parse(&im, Revision::AToD),
        Err(EepromError::DirectorySize { bytes: 256, .. })
    ));

    let mut im = hand_image();
    set_entry(&mut im, 49, 0x04BB, 0x1212);
    assert_eq!(
        Eeprom::parse(&im, Revision::AToD).unwrap_err(),
        EepromError::NoEndMarker { table: 1 }
    );

    let mut im = hand_image();
    set_entry(&mut im, 2, 0x2F58, 0x3000);
    let err = Eeprom::parse(&im, Revision::AToD).unwrap_err();
    assert_eq!(
        err,
        EepromError::OutOfRange {
            key: 0x03E8,
            name: "normal-gain linearisation",
            start: 0x1204,
            end: 0x3000,
            len: 8192
        }
    );
    assert!(err.to_string().contains("0x03e8"), "{err}");

    let mut im = hand_image();
    set_entry(&mut im, 2, 0x2F58, 0x120B);
    assert!(matches!(
        Eeprom::parse(&im, Revision::AToD),
        Err(EepromError::Ragged {
            key: 0x03E8,
            bytes: 7,
            width: 4,
            ..
        })
    ));

    assert!(matches!(
        Eeprom::parse(&hand_image()[..0x1000 + 100], Revision::AToD),
        Err(EepromError::TooSmall { table: 1, .. })
    ));
    // Rev E needs the second directory at 0x2000, beyond an 8 KiB image.
    assert!(matches!(
        Eeprom::parse(&hand_image(), Revision::E),
        Err(EepromError::TooSmall { table: 2, .. })
    ));
}

fn sample() -> Eeprom {
    let mut e = Eeprom::new();
    e.insert(0x04BB, Value::Ints(vec![42])).unwrap();
    e.insert(0x03EC, Value::Floats(vec![0.5, -0.25, 3.0]))
        .unwrap();
    e.insert(0x2715, Value::Ints(vec![9])).unwrap();
    e.insert(0x2715 + 1000, Value::Ints(vec![10])).unwrap();
    e.insert(0x2F58, Value::Shorts(vec![-1, 2, -3])).unwrap();
    e.insert(0x2EE1, Value::Bytes(vec![1, 2, 3, 4, 5, 6, 7, 8]))
        .unwrap();
    e
}

#[test]
fn built_images_parse_back() {
    let e = sample();
    let a = e.build(Revision::AToD, SIZE_A_TO_D).unwrap();
    assert_eq!(a.len(), 8192);
    assert_eq!(Eeprom::parse(&a, Revision::AToD).unwrap(), e);
    // The log keys live from address 0, as in a real instrument.
    assert_eq!(&a[0..4], &9i32.to_be_bytes());

    let im = e.build(Revision::E, SIZE_E).unwrap();
    assert_eq!(&im[0x2000..0x2002], &[0, 2]);
    assert_eq!(Eeprom::parse(&im, Revision::E).unwrap(), e);
    // The Rev E keys are only in the second directory.
    let first = Eeprom::parse(&im, Revision::AToD).unwrap();
    assert!(first.get(0x2F58).is_none() && first.get(0x2EE1).is_none());
    assert_eq!(first.get(0x04BB), Some(&Value::Ints(vec![42])));
}

#[test]
fn building_refuses_what_does_not_fit() {
    assert_eq!(
        Eeprom::new().build(Revision::AToD, 0x1000).unwrap_err(),
        EepromError::TooSmall {
            table: 1,
            address: 0x1000,
            len: 0x1000
        }
    );
    assert!(matches!(
        sample().build(Revision::E, SIZE_A_TO_D),
        Err(EepromError::TooSmall { table: 2, .. })
    ));
    let mut e = Eeprom::new();
    e.insert(0x03EC, Value::Floats(vec![0.0; 2000])).unwrap();
    assert!(matches!(
        e.build(Revision::AToD, SIZE_A_TO_D),
        Err(EepromError::Overflow { table: 1, .. })
    ));
    assert_eq!(
        Eeprom::new()
            .insert(0x04BB, Value::Floats(vec![1.0]))
            .unwrap_err(),
        EepromError::WrongKind {
            key: 0x04BB,
            name: "serial number",
            expected: ItemKind::Int,
            found: ItemKind::Float
        }
    );
    assert_eq!(
        Eeprom::new()
            .insert(0x0042, Value::Bytes(vec![]))
            .unwrap_err(),
        EepromError::MarkerKey { key: 0x42 }
    );
    let mut many = Eeprom::new();
    for k in 0..90u16 {
        many.insert(0x5000 + k, Value::Bytes(vec![1])).unwrap();
    }
    assert!(matches!(
        many.build(Revision::AToD, SIZE_A_TO_D),
        Err(EepromError::TooManyItems { table: 1, .. })
    ));
}

proptest::proptest! {
    #[test]
    fn arbitrary_images_never_panic(bytes in proptest::collection::vec(proptest::prelude::any::<u8>(), 0..0x2400)) {
        let _ = Eeprom::parse(&bytes, Revision::AToD);
        let _ = Eeprom::parse(&bytes, Revision::E);
    }

    #[test]
    fn arbitrary_directories_never_panic(
        entries in proptest::collection::vec((proptest::prelude::any::<u16>(), 0u32..0x2200), 0..90),
        count in 0u16..700,
    ) {
        let mut im = hand_image();
        im[0x1002..0x1004].copy_from_slice(&count.to_be_bytes());
        for (i, (k, a)) in entries.into_iter().enumerate() {
            if 0x1004 + 6 * i + 6 <= im.len() {
                set_entry(&mut im, i, k, a);
            }
        }
        let _ = Eeprom::parse(&im, Revision::AToD);
    }
}
