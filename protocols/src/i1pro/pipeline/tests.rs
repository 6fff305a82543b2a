//! Every step against numbers worked out by hand on the fixture's small tables (a few
//! distinct cell values, a 5-tap filter whose weights sum to 1).

use super::*;
use crate::i1pro::fixture::{calibration_a_to_d, calibration_e, spectrum};

const NORMAL: Gain = Gain::Normal;

fn exposure(t: f64) -> Exposure {
    Exposure {
        integration_s: t,
        gain: NORMAL,
    }
}

fn reading(cells: impl Fn(usize) -> i32) -> RawReading {
    let mut c = [0; CELLS];
    for (j, v) in c.iter_mut().enumerate() {
        *v = cells(j);
    }
    RawReading {
        cells: c,
        shielded: None,
    }
}

fn abs(cells: impl Fn(usize) -> f64, shielded: f64) -> AbsRaw {
    let mut c = [0.0; CELLS];
    for (j, v) in c.iter_mut().enumerate() {
        *v = cells(j);
    }
    AbsRaw { cells: c, shielded }
}

fn close(a: f64, b: f64, tol: f64) {
    assert!((a - b).abs() <= tol, "{a} vs {b}");
}

#[test]
fn horner() {
    // 1 + 2·2 + 0.5·4 + 0.25·8 = 9
    assert_eq!(linearise(&[1.0, 2.0, 0.5, 0.25], 2.0), 9.0);
    assert_eq!(linearise(&[3.0], 1e9), 3.0);
}

#[test]
fn rev_a_to_d_linearises_then_scales_and_patches_the_junk_cells() {
    let cal = calibration_a_to_d();
    let r = reading(|j| match j {
        0 => 7,
        10 => -512,
        127 => 9,
        _ => 1024,
    });
    let a = to_absraw(&cal, &r, &exposure(0.5)).unwrap();
    // 1024 + 1024²/2^19 = 1026, ×(1/0.5) = 2052; −512 + 512²/2^19 = −511.5 → −1023.
    assert_eq!(a.cells[1], 2052.0);
    assert_eq!(a.cells[10], -1023.0);
    assert_eq!(a.cells[0], 2052.0);
    assert_eq!(a.cells[127], 2052.0);
    assert_eq!(a.shielded, 0.0);

    // High gain: polynomial 0.5 + v, factor 9.5: (1024 + 0.5) / (0.25 · 9.5) = 431.368421…
    let high = Exposure {
        integration_s: 0.25,
        gain: Gain::High,
    };
    let a = to_absraw(&cal, &r, &high).unwrap();
    close(a.cells[1], 1024.5 / 2.375, 1e-12);
    close(a.cells[1], 431.368_421_052_631_6, 1e-9);
}

#[test]
fn rev_e_only_scales() {
    let cal = calibration_e();
    let mut r = reading(|_| 2000);
    r.shielded = Some([10, 20, 30, 40, 50, 60]);
    let a = to_absraw(&cal, &r, &exposure(0.5)).unwrap();
    assert_eq!(a.cells[0], 4000.0);
    assert_eq!(a.cells[127], 4000.0);
    // mean 35, ×2
    assert_eq!(a.shielded, 70.0);
    let high = Exposure {
        integration_s: 0.5,
        gain: Gain::High,
    };
    assert_eq!(
        to_absraw(&cal, &r, &high).unwrap_err(),
        PipelineError::NoHighGainOnRevE
    );
    r.shielded = None;
    assert!(matches!(
        to_absraw(&cal, &r, &exposure(0.5)),
        Err(PipelineError::Shape { .. })
    ));
    assert_eq!(
        to_absraw(&calibration_a_to_d(), &reading(|_| 0), &exposure(0.0)).unwrap_err(),
        PipelineError::IntegrationTime(0.0)
    );
}

#[test]
fn rev_a_to_d_dark_is_subtracted_cell_by_cell() {
    let cal = calibration_a_to_d();
    let mut r = vec![abs(|j| 2052.0 + j as f64, 0.0)];
    subtract_dark(&cal, &mut r, &abs(|_| 52.0, 0.0), &exposure(0.5)).unwrap();
    assert_eq!(r[0].cells[0], 2000.0);
    assert_eq!(r[0].cells[100], 2100.0);
}

