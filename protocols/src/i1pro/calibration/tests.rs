//! The calibration through the EEPROM and back, and every way it can be incomplete.

use super::*;
use crate::i1pro::fixture::{calibration_a_to_d, calibration_e, filter};

#[test]
fn a_to_d_calibration_survives_its_eeprom_image() {
    let cal = calibration_a_to_d();
    let image = cal.to_image().unwrap();
    assert_eq!(image.len(), 8192);
    assert_eq!(Calibration::from_image(&image, Model::I1Pro).unwrap(), cal);
    assert!(cal.has_ambient());
    assert!(!cal.uv_cut());
}

#[test]
fn rev_e_calibration_survives_its_eeprom_image() {
    let cal = calibration_e();
    let image = cal.to_image().unwrap();
    assert_eq!(image.len(), 16384);
    assert_eq!(Calibration::from_image(&image, Model::I1Pro2).unwrap(), cal);
    assert!(cal.uv_cut());
    // Read as a Rev A–D unit the image has no stray-light data: that is a model error.
    let mut wrong = cal.clone();
    wrong.model = Model::I1Pro;
    assert!(matches!(wrong.check(), Err(CalibrationError::Model { .. })));
}

#[test]
fn every_required_key_is_named_when_missing() {
    let required = [
        key::LIN_NORMAL,
        key::LIN_HIGH,
        key::FILTER_START,
        key::FILTER_COUNT,
        key::FILTER_COEF,
        key::WHITE_REF,
        key::EMISSIVE,
        key::AMBIENT,
        key::SENSOR_TARGET,
        key::DARK_THRESHOLD,
        key::SATURATION_NORMAL,
        key::SATURATION_HIGH,
        key::SERIAL,
        key::HIGH_GAIN_FACTOR,
        key::MIN_INTEGRATION,
        key::MAX_INTEGRATION,
        key::CPLD_REVISION,
        key::CAPABILITIES,
        key::PHYSICAL_FILTER,
        key::CAPABILITIES_E,
        key::STRAY_LIGHT,
        key::STRAY_LIGHT_SCALE,
        key::WAVELENGTH_POLY_EMISSIVE,
    ];
    let full = calibration_e().to_eeprom().unwrap();
    for k in required {
        let mut e = full.clone();
        e.remove(k).unwrap();
        let err = Calibration::from_eeprom(&e, Model::I1Pro2).unwrap_err();
        assert_eq!(
            err,
            CalibrationError::Missing {
                key: k,
                name: key_name(k),
                model: "i1Pro 2"
            }
        );
        assert!(err.to_string().contains(&format!("{k:#06x}")), "{err}");
    }
    let mut e = full.clone();
    e.remove(key::WHITE_REF);
    assert_eq!(
        Calibration::from_eeprom(&e, Model::I1Pro2)
            .unwrap_err()
            .to_string(),
        "the EEPROM lacks key 0x044c (white tile reflectance), which the i1Pro 2 needs"
    );
}

#[test]
fn optional_keys_may_be_missing() {
    let mut e = calibration_e().to_eeprom().unwrap();
    e.remove(key::MANUFACTURE_DATE);
    e.remove(key::WAVELENGTH_POLY_REFLECTIVE);
    let cal = Calibration::from_eeprom(&e, Model::I1Pro2).unwrap();
    assert_eq!(cal.manufacture_date, None);
    assert_eq!(cal.rev_e.unwrap().wavelength_poly_reflective, None);

    // The i1Monitor has no white tile.
    let mut monitor = calibration_a_to_d();
    monitor.model = Model::I1Monitor;
    monitor.white_reference = None;
    let image = monitor.to_image().unwrap();
    assert_eq!(
        Calibration::from_image(&image, Model::I1Monitor).unwrap(),
        monitor
    );
    assert!(matches!(
        Calibration::from_image(&image, Model::I1Pro),
        Err(CalibrationError::Missing { key: 0x044C, .. })
    ));

    // Without the diffuser's capability bits, an all −1 ambient table means no ambient.
    let mut plain = calibration_a_to_d();
    plain.capabilities = 0;
    plain.ambient = None;
    let back = Calibration::from_image(&plain.to_image().unwrap(), Model::I1Pro).unwrap();
    assert_eq!(back.ambient, None);
    assert!(!back.has_ambient());
}

