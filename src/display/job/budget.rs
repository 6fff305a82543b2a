//! `metamer budget` as one call: display models' reproduction error against the number of
//! measured patches on the simulated monitors, written as `budget.csv` and one chart per
//! monitor. Options that cannot work and outputs that may not be written are refused
//! before minutes of fitting.

use std::path::PathBuf;

use crate::display::budget::RAMP_STEPS;
use crate::display::budget::{run_budget_study, write_budget, BudgetError, BudgetPoint};
use crate::display::ModelKind;
use crate::output::{OutputError, OutputPolicy};
use crate::rig::Preset;

/// The study to run.
#[derive(Clone, Debug)]
pub struct Request {
    /// Output directory: `budget.csv` and `budget-PRESET.svg` per monitor.
    pub out: PathBuf,
    /// Simulated monitors by preset name; empty: all.
    pub displays: Vec<String>,
    /// Models by name; empty: all.
    pub models: Vec<String>,
    /// Fresh sets of readings per budget (the errors are pooled over them).
    pub trials: usize,
    /// Seed of the meter noise and of the verification colours.
    pub seed: u64,
    /// Replace `budget.csv` and the charts if they exist.
    pub force: bool,
}

/// A study was refused or failed.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    #[error("at least one trial is needed: each trial is one fresh set of readings")]
    NoTrials,
    #[error("{}: is a file, but the study writes budget.csv and one chart per display into a directory", .0.display())]
    OutIsFile(PathBuf),
    /// A monitor or model name that names none (the message lists the known ones).
    #[error("{0}")]
    UnknownName(String),
    /// Not transparent: the caller finds the output error in the chain (to offer --force).
    #[error("{0}")]
    Output(#[from] OutputError),
    #[error(transparent)]
    Study(#[from] BudgetError),
}

/// Runs the study and writes its table and charts; `progress` gets (fits done, fits in
/// all) from (0, all) on.
///
/// # Examples
///
/// PLCC on the ideal CRT, one trial per budget:
///
/// ```
/// use metamer::display::job::budget::{run, Request};
///
/// let out = std::env::temp_dir().join(format!("metamer-doc-budget-{}", std::process::id()));
/// let request = Request {
///     out: out.clone(),
///     displays: vec!["ideal-crt".into()],
///     models: vec!["plcc".into()],
///     trials: 1,
///     seed: 1,
///     force: true,
/// };
/// let points = run(&request, &|_, _| {})?;
/// assert!(points.iter().all(|p| p.preset == "ideal-crt" && p.mean_de00.is_finite()));
/// assert!(out.join("budget.csv").is_file());
/// # std::fs::remove_dir_all(&out)?;
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn run(request: &Request, progress: &dyn Fn(usize, usize)) -> Result<Vec<BudgetPoint>, Error> {
    let r = request;
    if r.trials == 0 {
        return Err(Error::NoTrials);
    }
    if r.out.exists() && !r.out.is_dir() {
        return Err(Error::OutIsFile(r.out.clone()));
    }
    let presets: Vec<Preset> = parse_or_all(&r.displays, &Preset::ALL)?;
    let models: Vec<ModelKind> = parse_or_all(&r.models, &ModelKind::ALL)?;
    let out = OutputPolicy::new(r.force);
    out.dir(&r.out)?;
    out.check(&r.out.join("budget.csv"))?;
    for p in &presets {
        out.check(&r.out.join(format!("budget-{}.svg", p.name())))?;
    }
    progress(0, presets.len() * models.len() * RAMP_STEPS.len());
    let points = run_budget_study(&presets, &models, r.trials, r.seed, progress)?;
    write_budget(&r.out, &points, &out)?;
    Ok(points)
}

/// Every name parsed, or `all` when there are none.
fn parse_or_all<T: Copy + std::str::FromStr<Err = String>>(
    names: &[String],
    all: &[T],
) -> Result<Vec<T>, Error> {
    if names.is_empty() {
        return Ok(all.to_vec());
    }
    names
        .iter()
        .map(|s| s.parse())
        .collect::<Result<_, String>>()
        .map_err(Error::UnknownName)
}
