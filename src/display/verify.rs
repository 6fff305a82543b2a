//! Checking a profile against measured patches, typically ones it was not fitted to: the
//! profile's forward prediction of each patch against its measured XYZ, in CIELAB relative
//! to the profile's white ([`ProfileVerification`], `metamer verify`'s result). The
//! characterization's own check of its fitted model on its held-out patches is another
//! job with its own result (`characterize::verify::HeldOutVerification`); both refuse a
//! prediction that is no colour the same way ([`check_prediction`]).

use serde::Serialize;

use super::diagnostics::percentile;
use super::model::Sample;
use super::profile::Profile;
use crate::color::{delta_e2000, delta_e76, Xyz};

/// How many of the worst patches a verification lists.
pub const WORST_SHOWN: usize = 5;

/// Mean, 95th percentile and maximum of a ΔE.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Stats {
    pub mean: f64,
    pub p95: f64,
    pub max: f64,
}

impl Stats {
    fn of(values: &[f64]) -> Stats {
        let mut sorted = values.to_vec();
        sorted.sort_by(f64::total_cmp);
        Stats {
            mean: values.iter().sum::<f64>() / values.len() as f64,
            p95: percentile(&sorted, 0.95),
            max: *sorted.last().expect("verified sets are not empty"),
        }
    }
}

/// One patch's prediction error.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct PatchError {
    /// Index of the patch in the file, from 1.
    pub index: usize,
    pub rgb: [f64; 3],
    pub measured_xyz: Xyz,
    pub predicted_xyz: Xyz,
    pub de00: f64,
    pub de76: f64,
}

/// A profile's prediction errors on a set of patches: what `metamer verify` prints (its
/// `--json` is this, serialized).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ProfileVerification {
    pub patches: usize,
    pub de00: Stats,
    pub de76: Stats,
    /// The [`WORST_SHOWN`] largest ΔE00, largest first.
    pub worst: Vec<PatchError>,
}

/// Why patches cannot be verified.
#[derive(Debug, thiserror::Error)]
pub enum VerifyError {
    #[error("no patches to verify")]
    NoSamples,
    #[error("patch {index} (r,g,b = {rgb:?}) has a drive value outside 0–1 or an XYZ that is not finite")]
    BadSample { index: usize, rgb: [f64; 3] },
    /// The profile's prediction is no colour: a ΔE of it would be NaN or infinite, and a
    /// mean over it NaN while the maximum hides it.
    #[error("the profile predicts X, Y, Z = {predicted:?} for patch {index} (r,g,b = {rgb:?}), which is not a colour a display shows ({why}): is the profile's tone curve or matrix damaged?")]
    BadPrediction {
        index: usize,
        rgb: [f64; 3],
        predicted: [f64; 3],
        why: String,
    },
}

/// Whether a model's prediction `predicted` of patch `index` (from 1, drive `rgb`) is a
/// colour a display shows. A model may predict a little below zero near black: that is an
/// error it makes, which the ΔE shows. Only what is no number, or brighter than any
/// display, is not: its ΔE would be NaN or infinite, and a mean over it NaN while the
/// maximum hides it.
pub fn check_prediction(index: usize, rgb: [f64; 3], predicted: Xyz) -> Result<(), VerifyError> {
    match metamer_color::check_xyz(predicted) {
        Err(
            e @ (metamer_color::Implausible::NotFinite(_)
            | metamer_color::Implausible::TooBright { .. }),
        ) => Err(VerifyError::BadPrediction {
            index,
            rgb,
            predicted: predicted.to_array(),
            why: e.to_string(),
        }),
        _ => Ok(()),
    }
}

/// Predicts every patch with `profile` and compares with what was measured.
pub fn verify_profile(
    profile: &Profile,
    patches: &[Sample],
) -> Result<ProfileVerification, VerifyError> {
    if patches.is_empty() {
        return Err(VerifyError::NoSamples);
    }
    let white = profile.white_xyz;
    let mut errors = Vec::with_capacity(patches.len());
    for (i, p) in patches.iter().enumerate() {
        let ok =
            p.rgb.iter().all(|d| (0.0..=1.0).contains(d)) && p.xyz.iter().all(|v| v.is_finite());
        if !ok {
            return Err(VerifyError::BadSample {
                index: i + 1,
                rgb: p.rgb,
            });
        }
        let predicted = profile.forward(p.rgb);
        check_prediction(i + 1, p.rgb, predicted)?;
        let (a, b) = (predicted.to_lab(white), p.xyz.to_lab(white));
        let (de00, de76) = (delta_e2000(a, b), delta_e76(a, b));
        if !(de00.is_finite() && de76.is_finite()) {
            return Err(VerifyError::BadPrediction {
                index: i + 1,
                rgb: p.rgb,
                predicted: predicted.to_array(),
                why: format!("its ΔE00 is {de00}, its ΔE*ab {de76}"),
            });
        }
        errors.push(PatchError {
            index: i + 1,
            rgb: p.rgb,
            measured_xyz: p.xyz,
            predicted_xyz: predicted,
            de00,
            de76,
        });
    }
    let de00: Vec<f64> = errors.iter().map(|e| e.de00).collect();
    let de76: Vec<f64> = errors.iter().map(|e| e.de76).collect();
    errors.sort_by(|a, b| b.de00.total_cmp(&a.de00));
    errors.truncate(WORST_SHOWN);
    Ok(ProfileVerification {
        patches: patches.len(),
        de00: Stats::of(&de00),
        de76: Stats::of(&de76),
        worst: errors,
    })
}

impl std::fmt::Display for ProfileVerification {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(f, "{} patches", self.patches)?;
        for (name, s) in [("ΔE00 ", &self.de00), ("ΔE*ab", &self.de76)] {
            writeln!(
                f,
                "{name} mean {:.3}  p95 {:.3}  max {:.3}",
                s.mean, s.p95, s.max
            )?;
        }
        write!(f, "worst patches (r,g,b 0–1: ΔE00):")?;
        for e in &self.worst {
            write!(
                f,
                "\n  #{} {:.4},{:.4},{:.4}: {:.3}",
                e.index, e.rgb[0], e.rgb[1], e.rgb[2], e.de00
            )?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Stats of 0, 1, 4 by hand: the mean is 5/3; the p95 lies at rank 0.95·2 = 1.9, so
    /// linearly between the 2nd and 3rd values, 1 + 0.9·3 = 3.7.
    #[test]
    fn stats_follow_a_hand_computation() {
        let s = Stats::of(&[0.0, 1.0, 4.0]);
        assert!((s.mean - 5.0 / 3.0).abs() < 1e-12);
        assert!((s.p95 - 3.7).abs() < 1e-12);
        assert_eq!(s.max, 4.0);
    }
}
