//! Spectra to tristimulus values.
//!
//! Emission: paper Eq. 8, X = K_m ∫ L(λ) x̄(λ) dλ with K_m = 683 lm/W, summed at 1 nm steps
//! (rectangle rule on the 1 nm grid of the CIE tables, the summation of CIE 15:2018 §7.1), so
//! a radiance in W·sr⁻¹·m⁻²·nm⁻¹ gives XYZ in cd/m².
//! Objects: X = k Σ S(λ) R(λ) x̄(λ) Δλ with k = 100 / Σ S(λ) ȳ(λ) Δλ (CIE 15:2018 §7.1, Eq. 7.2),
//! so the perfect diffuser has Y = 100.
//!
//! Which wavelengths are summed depends on what the spectrum is ([`summation_range`]):
//! - a table at 1 nm or one interpolated linearly (the CIE tables, the renderer's spectra,
//!   the validation-box contract): 380–780 nm, the range of paper Eq. 8, with the
//!   spectrum's own values — unchanged whatever the grid;
//! - a measurement coarser than 1 nm, interpolated by Sprague ([`Spectrum::measured`], e.g.
//!   an i1Pro's 36 bands at 10 nm): the CIE's standard method, summation at 1 nm over
//!   360–830 nm (CIE 15:2018 §7; ISO/CIE 11664-3), with the data interpolated to 1 nm as
//!   CIE 167:2005 recommends (Sprague) and held at their end values beyond the measured
//!   range. protocols/color/README.md compares it with ArgyllCMS and colour-science.

use std::ops::RangeInclusive;

use crate::{observer, ObserverKind, Spectrum, Xyz};

/// Maximum luminous efficacy for photopic vision, lm/W (paper Eq. 8).
pub const K_M: f64 = 683.0;
/// Integration range of paper Eq. 8.
pub const START_NM: i32 = 380;
pub const END_NM: i32 = 780;
/// Range of the CIE's standard method (CIE 15:2018 §7), the span of its 1 nm tables.
pub const CIE_START_NM: i32 = 360;
pub const CIE_END_NM: i32 = 830;

/// The whole wavelengths a spectrum is summed over: the CIE's 360–830 nm for a measurement
/// interpolated by Sprague, paper Eq. 8's 380–780 nm for every other spectrum.
pub fn summation_range(spectrum: &Spectrum) -> RangeInclusive<i32> {
    if spectrum.sprague() {
        CIE_START_NM..=CIE_END_NM
    } else {
        START_NM..=END_NM
    }
}

/// Σ f(λ)·cmf(λ) over `range` at 1 nm.
fn integrate(f: impl Fn(f64) -> f64, kind: ObserverKind, range: RangeInclusive<i32>) -> Xyz {
    let o = observer(kind);
    let mut acc = [0.0; 3];
    for nm in range {
        let v = f(nm as f64);
        if v == 0.0 {
            continue;
        }
        let cmf = o.at_nm(nm);
        for k in 0..3 {
            acc[k] += v * cmf[k];
        }
    }
    Xyz::from_array(acc)
}

/// Absolute XYZ (cd/m²) of a spectral radiance in W·sr⁻¹·m⁻²·nm⁻¹ (paper Eq. 8).
pub fn radiance_to_xyz(radiance: &Spectrum, kind: ObserverKind) -> Xyz {
    integrate(|nm| radiance.value_at(nm), kind, summation_range(radiance)).scaled(K_M)
}

/// Luminance (cd/m²) of a spectral radiance.
pub fn luminance(radiance: &Spectrum) -> f64 {
    radiance_to_xyz(radiance, ObserverKind::Cie1931).y
}

/// Relative XYZ of a reflectance lit by an illuminant, Y = 100 for the perfect diffuser
/// (summed over the reflectance's [`summation_range`]).
pub fn reflectance_to_xyz(
    reflectance: &Spectrum,
    illuminant: &Spectrum,
    kind: ObserverKind,
) -> Xyz {
    let range = summation_range(reflectance);
    let norm = integrate(|nm| illuminant.value_at(nm), kind, range.clone()).y;
    integrate(
        |nm| illuminant.value_at(nm) * reflectance.value_at(nm),
        kind,
        range,
    )
    .scaled(100.0 / norm)
}