#[test]
fn drift_correction_by_hand() {
    // z = max(1.144·85 = 97.24, 1.01·90, 1.01·80, 1.01·100 = 101) = 101;
    // 101 − (101 − 100)·(101 − 90)/(101 − 80) = 101 − 11/21.
    let d = drift_corrected_dark(&abs(|_| 100.0, 80.0), 90.0);
    close(d[5], 101.0 - 11.0 / 21.0, 1e-12);
    // z = 1.144·90 = 102.96 wins; 102.96 − 92.96·2.96/22.96 = 90.975 609 76…
    let d = drift_corrected_dark(&abs(|_| 10.0, 80.0), 100.0);
    close(d[0], 90.975_609_76, 1e-8);
    // No drift, no change.
    let d = drift_corrected_dark(&abs(|j| j as f64, 80.0), 80.0);
    close(d[77], 77.0, 1e-12);
}

#[test]
fn rev_e_linearises_after_dark_subtraction() {
    let cal = calibration_e();
    let mut r = vec![abs(|_| 4000.0, 60.0)];
    subtract_dark(&cal, &mut r, &abs(|_| 400.0, 60.0), &exposure(0.5)).unwrap();
    // (4000 − 400)/2 = 1800 counts; 1800 + 1800²/2^20 = 1803.089 904 785 156 25; ×2.
    close(r[0].cells[9], 3606.1798095703125, 1e-9);
}

#[test]
fn averaging_flags_saturation_and_inconsistency() {
    let a = abs(|j| if j == 0 { 5000.0 } else { 100.0 }, 0.0);
    let b = abs(|_| 110.0, 0.0);
    let avg = average(Revision::AToD, &[a.clone(), b], Some(111.0), 1.0).unwrap();
    assert_eq!(avg.mean.cells[5], 105.0);
    assert_eq!(avg.mean.cells[0], 2555.0);
    assert_eq!(avg.highest, 110.0);
    // means 100 and 110: 10 / 105 = 0.095 ≤ 0.1; the junk 5000 is not looked at.
    assert!(!avg.saturated && !avg.inconsistent);

    let c = abs(|_| 112.0, 0.0);
    let avg = average(Revision::AToD, &[a.clone(), c], Some(111.0), 1.0).unwrap();
    // 12 / 106 = 0.113 > 0.1, and 112 > 111.
    assert!(avg.saturated && avg.inconsistent);

    // Rev E has no junk cells: cell 0 counts.
    let avg = average(Revision::E, &[a], Some(1000.0), 1.0).unwrap();
    assert_eq!(avg.highest, 5000.0);
    assert!(avg.saturated);

    // Near zero the dark threshold sets the scale: spread 3 against max(1.5, 2·10) = 20 is
    // 0.15, inconsistent; against 2·20 = 40 it is 0.075.
    let z = [abs(|_| 0.0, 0.0), abs(|_| 3.0, 0.0)];
    assert!(
        average(Revision::AToD, &z, None, 10.0)
            .unwrap()
            .inconsistent
    );
    assert!(
        !average(Revision::AToD, &z, None, 20.0)
            .unwrap()
            .inconsistent
    );
    assert_eq!(
        average(Revision::AToD, &[], None, 1.0).unwrap_err(),
        PipelineError::NoReadings
    );
}

#[test]
fn thresholds_by_hand() {
    let cal = calibration_a_to_d();
    let none: [RawReading; 0] = [];
    // 150 + 900·0.5 = 600 counts.
    assert_eq!(dark_threshold_counts(&cal, &exposure(0.5), &none), 600.0);
    // ×2 per second: saturation 90000, dark 1200.
    assert_eq!(
        thresholds(&cal, &exposure(0.5), &none).unwrap(),
        (90_000.0, 1200.0)
    );
    // High gain: 600 × 9.5 = 5700 counts, ÷ (0.5 · 9.5): the same 1200; saturation
    // 45000 ÷ 4.75 = 9473.68….
    let high = Exposure {
        integration_s: 0.5,
        gain: Gain::High,
    };
    assert_eq!(dark_threshold_counts(&cal, &high, &none), 5700.0);
    let (sat, dark) = thresholds(&cal, &high, &none).unwrap();
    close(dark, 1200.0, 1e-9);
    close(sat, 45_000.0 / 4.75, 1e-9);
    // Rev E: the mean of the shielded cells, (10 + … + 60)/6 = 35 and (20 + … + 70)/6 = 45.
    let cal_e = calibration_e();
    let mut a = reading(|_| 0);
    a.shielded = Some([10, 20, 30, 40, 50, 60]);
    let mut b = a.clone();
    b.shielded = Some([20, 30, 40, 50, 60, 70]);
    assert_eq!(dark_threshold_counts(&cal_e, &exposure(0.5), &[a, b]), 40.0);

    let dark = average(Revision::AToD, &[abs(|_| 2401.0, 0.0)], None, 1200.0).unwrap();
    assert!(dark.too_bright_for_dark(1200.0));
    assert!(!dark.too_bright_for_dark(1200.5));
}

