//! From readings to what the fit and the verification use: repeats averaged per planned
//! patch, and the fitted model's forward prediction of each held-out verification patch
//! compared with its measurement (`display::verify`), CIELAB relative to the measured white
//! (the paper's validation uses the display white as reference white).

use metamer_drivers::{Flag, Reading};
use serde::Serialize;

use super::plan::{DriveStep, Purpose};
use crate::color::Xyz;
use crate::display::model::Sample;
use crate::display::verify::{verify, Verification, VerifyError};

/// A planned patch with its readings averaged.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct AveragedPatch {
    /// [`DriveStep::patch`].
    pub patch: usize,
    pub label: String,
    pub rgb8: [u8; 3],
    pub purpose: Purpose,
    /// Mean XYZ over the usable readings, cd/m².
    pub xyz: Xyz,
    /// Usable readings averaged.
    pub readings: usize,
}

impl AveragedPatch {
    /// As the display models take it: drive 0–1 and XYZ.
    pub fn to_sample(&self) -> Sample {
        Sample::from_rgb8(self.rgb8, self.xyz)
    }
}

/// A reading whose XYZ may be used: finite, and not flagged as beyond the instrument's
/// range (a low-light flag only says the accuracy is lower, the value is still the best
/// there is).
pub fn usable(reading: &Reading) -> bool {
    reading.xyz.iter().all(|v| v.is_finite())
        && !reading.flags.iter().any(|f| {
            matches!(
                f,
                Flag::OverRange | Flag::ChromaticityOverRange | Flag::Saturated
            )
        })
}

/// Averages the usable readings of each distinct patch; patches without any usable
/// reading are listed in the error.
pub fn average(readings: &[(&DriveStep, &Reading)]) -> Result<Vec<AveragedPatch>, Vec<String>> {
    let n = readings.iter().map(|(p, _)| p.patch + 1).max().unwrap_or(0);
    let mut sums: Vec<Option<AveragedPatch>> = vec![None; n];
    for (p, r) in readings {
        let slot = sums[p.patch].get_or_insert_with(|| AveragedPatch {
            patch: p.patch,
            label: p.label.clone(),
            rgb8: p.rgb,
            purpose: p.purpose,
            xyz: Xyz::default(),
            readings: 0,
        });
        if usable(r) {
            slot.xyz = slot.xyz + r.xyz;
            slot.readings += 1;
        }
    }
    let mut out = Vec::new();
    let mut unusable = Vec::new();
    for mut a in sums.into_iter().flatten() {
        if a.readings == 0 {
            unusable.push(format!("{} (RGB {:?})", a.label, a.rgb8));
            continue;
        }
        let k = a.readings as f64;
        a.xyz = a.xyz.map(|v| v / k);
        out.push(a);
    }
    if unusable.is_empty() {
        Ok(out)
    } else {
        Err(unusable)
    }
}

