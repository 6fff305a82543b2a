//! The comparisons as the experiment's validation stage keeps them for later runs and for
//! `metamer lab`: `comparisons.json` (the three assessments with their intervals and
//! verdicts) and, per comparison, its point estimates as CSV with its ΔE chart.

use std::path::Path;

use serde::{Deserialize, Serialize};

use super::assess::Assessment;
use super::chart::write_delta_e_chart;
use super::compare::Comparison;
use super::error::ValidationError;
use crate::color::Xyz;
use crate::output::OutputPolicy;

/// What the validation found, as `comparisons.json`: each comparison patch by patch with
/// both readings' uncertainty (the mean's covariance in X, Y, Z), ΔE*ab and ΔE00 with
/// their bias-aware 95 % intervals, the verdict on the JND at 95 % confidence (`jnd`:
/// below, above, undecided) and the count by point estimate named as such
/// (`below_jnd_point`), and the mean and max with their intervals.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct ValidationResult {
    /// The file's layout ([`RESULT_VERSION`]).
    pub version: u32,
    /// CIELAB's reference white, cd/m².
    pub white: Xyz,
    pub out_of_gamut_patches: Vec<usize>,
    pub display_vs_box: Assessment,
    pub simulation_vs_box: Assessment,
    pub display_vs_simulation: Assessment,
}

/// The name of the file [`ValidationResult`] is written to.
pub const FILE: &str = "comparisons.json";

/// The layout of [`FILE`]: 2 since it holds intervals and verdicts (1 held point
/// estimates only). Part of the validation stage's inputs, so a stage written in the
/// earlier layout runs again.
pub const RESULT_VERSION: u32 = 2;

/// The point estimates of `assessment`, `STEM.csv`, and its ΔE chart, `STEM.svg`, in
/// `dir`. Returns the two file names.
pub(super) fn write_point_files(
    dir: &Path,
    stem: &str,
    assessment: &Assessment,
    policy: &OutputPolicy,
) -> Result<[String; 2], ValidationError> {
    let csv = format!("{stem}.csv");
    policy.write(
        &dir.join(&csv),
        Comparison::from(assessment).to_csv().as_bytes(),
    )?;
    let svg = format!("{stem}.svg");
    write_delta_e_chart(assessment, &dir.join(&svg), policy)?;
    Ok([csv, svg])
}
