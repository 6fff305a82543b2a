//! Checking a model against measured patches it was not fitted to: its forward prediction
//! of each patch against the measured XYZ, in CIELAB relative to a white
//! ([`Verification`]). `metamer verify` checks a profile against a measurement file
//! ([`verify_profile`], relative to the profile's white); a characterization checks the
//! model it fitted on the patches it held out (`characterize::verify::verify_held_out`,
//! relative to the white it measured). Both go through [`verify`], which refuses a patch or
//! a prediction that is no colour.

use serde::{Serialize, Serializer};

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
    /// Of a set that is not empty; the mean sums the values smallest first.
    fn of(values: &[f64]) -> Stats {
        let mut sorted = values.to_vec();
        sorted.sort_by(f64::total_cmp);
        Stats {
            mean: sorted.iter().sum::<f64>() / sorted.len() as f64,
            p95: percentile(&sorted, 0.95),
            max: *sorted.last().expect("verified sets are not empty"),
        }
    }
}

/// One patch's prediction: measured, predicted and their differences in CIELAB.
#[derive(Clone, Debug, PartialEq)]
pub struct VerifiedPatch {
    /// The patch's number from 1: its place in the measurement file, or in the
    /// characterization's plan.
    pub index: usize,
    /// The plan's name of the patch; a measurement file's patches have none.
    pub label: Option<String>,
    /// Drive values 0–1.
    pub rgb: [f64; 3],
    pub measured_xyz: Xyz,
    pub predicted_xyz: Xyz,
    /// CIEDE2000 between measured and predicted.
    pub de00: f64,
    /// CIE 1976 ΔE*ab between measured and predicted.
    pub de76: f64,
}

/// A model's prediction errors on a set of patches, in CIELAB relative to a white: what
/// `metamer verify` prints for a profile against a measurement file, and the
/// characterization's own check of its fitted model on the patches it held out of the fit
/// (the summary's `verification`). Both are made by [`verify`], which refuses a patch or a
/// prediction that is no colour. It serializes as `metamer verify --json` writes it; the
/// characterization's summary writes it with [`serialize_held_out`].
#[derive(Clone, Debug, PartialEq)]
pub struct Verification {
    /// The white CIELAB is taken relative to, cd/m²: the profile's, or the measured one.
    pub white_xyz: Xyz,
    /// Every patch verified, in the order given.
    pub patches: Vec<VerifiedPatch>,
    pub de00: Stats,
    pub de76: Stats,
}

impl VerifiedPatch {
    /// The drives as the nearest 8-bit codes: exact for a characterization's patches,
    /// whose drives are codes over 255.
    pub fn rgb8(&self) -> [u8; 3] {
        self.rgb.map(|c| (c * 255.0).round() as u8)
    }
}

impl Verification {
    /// The [`WORST_SHOWN`] patches of largest ΔE00, largest first.
    pub fn worst(&self) -> Vec<&VerifiedPatch> {
        let mut worst: Vec<&VerifiedPatch> = self.patches.iter().collect();
        worst.sort_by(|a, b| b.de00.total_cmp(&a.de00));
        worst.truncate(WORST_SHOWN);
        worst
    }
}

/// `metamer verify --json`: the patch count, the statistics and the worst patches.
impl Serialize for Verification {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        #[derive(Serialize)]
        struct Worst {
            index: usize,
            rgb: [f64; 3],
            measured_xyz: Xyz,
            predicted_xyz: Xyz,
            de00: f64,
            de76: f64,
        }
        #[derive(Serialize)]
        struct Form<'a> {
            patches: usize,
            de00: &'a Stats,
            de76: &'a Stats,
            worst: Vec<Worst>,
        }
        Form {
            patches: self.patches.len(),
            de00: &self.de00,
            de76: &self.de76,
            worst: self
                .worst()
                .into_iter()
                .map(|p| Worst {
                    index: p.index,
                    rgb: p.rgb,
                    measured_xyz: p.measured_xyz,
                    predicted_xyz: p.predicted_xyz,
                    de00: p.de00,
                    de76: p.de76,
                })
                .collect(),
        }
        .serialize(s)
    }
}