#[test]
fn a_diffuser_claimed_over_a_no_ambient_table_gives_no_ambient_mode() {
    // The capability bits claim the diffuser, but the table is the −1 marker that units
    // without one store: read as it is, it would turn every reading into negative lux.
    let mut claimed = calibration_a_to_d();
    assert_ne!(claimed.capabilities & CAPS_AMBIENT, 0);
    claimed.ambient = None;
    let items = claimed.to_eeprom().unwrap();
    assert_eq!(
        AmbientTable::in_eeprom(&items),
        AmbientTable::NoAmbientMarker
    );
    let back = Calibration::from_eeprom(&items, Model::I1Pro).unwrap();
    assert_eq!(back.ambient, None);
    assert!(back.claims_ambient());
    assert!(!back.has_ambient());

    // A table with one factor that is not positive calibrates nothing either; which band
    // is named.
    let mut bad = calibration_a_to_d().ambient.unwrap();
    bad[7] = 0.0;
    let mut items = calibration_a_to_d().to_eeprom().unwrap();
    items
        .insert(
            key::AMBIENT,
            Value::Floats(bad.iter().map(|&v| v as f32).collect()),
        )
        .unwrap();
    assert_eq!(
        AmbientTable::in_eeprom(&items),
        AmbientTable::Unusable {
            band: 7,
            value: 0.0
        }
    );
    assert!(!Calibration::from_eeprom(&items, Model::I1Pro)
        .unwrap()
        .has_ambient());

    // Rev E claims it with its own capability word.
    let mut e = calibration_e();
    e.capabilities = 0;
    e.ambient = None;
    let back = Calibration::from_image(&e.to_image().unwrap(), Model::I1Pro2).unwrap();
    assert!(back.claims_ambient() && !back.has_ambient());

    assert_eq!(AmbientTable::of(None), AmbientTable::Missing);
    assert_eq!(
        AmbientTable::of(calibration_a_to_d().ambient.as_ref()),
        AmbientTable::Usable
    );
}

#[test]
fn malformed_items_are_errors() {
    let full = calibration_a_to_d().to_eeprom().unwrap();

    let mut e = full.clone();
    e.insert(key::EMISSIVE, Value::Floats(vec![1.0; 35]))
        .unwrap();
    assert_eq!(
        Calibration::from_eeprom(&e, Model::I1Pro).unwrap_err(),
        CalibrationError::Length {
            key: key::EMISSIVE,
            name: "emissive calibration factors",
            expected: "36".into(),
            found: 35
        }
    );

    // Band 35 starting at cell 125 with 5 coefficients would read cells 125..130.
    let mut starts: Vec<i32> = (0..36).map(|w| 3 * w).collect();
    starts[35] = 125;
    let mut e = full.clone();
    e.insert(key::FILTER_START, Value::Ints(starts)).unwrap();
    assert_eq!(
        Calibration::from_eeprom(&e, Model::I1Pro).unwrap_err(),
        CalibrationError::FilterRange {
            band: 35,
            start: 125,
            end: 130
        }
    );

    let mut e = full.clone();
    e.insert(key::FILTER_COEF, Value::Floats(vec![0.5; 179]))
        .unwrap();
    assert!(matches!(
        Calibration::from_eeprom(&e, Model::I1Pro),
        Err(CalibrationError::Length {
            key: key::FILTER_COEF,
            found: 179,
            ..
        })
    ));

    let mut e = full.clone();
    e.insert(key::LIN_NORMAL, Value::Floats(vec![])).unwrap();
    assert!(matches!(
        Calibration::from_eeprom(&e, Model::I1Pro),
        Err(CalibrationError::Length {
            key: key::LIN_NORMAL,
            found: 0,
            ..
        })
    ));
}

#[test]
fn filter_applies_by_hand() {
    // cells[j] = j: band w = Σ c_k (3w + k) = 3w + (0.25·1 + 0.375·2 + 0.25·3 + 0.0625·4) = 3w + 2.
    let mut cells = [0.0; 128];
    for (j, c) in cells.iter_mut().enumerate() {
        *c = j as f64;
    }
    let s = filter().apply(&cells);
    for (w, v) in s.iter().enumerate() {
        assert_eq!(*v, 3.0 * w as f64 + 2.0);
    }
    assert!(matches!(
        Filter::new(vec![0; 35], vec![vec![1.0]; 35]),
        Err(CalibrationError::FilterBands { found: 35 })
    ));
}

#[test]
fn stray_light_matrix_by_hand() {
    let m = calibration_e().rev_e.unwrap().stray_light_matrix();
    // 1 + 0 on the diagonal; 0.5 · (−3277) / 32767 next to it; nothing further out.
    assert_eq!(m[0][0], 1.0);
    assert!((m[0][1] - (-1638.5 / 32767.0)).abs() < 1e-15);
    assert!((m[5][4] + 0.050_004_577_776).abs() < 1e-12);
    assert_eq!(m[0][2], 0.0);
}

proptest::proptest! {
    /// Corrupting any bytes of a good image (directory, counts, filter tables) gives an error
    /// or a calibration, never a panic.
    #[test]
    fn corrupted_images_never_panic(
        hits in proptest::collection::vec((0usize..0x4000, proptest::prelude::any::<u8>()), 1..40),
        rev_e in proptest::prelude::any::<bool>(),
    ) {
        let (cal, model) = if rev_e {
            (calibration_e(), Model::I1Pro2)
        } else {
            (calibration_a_to_d(), Model::I1Pro)
        };
        let mut image = cal.to_image().unwrap();
        // Aim half the hits at the directories and the first items, where damage matters.
        for (i, (at, byte)) in hits.into_iter().enumerate() {
            let at = if i % 2 == 0 { 0x1000 + at % 0x400 } else { at % image.len() };
            image[at] = byte;
        }
        let _ = Calibration::from_image(&image, model);
    }
}
