//! Spectra to tristimulus values.
//!
//! Emission: paper Eq. 8, X = K_m ∫ L(λ) x̄(λ) dλ with K_m = 683 lm/W, integrated from 380 to
//! 780 nm at 1 nm steps (rectangle rule on the 1 nm grid of the CIE tables, the summation of
//! CIE 15:2018 §7.1), so a radiance in W·sr⁻¹·m⁻²·nm⁻¹ gives XYZ in cd/m².
//! Objects: X = k Σ S(λ) R(λ) x̄(λ) Δλ with k = 100 / Σ S(λ) ȳ(λ) Δλ (CIE 15:2018 §7.1, Eq. 7.2),
//! so the perfect diffuser has Y = 100.

use crate::{observer, ObserverKind, Spectrum, Xyz};

/// Maximum luminous efficacy for photopic vision, lm/W (paper Eq. 8).
pub const K_M: f64 = 683.0;
/// Integration range of paper Eq. 8.
pub const START_NM: i32 = 380;
pub const END_NM: i32 = 780;

/// Σ f(λ)·cmf(λ) over 380..=780 nm at 1 nm.
fn integrate(f: impl Fn(f64) -> f64, kind: ObserverKind) -> Xyz {
    let o = observer(kind);
    let mut acc = [0.0; 3];
    for nm in START_NM..=END_NM {
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
    integrate(|nm| radiance.value_at(nm), kind).scaled(K_M)
}

/// Luminance (cd/m²) of a spectral radiance.
pub fn luminance(radiance: &Spectrum) -> f64 {
    radiance_to_xyz(radiance, ObserverKind::Cie1931).y
}

/// Relative XYZ of a reflectance lit by an illuminant, Y = 100 for the perfect diffuser.
pub fn reflectance_to_xyz(
    reflectance: &Spectrum,
    illuminant: &Spectrum,
    kind: ObserverKind,
) -> Xyz {
    let norm = integrate(|nm| illuminant.value_at(nm), kind).y;
    integrate(
        |nm| illuminant.value_at(nm) * reflectance.value_at(nm),
        kind,
    )
    .scaled(100.0 / norm)
}

/// The white point of an illuminant (the perfect diffuser under it), Y = 100.
pub fn illuminant_white(illuminant: &Spectrum, kind: ObserverKind) -> Xyz {
    let norm = integrate(|nm| illuminant.value_at(nm), kind).y;
    integrate(|nm| illuminant.value_at(nm), kind).scaled(100.0 / norm)
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
}
