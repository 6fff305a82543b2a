//! The end of a characterization: average repeats, fit the chosen model on the fit patches,
//! verify it on the held-out patches, and write the profile, the raw readings as CGATS
//! `.ti3` (ArgyllCMS reads it too), the SVG report and a JSON summary next to the log.

use std::path::{Path, PathBuf};

use metamer_drivers::{InstrumentInfo, Reading};
use serde::Serialize;

use super::adaptive::report::AdaptiveReport;
use super::plan::{DriveStep, Purpose};
use super::report::{write_report, Report, ReportError};
use super::verify::{average, usable, verify_held_out};
use crate::color::Xyz;
use crate::display::model::{FitError, Sample};
use crate::display::verify::Verification;
use crate::display::{fit_profile, write_ti3, ModelKind, ProfileError, Residuals};
use crate::output::{OutputError, OutputPolicy};
use crate::session::CostReport;

pub const PROFILE_FILE: &str = "profile.json";
pub const TI3_FILE: &str = "readings.ti3";
pub const REPORT_FILE: &str = "report.svg";
pub const SUMMARY_FILE: &str = "summary.json";

/// Finishing failed; the journal is untouched, so fixing the cause and resuming the session
/// finishes without measuring anything.
#[derive(Debug, thiserror::Error)]
pub enum FinishError {
    #[error("no usable reading of {}: every one was out of the instrument's range", .0.join(", "))]
    Unusable(Vec<String>),
    #[error("no white patch was measured: CIELAB needs the display white")]
    NoWhite,
    #[error("fitting {model}: {source}")]
    Fit { model: ModelKind, source: FitError },
    #[error("the plan has no verification patches")]
    NoVerification,
    /// The fitted model predicts a verification patch as no colour.
    #[error(transparent)]
    Verify(#[from] crate::display::verify::VerifyError),
    #[error(transparent)]
    Profile(#[from] ProfileError),
    #[error("writing {}: {source}", path.display())]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error(transparent)]
    Report(#[from] ReportError),
    #[error("{0}")]
    Output(#[from] OutputError),
}

/// Who measured what, for the files' descriptions.
pub struct MeasuredBy<'a> {
    pub display: &'a str,
    pub display_description: &'a str,
    pub instrument: &'a str,
    pub instrument_info: &'a InstrumentInfo,
    /// The measurement's budget and what it took.
    pub cost: &'a CostReport,
}

/// What a finished characterization found; also written as `summary.json`.
#[derive(Clone, Debug, Serialize)]
pub struct Summary {
    pub display: String,
    pub display_description: String,
    pub instrument: String,
    pub instrument_info: InstrumentInfo,
    pub model: ModelKind,
    pub verdict: String,
    /// PLCC assumptions the fit patches contradict, one sentence each.
    pub failures: Vec<String>,
    pub readings: usize,
    pub fit_patches: usize,
    pub white_xyz: Xyz,
    pub black_xyz: Xyz,
    /// The model against the patches it was fitted to.
    pub fit_residuals: Residuals,
    /// The model against the held-out patches (ΔE00 relative to the measured white).
    #[serde(serialize_with = "crate::display::verify::serialize_held_out")]
    pub verification: Verification,
    /// How the adaptive plan chose its patches; absent for the fixed plan.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub adaptive: Option<AdaptiveReport>,
    pub files: Files,
    /// The readings, placements and time estimated before the first reading of this run
    /// and what the run took.
    pub cost: CostReport,
}

/// The files written.
#[derive(Clone, Debug, Serialize)]
pub struct Files {
    pub log: PathBuf,
    pub profile: PathBuf,
    pub ti3: PathBuf,
    pub report: PathBuf,
    pub summary: PathBuf,
}

/// The files a characterization writes into `dir` beside its log at `log`.
pub fn files(dir: &Path, log: &Path) -> Files {
    Files {
        log: log.to_path_buf(),
        profile: dir.join(PROFILE_FILE),
        ti3: dir.join(TI3_FILE),
        report: dir.join(REPORT_FILE),
        summary: dir.join(SUMMARY_FILE),
    }
}

impl Files {
    /// The files written (the log is not: it is the input).
    pub fn outputs(&self) -> [&Path; 4] {
        [&self.profile, &self.ti3, &self.report, &self.summary]
    }
}

/// Fits, verifies and writes everything into `dir` from the complete `readings` of the
/// log at `log`, under the output policy `out`.
pub fn finish(
    dir: &Path,
    log: &Path,
    readings: &[(&DriveStep, &Reading)],
    model: ModelKind,
    who: &MeasuredBy,
    out: &OutputPolicy,
    adaptive: Option<AdaptiveReport>,
) -> Result<Summary, FinishError> {
    let files = files(dir, log);
    // Before the fit: a refusal costs nothing and leaves every file as it was.
    for f in files.outputs() {
        out.check(f)?;
    }
    let averaged = average(readings).map_err(FinishError::Unusable)?;
    let white = averaged
        .iter()
        .find(|p| p.rgb8 == [255; 3])
        .ok_or(FinishError::NoWhite)?
        .xyz;
    let black = averaged
        .iter()
        .find(|p| p.rgb8 == [0; 3])
        .map_or(Xyz::default(), |p| p.xyz);
    // Every usable reading, not the averages: the fit averages repeats itself and needs them
    // to estimate the meter's noise for its verdict.
    let training: Vec<Sample> = readings
        .iter()
        .filter(|(p, r)| p.purpose == Purpose::Fit && usable(r))
        .map(|(p, r)| Sample::from_rgb8(p.rgb, r.xyz))
        .collect();
    let profile = fit_profile(model, &training, Some(log))
        .map_err(|source| FinishError::Fit { model, source })?;
    let forward = |rgb: [f64; 3]| profile.forward(rgb);
    let verification =
        verify_held_out(&averaged, white, &forward)?.ok_or(FinishError::NoVerification)?;

    profile.save(&files.profile, out)?;
    let raw: Vec<Sample> = readings
        .iter()
        .filter(|(_, r)| usable(r))
        .map(|(p, r)| Sample::from_rgb8(p.rgb, r.xyz))
        .collect();
    let description = format!(
        "metamer characterize: {} measured with {} ({})",
        who.display, who.instrument_info.model, who.instrument
    );
    write_ti3(&files.ti3, &raw, &description, out).map_err(|source| FinishError::Io {
        path: files.ti3.clone(),
        source,
    })?;
    let diagnostics = profile.diagnostics();
    write_report(
        &Report {
            title: format!(
                "{} — {} — model {}",
                who.display, who.instrument_info.model, model
            ),
            patches: &averaged,
            forward: Some(&forward),
            verification: Some(&verification),
        },
        &files.report,
        out,
    )?;
    let summary = Summary {
        display: who.display.to_string(),
        display_description: who.display_description.to_string(),
        instrument: who.instrument.to_string(),
        instrument_info: who.instrument_info.clone(),
        model,
        verdict: diagnostics.verdict.clone(),
        failures: diagnostics.failures.clone(),
        readings: readings.len(),
        fit_patches: averaged
            .iter()
            .filter(|p| p.purpose == Purpose::Fit)
            .count(),
        white_xyz: white,
        black_xyz: black,
        fit_residuals: diagnostics.residuals.clone(),
        verification,
        adaptive,
        files: files.clone(),
        cost: who.cost.clone(),
    };
    let text = serde_json::to_string_pretty(&summary).expect("a summary serializes") + "\n";
    out.write(&files.summary, text.as_bytes())?;
    Ok(summary)
}