/// The characterization's own check: the model it fitted (`predict`, its forward
/// direction, drive 0–1 → XYZ) against the measured verification patches of `patches`, the
/// ones held out of the fit, relative to the white it measured (the summary's
/// `verification`). None if the plan held none out; an error if the model predicts a
/// patch as no colour (the same check as `metamer verify`'s), which would otherwise make
/// the mean NaN and the summary's statistics `null`.
pub fn verify_held_out(
    patches: &[AveragedPatch],
    white_xyz: Xyz,
    predict: &dyn Fn([f64; 3]) -> Xyz,
) -> Result<Option<Verification>, VerifyError> {
    let held_out: Vec<_> = patches
        .iter()
        .filter(|p| p.purpose == Purpose::Verify)
        .map(|p| (p.patch + 1, Some(p.label.clone()), p.to_sample()))
        .collect();
    if held_out.is_empty() {
        return Ok(None);
    }
    verify(held_out, white_xyz, predict).map(Some)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn planned(patch: usize, rgb: [u8; 3], purpose: Purpose) -> DriveStep {
        DriveStep {
            index: patch,
            patch,
            repeat: 0,
            rgb,
            purpose,
            label: format!("p{patch}"),
        }
    }

    #[test]
    fn repeats_are_averaged_and_out_of_range_readings_left_out() {
        let a = planned(0, [0, 0, 0], Purpose::Fit);
        let b = planned(1, [9, 9, 9], Purpose::Verify);
        let r1 = Reading::from_yxy(1.0, 0.3, 0.3, "t");
        let r2 = Reading::from_yxy(3.0, 0.3, 0.3, "t");
        let mut over = Reading::from_yxy(1e6, 0.3, 0.3, "t");
        over.flags.push(Flag::OverRange);
        let mut low = Reading::from_yxy(0.005, 0.3, 0.3, "t");
        low.flags.push(Flag::LowLight);
        let avg = average(&[(&a, &r1), (&b, &low), (&a, &r2), (&a, &over)]).unwrap();
        assert_eq!(avg.len(), 2);
        assert_eq!(avg[0].readings, 2);
        assert!((avg[0].xyz[1] - 2.0).abs() < 1e-15);
        assert_eq!(avg[1].readings, 1, "low light is still a value");
        assert_eq!(avg[1].to_sample().rgb, [9.0 / 255.0; 3]);
        let e = average(&[(&a, &over)]).unwrap_err();
        assert_eq!(e, vec!["p0 (RGB [0, 0, 0])".to_string()]);
    }

    #[test]
    fn statistics_of_a_known_error() {
        // A prediction that scales XYZ by k leaves a, b at 0 for a neutral patch and moves
        // L* only: ΔE00 of a pure ΔL at L ≈ 50 is ΔL/S_L with S_L = 1 (CIEDE2000, Sharma
        // et al. 2005 Eq. 13: S_L = 1 + 0.015(L̄−50)²/√(20+(L̄−50)²)).
        let white = Xyz::new(95.047, 100.0, 108.883);
        let grey_y = 18.418_651_851_244_416; // L* = 50 exactly: ((50+16)/116)³·100
        let patches: Vec<AveragedPatch> = (0..21)
            .map(|i| AveragedPatch {
                patch: i,
                label: format!("g{i}"),
                rgb8: [i as u8; 3],
                purpose: if i == 0 {
                    Purpose::Fit
                } else {
                    Purpose::Verify
                },
                xyz: white.map(|w| w * grey_y / 100.0),
                readings: 1,
            })
            .collect();
        // Sample i is predicted with lightness off by i/10 (moving Y by the slope of L*).
        let predict = |rgb: [f64; 3]| {
            let i = (rgb[0] * 255.0).round();
            let l = 50.0 + i / 10.0;
            let y = ((l + 16.0) / 116.0).powi(3) * 100.0;
            white.map(|w| w * y / 100.0)
        };
        let v = verify_held_out(&patches, white, &predict).unwrap().unwrap();
        assert_eq!(v.patches.len(), 20);
        for (k, p) in v.patches.iter().enumerate() {
            let dl = (k + 1) as f64 / 10.0;
            let lbar: f64 = 50.0 + dl / 2.0;
            let sl = 1.0 + 0.015 * (lbar - 50.0).powi(2) / (20.0 + (lbar - 50.0).powi(2)).sqrt();
            assert!((p.de00 - dl / sl).abs() < 1e-9, "{:?}: {}", p.label, p.de00);
        }
        assert!((v.de00.max - v.patches[19].de00).abs() < 1e-15);
        // Rank 0.95·19 = 18.05: between the 19th and 20th values.
        let p95 = v.patches[18].de00 + 0.05 * (v.patches[19].de00 - v.patches[18].de00);
        assert!((v.de00.p95 - p95).abs() < 1e-12);
        let mean = v.patches.iter().map(|p| p.de00).sum::<f64>() / 20.0;
        assert!((v.de00.mean - mean).abs() < 1e-12);
        assert!(verify_held_out(&patches[..1], white, &predict)
            .unwrap()
            .is_none());
        // A model that predicts one patch as no colour is an error naming that patch, not
        // a NaN mean.
        let broken = |rgb: [f64; 3]| {
            if (rgb[0] * 255.0).round() == 7.0 {
                Xyz::new(f64::NAN, f64::NAN, f64::NAN)
            } else {
                predict(rgb)
            }
        };
        let e = verify_held_out(&patches, white, &broken)
            .unwrap_err()
            .to_string();
        assert!(e.contains("for patch 8 (r,g,b = "), "{e}");
    }
}