/// The white point of an illuminant (the perfect diffuser under it), Y = 100, over paper
/// Eq. 8's 380–780 nm.
pub fn illuminant_white(illuminant: &Spectrum, kind: ObserverKind) -> Xyz {
    illuminant_white_over(illuminant, kind, START_NM..=END_NM)
}

/// The white point of an illuminant summed over `range` (for a reflectance's Lab, the range
/// the reflectance is summed over: [`summation_range`]).
pub fn illuminant_white_over(
    illuminant: &Spectrum,
    kind: ObserverKind,
    range: RangeInclusive<i32>,
) -> Xyz {
    let sum = integrate(|nm| illuminant.value_at(nm), kind, range);
    sum.scaled(100.0 / sum.y)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Illuminant;

    #[test]
    fn d65_white_matches_cie_published_white_point() {
        // CIE 15:2018 Table T.3: D65, 2° observer, 1 nm: X = 95.04, Z = 108.88 (5 nm
        // interpolated data land within 0.01 of these).
        let w = illuminant_white(&Illuminant::D65.spectrum(), ObserverKind::Cie1931);
        assert!((w.x - 95.04).abs() < 0.02, "{w:?}");
        assert_eq!(w.y, 100.0);
        assert!((w.z - 108.88).abs() < 0.02, "{w:?}");
        // Illuminant A: 109.85, 100, 35.58 (CIE 15:2018 Table T.3).
        let a = illuminant_white(&Illuminant::A.spectrum(), ObserverKind::Cie1931);
        assert!(
            (a.x - 109.85).abs() < 0.02 && (a.z - 35.58).abs() < 0.02,
            "{a:?}"
        );
        // D65 with the 10° observer: 94.81, 100, 107.32.
        let w10 = illuminant_white(&Illuminant::D65.spectrum(), ObserverKind::Cie1964);
        assert!(
            (w10.x - 94.81).abs() < 0.02 && (w10.z - 107.32).abs() < 0.03,
            "{w10:?}"
        );
    }

    #[test]
    fn monochromatic_555nm_is_683_lm_per_watt() {
        // 1 W·sr⁻¹·m⁻²·nm⁻¹ in a 1 nm line at 555 nm (ȳ = 1): Y = 683 cd/m².
        let line = Spectrum::new(vec![554.0, 555.0, 556.0], vec![0.0, 1.0, 0.0]).unwrap();
        let xyz = radiance_to_xyz(&line, ObserverKind::Cie1931);
        assert!((xyz.y - 683.0).abs() < 1e-9, "{xyz:?}");
        // x̄(555) = 0.5121, z̄(555) = 0.005749999 (CIE 1931 table).
        assert!((xyz.x / 683.0 - 0.512050).abs() < 1e-3, "{xyz:?}");
    }

    /// What an i1Pro reads off a ColorChecker patch lit by the `ips-lcd` display white: the
    /// white's 1 nm radiance times the BabelColor reflectance at 380, 390, …, 730 nm (both
    /// tables' own samples, no interpolation), as a measured 10 nm spectrum.
    fn i1pro_reading(patch: Option<usize>) -> Spectrum {
        let white = crate::SpectralTable::parse(
            include_str!("../../../data/display_white_ips_lcd.csv"),
            "data/display_white_ips_lcd.csv",
        )
        .unwrap()
        .first();
        let cc = crate::colorchecker(crate::ColorCheckerSet::BabelColorAverage);
        let values = (0..36)
            .map(|i| {
                let nm = 380.0 + 10.0 * i as f64;
                white.value_at(nm) * patch.map_or(1.0, |p| cc[p].value_at(nm))
            })
            .collect();
        Spectrum::measured(380.0, 10.0, values).unwrap()
    }

    #[test]
    fn a_10nm_reading_integrates_as_colour_science_does() {
        // colour-science 0.4.7: `colour.sd_to_XYZ(sd, cmfs, colour.sd_ones(cmfs.shape),
        // k=683, method="Integration")` × 100 on the same 36 samples, CIE 1931 2° (which
        // aligns the data to the CMFs' 360–830 nm at 1 nm: Sprague interpolation,
        // constant extrapolation). Printed by protocols/color/reference/sampled_xyz.py.
        let cases = [
            (
                None,
                [
                    190.203_348_864_693_23,
                    199.999_957_762_433_9,
                    223.418_284_255_467_63,
                ],
            ),
            (
                Some(12),
                [
                    17.815_135_994_453_716,
                    11.142_920_780_062_05,
                    64.327_536_341_559_82,
                ],
            ),
            (
                Some(14),
                [
                    40.143_482_662_556_04,
                    23.663_426_324_471_985,
                    10.411_157_770_599_122,
                ],
            ),
            (
                Some(18),
                [
                    172.924_506_605_701_57,
                    182.524_758_473_718_26,
                    197.792_869_369_667_47,
                ],
            ),
        ];
        for (patch, want) in cases {
            let got = radiance_to_xyz(&i1pro_reading(patch), ObserverKind::Cie1931).to_array();
            for k in 0..3 {
                assert!(
                    ((got[k] - want[k]) / want[k]).abs() < 1e-9,
                    "{patch:?}: {got:?} vs {want:?}"
                );
            }
        }
    }

    #[test]
    fn a_10nm_reading_agrees_with_argyll_and_differs_from_linear_interpolation() {
        // ArgyllCMS 2.3.1 `spec2cie` on the same spectra in an emissive .sp file (printed
        // to 6 digits in units of 1000 cd/m²): display white and patch 15 (red).
        let argyll = [
            (None, [190.204, 199.992, 223.414]),
            (Some(14), [40.1487, 23.6651, 10.411]),
        ];
        for (patch, want) in argyll {
            let got = radiance_to_xyz(&i1pro_reading(patch), ObserverKind::Cie1931).to_array();
            for k in 0..3 {
                assert!(
                    ((got[k] - want[k]) / want[k]).abs() < 2.5e-4,
                    "{got:?} vs {want:?}"
                );
            }
        }
        // The same samples read linearly and zero beyond 730 nm (what metamer did before)
        // lose 0.8 % of the white's Z: the blue LED's narrow peak falls between bands.
        let sprague = radiance_to_xyz(&i1pro_reading(None), ObserverKind::Cie1931);
        let s = i1pro_reading(None);
        let linear = Spectrum::from_grid(380.0, 10.0, s.values().to_vec()).unwrap();
        let lin = radiance_to_xyz(&linear, ObserverKind::Cie1931);
        assert!(
            (lin.z / sprague.z - 1.0 + 0.008_06).abs() < 1e-4,
            "{lin:?} {sprague:?}"
        );
        assert!(
            (lin.x / sprague.x - 1.0 + 0.002_05).abs() < 1e-4,
            "{lin:?} {sprague:?}"
        );
    }

    #[test]
    fn the_1nm_path_is_unchanged_by_the_measured_method() {
        // A spectrum at 1 nm is summed at its own samples, over 380–780 nm, whatever it
        // is marked as (as_measured leaves it alone).
        let line = Spectrum::new(vec![554.0, 555.0, 556.0], vec![0.0, 1.0, 0.0]).unwrap();
        assert_eq!(line.clone().as_measured(), line);
        let fine = Spectrum::constant(380.0, 780.0, 0.01);
        assert_eq!(fine.clone().as_measured(), fine);
        assert_eq!(summation_range(&fine), START_NM..=END_NM);
        assert_eq!(
            summation_range(&i1pro_reading(None)),
            CIE_START_NM..=CIE_END_NM
        );
    }
}
