//! The pipeline backwards: spectrum → counts → bytes → counts → spectrum must come back to
//! within the rounding of counts to integers, bounded per band by hand below.

use super::*;
use crate::i1pro::calibration::Gain;
use crate::i1pro::fixture::{calibration_a_to_d, calibration_e, spectrum};
use crate::i1pro::pipeline::{self, emissive};
use crate::i1pro::readings;
use proptest::prelude::*;

const MAX_POSITIVE: u16 = 0xFFFF;

fn exposure(t: f64) -> Exposure {
    Exposure {
        integration_s: t,
        gain: Gain::Normal,
    }
}

#[test]
fn newton_inverts_the_linearisation() {
    // 1024 + 1024²/2^19 = 1026.
    let x = inverse_linearise(&[0.0, 1.0, 1.0 / 524_288.0, 0.0], 1026.0).unwrap();
    assert!((x - 1024.0).abs() < 1e-9, "{x}");
    assert_eq!(inverse_linearise(&[0.5, 1.0], 3.0).unwrap(), 2.5);
    assert!(inverse_linearise(&[7.0], 3.0).is_err());
}

#[test]
fn uncalibrating_divides_by_the_factors() {
    let cal = calibration_a_to_d();
    let r = spectrum(|w| 2.0 * (1.0 + w / 64.0) / 512.0);
    assert_eq!(uncalibrate_emissive(&cal, &r).unwrap(), [2.0; BANDS]);
    let mut zero = cal.clone();
    zero.emissive[4] = 0.0;
    assert_eq!(
        uncalibrate_emissive(&zero, &r).unwrap_err(),
        PipelineError::ZeroFactor {
            what: "the emissive calibration factor",
            band: 4,
            nm: 420.0
        }
    );
    let a = uncalibrate_ambient(&cal, &pipeline::ambient(&cal, &[3.0; BANDS]).unwrap()).unwrap();
    for v in a {
        assert!((v - 3.0).abs() < 1e-12);
    }
    assert_eq!(
        uncalibrate_reflective(&[0.5; BANDS], &[0.25; BANDS]).unwrap(),
        [2.0; BANDS]
    );
}

#[test]
fn least_norm_cells_resample_to_the_target() {
    for cal in [calibration_a_to_d(), calibration_e()] {
        let s = spectrum(|w| 1000.0 + 30.0 * w);
        let x = cells_for(&cal, &s).unwrap();
        let back = pipeline::resample(&cal, &x);
        for (b, t) in back.iter().zip(&s) {
            assert!((b - t).abs() < 1e-8, "{b} vs {t}");
        }
        if cal.revision() == Revision::AToD {
            assert_eq!(x[0], x[1]);
            assert_eq!(x[127], x[126]);
        }
        // Cells no band reads get nothing.
        assert_eq!(x[120], 0.0);
    }
}

/// Per band, the most a ±0.5 count rounding can move the calibrated result: Σ|weights| (1
/// here) × 0.5 count × the steepest linearisation slope (below 1.3 for counts < 65536 with
/// c2 ≤ 2^-19) / t × the emissive factor × the largest stray-light row sum (≤ 1.1).
fn rounding_bound(cal: &Calibration, t: f64, band: usize) -> f64 {
    0.5 * 1.3 / t * cal.emissive[band] * 1.1
}

fn round_trip(
    cal: &Calibration,
    radiance: &GridSpectrum,
    t: f64,
) -> (GridSpectrum, pipeline::Averaged) {
    let e = exposure(t);
    let rev = cal.revision();
    let shielded = (rev == Revision::E).then_some([300u16, 310, 290, 305, 295, 300]);
    let dark_raw = RawReading {
        cells: [250; CELLS],
        shielded,
    };
    let dark = pipeline::dark(cal, std::slice::from_ref(&dark_raw), &e).unwrap();
    let r = emissive_reading(cal, &e, radiance, &dark.mean, shielded, MAX_POSITIVE).unwrap();
    let bytes = readings::encode(&[dark_raw, r.clone(), r], rev, MAX_POSITIVE).unwrap();
    let parsed = readings::parse(&bytes, rev, 3, MAX_POSITIVE).unwrap();
    let (s, avg) = pipeline::measure(cal, &parsed[1..], &dark.mean, &e).unwrap();
    (emissive(cal, &s), avg)
}

#[test]
fn spectrum_to_counts_and_back_within_rounding() {
    let radiance = spectrum(|w| 8.0 + 4.0 * (w / 6.0).sin());
    for cal in [calibration_a_to_d(), calibration_e()] {
        for t in [0.5, 2.0] {
            let (back, avg) = round_trip(&cal, &radiance, t);
            assert!(!avg.saturated && !avg.inconsistent);
            for (w, (b, r)) in back.iter().zip(&radiance).enumerate() {
                let bound = rounding_bound(&cal, t, w);
                assert!(
                    (b - r).abs() <= bound,
                    "{:?} t {t} band {w}: {b} vs {r} (±{bound})",
                    cal.model
                );
            }
        }
    }
}

#[test]
fn too_much_light_comes_back_saturated() {
    // 200 W/… in every band needs ~100 000 counts per second per cell: clipped at the top.
    for cal in [calibration_a_to_d(), calibration_e()] {
        let (_, avg) = round_trip(&cal, &[200.0; BANDS], 1.0);
        assert!(avg.saturated, "{:?}", cal.model);
    }
}

#[test]
fn shape_mismatches_are_errors() {
    let cal = calibration_e();
    let dark = pipeline::AbsRaw {
        cells: [0.0; CELLS],
        shielded: 0.0,
    };
    assert!(matches!(
        counts_for(&cal, &exposure(1.0), &[0.0; CELLS], &dark, None, 0),
        Err(PipelineError::Shape { .. })
    ));
    assert!(matches!(
        counts_for(
            &calibration_a_to_d(),
            &exposure(1.0),
            &[0.0; CELLS],
            &dark,
            Some([0; 6]),
            0
        ),
        Err(PipelineError::Shape { .. })
    ));
}

proptest! {
    /// Smooth spectra, as light is at 10 nm: a spectrum that alternates between neighbouring
    /// bands faster than the filter's width needs negative light in some cells, which the
    /// sensor cannot report.
    #[test]
    fn any_smooth_spectrum_round_trips(
        level in 4.0f64..20.0,
        depth in 0.0f64..0.8,
        period in 12.0f64..80.0,
        phase in 0.0f64..6.3,
        t in 0.1f64..3.0,
    ) {
        let radiance = spectrum(|w| level * (1.0 + depth * (std::f64::consts::TAU * w / period + phase).sin()));
        for cal in [calibration_a_to_d(), calibration_e()] {
            let (back, _) = round_trip(&cal, &radiance, t);
            for (w, (b, r)) in back.iter().zip(&radiance).enumerate() {
                prop_assert!((b - r).abs() <= rounding_bound(&cal, t, w), "band {} {} vs {}", w, b, r);
            }
        }
    }
}