#[test]
fn stray_light_by_hand() {
    let cal = calibration_e();
    let s = stray_light(cal.rev_e.as_ref().unwrap(), &[1.0; BANDS]);
    let m = 1638.5 / 32767.0;
    // Edge rows have one neighbour, inner rows two.
    close(s[0], 1.0 - m, 1e-15);
    close(s[17], 1.0 - 2.0 * m, 1e-15);
    close(s[35], 1.0 - m, 1e-15);
}

#[test]
fn calibrations_by_hand() {
    let cal = calibration_a_to_d();
    let s = [2.0; BANDS];
    let e = emissive(&cal, &s);
    assert_eq!(e[0], 2.0 / 512.0);
    assert_eq!(e[32], 2.0 * 1.5 / 512.0);
    let a = ambient(&cal, &s).unwrap();
    assert_eq!(a[32], 2.0 * 1.5 / 512.0 * 4.0);
    let mut none = cal.clone();
    none.ambient = None;
    assert_eq!(ambient(&none, &s).unwrap_err(), PipelineError::NoAmbient);

    // White tile read as 2000 except band 3 (500, clamped to 1000).
    let white = spectrum(|w| if w == 3.0 { 500.0 } else { 2000.0 });
    let f = reflective_factors(&cal, &white).unwrap();
    assert_eq!(f[0], 0.875 / 2000.0);
    assert_eq!(f[3], (0.875 - 3.0 / 256.0) / 1000.0);
    // A sample reading half the white gives half the tile's reflectance.
    let r = reflective(&[1000.0; BANDS], &f);
    close(r[10], (0.875 - 10.0 / 256.0) / 2.0, 1e-15);
    let mut monitor = cal.clone();
    monitor.white_reference = None;
    assert_eq!(
        reflective_factors(&monitor, &white).unwrap_err(),
        PipelineError::NoWhiteReference
    );

    // Open aperture 100 everywhere but 0.1 in band 0: mean 97.225, floor 0.3889.
    let open = spectrum(|w| if w == 0.0 { 0.1 } else { 100.0 });
    let t = transmissive_factors(&open);
    close(t[0], 1.0 / 0.388_9, 1e-9);
    assert_eq!(t[1], 0.01);
    close(transmissive(&[50.0; BANDS], &t)[1], 0.5, 1e-15);
}

#[test]
fn whole_chain_by_hand() {
    let cal = calibration_a_to_d();
    let e = exposure(0.5);
    // Dark of 0 counts; two readings of 1024 counts: absraw 2052 everywhere (junk cells
    // patched), the weights sum to 1, so every band is 2052.
    let dark = super::dark(&cal, &[reading(|_| 0)], &e).unwrap();
    assert_eq!(dark.mean.cells[50], 0.0);
    let (s, avg) = measure(
        &cal,
        &[reading(|_| 1024), reading(|_| 1024)],
        &dark.mean,
        &e,
    )
    .unwrap();
    assert!(!avg.saturated && !avg.inconsistent);
    for v in s {
        assert_eq!(v, 2052.0);
    }
    assert_eq!(emissive(&cal, &s)[0], 2052.0 / 512.0);
}

#[test]
fn dark_interpolates_linearly_in_counts() {
    // 1000 /s at 0.1 s is 100 counts; 50 /s at 4 s is 200 counts: b = 100/3.9 counts/s.
    // At 1 s: 100 + 0.9·100/3.9 = 123.076 923… counts, /1 s.
    let d1 = abs(|_| 1000.0, 20.0);
    let d2 = abs(|_| 50.0, 1.0);
    let d = interpolate_dark(&d1, 0.1, &d2, 4.0, 1.0).unwrap();
    close(d.cells[3], 100.0 + 90.0 / 3.9, 1e-12);
    close(d.cells[3], 123.076_923_076_9, 1e-9);
    // shielded: 2 counts and 4 counts → 2 + 0.9·2/3.9 at 1 s.
    close(d.shielded, 2.0 + 1.8 / 3.9, 1e-12);
    // At the measured times it gives the measured darks back.
    close(
        interpolate_dark(&d1, 0.1, &d2, 4.0, 0.1).unwrap().cells[0],
        1000.0,
        1e-9,
    );
    close(
        interpolate_dark(&d1, 0.1, &d2, 4.0, 4.0).unwrap().cells[0],
        50.0,
        1e-12,
    );
    assert_eq!(
        interpolate_dark(&d1, 1.0, &d2, 1.0, 2.0).unwrap_err(),
        PipelineError::SameDarkTimes(1.0)
    );
    assert!(interpolate_dark(&d1, 0.1, &d2, 4.0, -1.0).is_err());
}
