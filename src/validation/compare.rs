//! A comparison's point estimates: per patch both readings' XYZ and CIELAB and their ΔE*ab
//! and ΔE00, with the mean and max over the patches. They are the view of an
//! [`Assessment`] without its intervals, so the one comparison ([`super::assess`]) makes
//! them; [`compare`] is that comparison of two plain lists of XYZ known exactly.

use serde::{Deserialize, Serialize};

use crate::color::Xyz;

use super::assess::{
    check_white, compare_pairs, exact_side, Assessment, PatchPair, Stat, JND_DE76,
};
use super::error::ValidationError;
use super::propagate::Propagation;

/// One patch compared.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PatchComparison {
    /// 1-based ColorChecker patch number.
    pub patch: usize,
    pub name: String,
    pub reference_xyz: Xyz,
    pub test_xyz: Xyz,
    pub reference_lab: [f64; 3],
    pub test_lab: [f64; 3],
    pub de76: f64,
    pub de00: f64,
}

/// A whole comparison with its summary.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Comparison {
    /// What the reference readings are (e.g. "box") and what is tested (e.g. "display").
    pub reference: String,
    pub test: String,
    /// Reference white of CIELAB, cd/m².
    pub white: Xyz,
    pub patches: Vec<PatchComparison>,
    pub mean_de76: f64,
    pub max_de76: f64,
    pub mean_de00: f64,
    pub max_de00: f64,
    /// How many patches' ΔE*ab point estimates are below [`JND_DE76`] (no uncertainty
    /// considered: [`super::assess`] says what holds at 95 % confidence).
    #[serde(alias = "below_jnd")]
    pub below_jnd_point: usize,
}

/// Compares `test` against `reference`, the i-th reading of each as patch i + 1, in CIELAB
/// relative to `white`: the readings are taken as exact, so this is the assessment's point
/// estimates.
pub fn compare(
    reference_name: &str,
    reference: &[Xyz],
    test_name: &str,
    test: &[Xyz],
    white: Xyz,
) -> Result<Comparison, ValidationError> {
    if reference.len() != test.len() {
        return Err(ValidationError::LengthMismatch {
            reference: reference.len(),
            test: test.len(),
        });
    }
    check_white(white)?;
    let pairs = exact_pairs(reference, test, white, &[]);
    // Exact readings have no noise to propagate; the method is never used.
    let a = compare_pairs(reference_name, test_name, pairs, white, Propagation::Linear);
    Ok(Comparison::from(&a))
}

/// The i-th reading of each list as patch i + 1, both taken as exact, the patches in
/// `out_of_gamut` marked as outside the display's gamut.
pub(super) fn exact_pairs(
    reference: &[Xyz],
    test: &[Xyz],
    white: Xyz,
    out_of_gamut: &[usize],
) -> Vec<PatchPair> {
    reference
        .iter()
        .zip(test)
        .enumerate()
        .map(|(i, (r, t))| PatchPair {
            patch: i + 1,
            reference: exact_side(*r, white),
            test: exact_side(*t, white),
            out_of_gamut: out_of_gamut.contains(&(i + 1)),
            sequential: None,
        })
        .collect()
}

impl From<&Assessment> for Comparison {
    /// The point estimates of `a`, its summaries taken over the point values alone (an
    /// empty comparison's are 0).
    fn from(a: &Assessment) -> Comparison {
        let patches: Vec<PatchComparison> = a
            .patches
            .iter()
            .map(|p| PatchComparison {
                patch: p.patch,
                name: p.name.clone(),
                reference_xyz: p.reference.xyz,
                test_xyz: p.test.xyz,
                reference_lab: p.reference.lab,
                test_lab: p.test.lab,
                de76: p.de76,
                de00: p.de00,
            })
            .collect();
        // The assessment's summaries of the point values; over no patches they are not
        // numbers, and a comparison says 0.
        let point = |s: Stat| if patches.is_empty() { 0.0 } else { s.value };
        Comparison {
            reference: a.reference.clone(),
            test: a.test.clone(),
            white: a.white,
            below_jnd_point: a.below_jnd_point,
            mean_de76: point(a.mean_de76),
            max_de76: point(a.max_de76),
            mean_de00: point(a.mean_de00),
            max_de00: point(a.max_de00),
            patches,
        }
    }
}

impl Comparison {
    /// One CSV row per patch: `patch,name,X_ref,…,de76,de00`.
    pub fn to_csv(&self) -> String {
        let mut s = String::from(
            "patch,name,X_ref,Y_ref,Z_ref,X_test,Y_test,Z_test,L_ref,a_ref,b_ref,L_test,a_test,b_test,de76,de00\n",
        );
        for p in &self.patches {
            let nums: Vec<String> = p
                .reference_xyz
                .into_iter()
                .chain(p.test_xyz)
                .chain(p.reference_lab)
                .chain(p.test_lab)
                .chain([p.de76, p.de00])
                .map(|v| format!("{v:.6}"))
                .collect();
            s += &format!("{},{},{}\n", p.patch, p.name, nums.join(","));
        }
        s
    }

    /// The one-line summary a user reads first.
    pub fn summary(&self) -> String {
        format!(
            "{} of {} patches below the JND (ΔE*ab < {JND_DE76}) by point estimate; ΔE*ab mean {:.2} max {:.2}; ΔE00 mean {:.2} max {:.2}",
            self.below_jnd_point,
            self.patches.len(),
            self.mean_de76,
            self.max_de76,
            self.mean_de00,
            self.max_de00
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identical_readings_differ_by_zero_and_scaled_white_by_hand_value() {
        let white = Xyz::new(95.047, 100.0, 108.883);
        let a = vec![Xyz::new(20.0, 21.0, 22.0), Xyz::new(40.0, 42.0, 44.0)];
        let c = compare("box", &a, "display", &a, white).unwrap();
        assert_eq!(c.below_jnd_point, 2);
        assert_eq!(c.max_de76, 0.0);
        // A grey at L* = 50 against one at L* = 51.5 (by hand: ((50+16)/116)^3 = 0.18418652,
        // ((51.5+16)/116)^3 = 0.19703227): neutral, so ΔE*ab = ΔL* = 1.5.
        let g = |y: f64| Xyz::new(white.x * y, white.y * y, white.z * y);
        let c = compare("r", &[g(0.18418652)], "t", &[g(0.19703227)], white).unwrap();
        assert!((c.patches[0].de76 - 1.5).abs() < 1e-4, "{:?}", c.patches[0]);
        assert_eq!(c.below_jnd_point, 1);
        assert!(c
            .summary()
            .starts_with("1 of 1 patches below the JND (ΔE*ab < 2.3) by point estimate"));
    }

    #[test]
    fn mismatched_inputs_are_errors() {
        let w = Xyz::new(95.0, 100.0, 108.0);
        let e = compare("r", &[w], "t", &[], w).unwrap_err();
        assert!(e.to_string().contains("1 reference vs 0 test"));
        let e = compare("r", &[w], "t", &[w], Xyz::default()).unwrap_err();
        assert!(e.to_string().contains("must have positive"));
    }
}