/// The characterization summary's `verification`: the white, every patch by label and
/// 8-bit drive with its ΔE00, and the ΔE00 statistics (`serialize_with` of its field).
pub fn serialize_held_out<S: Serializer>(v: &Verification, s: S) -> Result<S::Ok, S::Error> {
    #[derive(Serialize)]
    struct Patch<'a> {
        label: &'a str,
        rgb8: [u8; 3],
        measured_xyz: Xyz,
        predicted_xyz: Xyz,
        delta_e00: f64,
    }
    #[derive(Serialize)]
    struct Form<'a> {
        white_xyz: Xyz,
        patches: Vec<Patch<'a>>,
        mean: f64,
        p95: f64,
        max: f64,
    }
    Form {
        white_xyz: v.white_xyz,
        patches: v
            .patches
            .iter()
            .map(|p| Patch {
                label: p.label.as_deref().unwrap_or_default(),
                rgb8: p.rgb8(),
                measured_xyz: p.measured_xyz,
                predicted_xyz: p.predicted_xyz,
                delta_e00: p.de00,
            })
            .collect(),
        mean: v.de00.mean,
        p95: v.de00.p95,
        max: v.de00.max,
    }
    .serialize(s)
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

/// Predicts every patch with `profile` and compares with what was measured, relative to the
/// profile's white; the patches are numbered in their order from 1.
pub fn verify_profile(profile: &Profile, patches: &[Sample]) -> Result<Verification, VerifyError> {
    let numbered = patches.iter().enumerate().map(|(i, p)| (i + 1, None, *p));
    verify(numbered, profile.white_xyz, &|rgb| profile.forward(rgb))
}

/// Predicts each patch (its number from 1, its label if it has one, and its sample) with
/// `predict`, the model's forward direction (drive 0–1 → XYZ), and compares with what was
/// measured in CIELAB relative to `white_xyz`. A patch that is no measurement (a drive
/// outside 0–1, an XYZ that is not finite) or a prediction that is no colour is an error
/// naming the patch: its ΔE would be NaN or infinite, and a mean over it NaN while the
/// maximum hides it.
pub fn verify(
    patches: impl IntoIterator<Item = (usize, Option<String>, Sample)>,
    white_xyz: Xyz,
    predict: &dyn Fn([f64; 3]) -> Xyz,
) -> Result<Verification, VerifyError> {
    let white = white_xyz;
    let mut verified = Vec::new();
    for (index, label, p) in patches {
        let ok =
            p.rgb.iter().all(|d| (0.0..=1.0).contains(d)) && p.xyz.iter().all(|v| v.is_finite());
        if !ok {
            return Err(VerifyError::BadSample { index, rgb: p.rgb });
        }
        let predicted = predict(p.rgb);
        check_prediction(index, p.rgb, predicted)?;
        let (measured_lab, predicted_lab) = (p.xyz.to_lab(white), predicted.to_lab(white));
        let de00 = delta_e2000(measured_lab, predicted_lab);
        let de76 = delta_e76(measured_lab, predicted_lab);
        if !(de00.is_finite() && de76.is_finite()) {
            return Err(VerifyError::BadPrediction {
                index,
                rgb: p.rgb,
                predicted: predicted.to_array(),
                why: format!("its ΔE00 is {de00}, its ΔE*ab {de76}"),
            });
        }
        verified.push(VerifiedPatch {
            index,
            label,
            rgb: p.rgb,
            measured_xyz: p.xyz,
            predicted_xyz: predicted,
            de00,
            de76,
        });
    }
    if verified.is_empty() {
        return Err(VerifyError::NoSamples);
    }
    let de00: Vec<f64> = verified.iter().map(|e| e.de00).collect();
    let de76: Vec<f64> = verified.iter().map(|e| e.de76).collect();
    Ok(Verification {
        white_xyz,
        de00: Stats::of(&de00),
        de76: Stats::of(&de76),
        patches: verified,
    })
}

impl std::fmt::Display for Verification {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(f, "{} patches", self.patches.len())?;
        for (name, s) in [("ΔE00 ", &self.de00), ("ΔE*ab", &self.de76)] {
            writeln!(
                f,
                "{name} mean {:.3}  p95 {:.3}  max {:.3}",
                s.mean, s.p95, s.max
            )?;
        }
        write!(f, "worst patches (r,g,b 0–1: ΔE00):")?;
        for e in self.worst() {
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
