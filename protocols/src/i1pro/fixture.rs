//! Synthetic calibrations for the tests: every float is a short binary fraction, so it
//! survives the EEPROM's float32 exactly and round trips compare with `==`.

use super::calibration::{caps_e, Calibration, Filter, RevECalibration, CAPS_AMBIENT};
use super::{Model, BANDS};

/// Band `w` reads cells `3w .. 3w+5` with weights summing to 1; band 0 touches junk cell 0.
pub fn filter() -> Filter {
    let starts = (0..BANDS).map(|w| 3 * w).collect();
    let coef = vec![vec![0.0625, 0.25, 0.375, 0.25, 0.0625]; BANDS];
    Filter::new(starts, coef).unwrap()
}

pub fn spectrum(f: impl Fn(f64) -> f64) -> [f64; BANDS] {
    let mut s = [0.0; BANDS];
    for (w, v) in s.iter_mut().enumerate() {
        *v = f(w as f64);
    }
    s
}

pub fn calibration_a_to_d() -> Calibration {
    Calibration {
        model: Model::I1Pro,
        serial: 1_234_567,
        manufacture_date: Some(10_072_002),
        cpld_revision: 301,
        capabilities: CAPS_AMBIENT,
        physical_filter: 0x80,
        // 2^-19 ≈ 1.9e-6: a gentle bend, like the real polynomials.
        linearisation_normal: vec![0.0, 1.0, 1.0 / 524_288.0, 0.0],
        linearisation_high: vec![0.5, 1.0, 0.0, 0.0],
        high_gain_factor: 9.5,
        min_integration_s: 19.0 / 4096.0,
        max_integration_s: 4.5,
        filter: filter(),
        white_reference: Some(spectrum(|w| 0.875 - w / 256.0)),
        emissive: spectrum(|w| (1.0 + w / 64.0) / 512.0),
        ambient: Some(spectrum(|w| 3.0 + w / 32.0)),
        sensor_target: 37_000,
        dark_threshold: 150,
        saturation_normal: 45_000,
        saturation_high: 45_000,
        rev_e: None,
    }
}

pub fn calibration_e() -> Calibration {
    let mut stray = [[0i16; BANDS]; BANDS];
    for (i, row) in stray.iter_mut().enumerate() {
        for (j, v) in row.iter_mut().enumerate() {
            if i.abs_diff(j) == 1 {
                *v = -3277;
            }
        }
    }
    Calibration {
        model: Model::I1Pro2,
        cpld_revision: 629,
        capabilities: 0,
        physical_filter: 0x82,
        linearisation_normal: vec![0.0, 1.0, 1.0 / 1_048_576.0, 0.0],
        rev_e: Some(RevECalibration {
            capabilities: caps_e::AMBIENT | caps_e::WAVELENGTH_LED | caps_e::UV_FILTER,
            stray_light: stray,
            stray_light_scale: 0.5,
            wavelength_poly_emissive: [380.0, 2.75, 0.0, 0.0],
            wavelength_poly_reflective: Some([379.5, 2.75, 0.0, 0.0]),
        }),
        ..calibration_a_to_d()
    }
}
