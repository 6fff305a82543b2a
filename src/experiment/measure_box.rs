//! The box stage: the `measure-box` session into the experiment's `box/` directory, on the
//! simulated truth box when both instruments are simulated, on the real box otherwise; its
//! measured scene and spot readings are what the later stages read.

use std::path::{Path, PathBuf};

use metamer_drivers::Spec;
use serde::Serialize;

use super::error::ExperimentError;
use super::progress::Progress;
use super::readings::{write_readings, PatchReading};
use crate::measure_box::setup::{self, BoxRig, RigError, RigRequest};
use crate::measure_box::{self, BoxDetails, Instruments, Options, Outcome};
use crate::output::OutputPolicy;
use crate::rig::Scenario;
use crate::session::repeats::Repeatability;
use crate::session::{Operator, RunOptions, StepProgress, TerminalOperator, Unattended};

/// How the box is measured.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MeasureBox {
    /// The spectral instrument (tiles, materials) and the spot meter (fall-off, spots).
    pub spectral: Spec,
    pub spot: Spec,
    /// A plan file; None: the paper's plan.
    pub plan: Option<PathBuf>,
    pub repeats: Option<usize>,
    /// The simulated box's seed (and its instruments').
    pub seed: u64,
    /// The simulated box's light (None: the default). A real box has its own light, so it
    /// is refused with real instruments; left out of the stage's hash when None, so a real
    /// rig's box stage stays valid.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub light: Option<Scenario>,
}

pub const SCENE_FILE: &str = "scene.json";
pub const SPOTS_FILE: &str = "spots.csv";

fn bad(message: impl std::fmt::Display) -> ExperimentError {
    ExperimentError::Box(message.to_string())
}

/// Measures the box into `dir`; returns the files the later stages read.
pub fn measure(
    dir: &Path,
    m: &MeasureBox,
    resume: bool,
    unattended: bool,
    run: &RunOptions,
    progress: &dyn Fn(Progress),
) -> Result<Vec<String>, ExperimentError> {
    let plan = setup::load_plan(m.plan.as_deref(), m.repeats).map_err(bad)?;
    let request = RigRequest {
        plan: &plan,
        spectral: &m.spectral,
        spot: &m.spot,
        seed: m.seed,
        light: m.light,
    };
    // `--unattended` at a terminal: nobody is there to press Enter.
    let operator = || -> Box<dyn Operator> {
        if unattended {
            Box::new(Unattended)
        } else {
            Box::new(TerminalOperator)
        }
    };
    let BoxRig {
        mut spectral,
        mut spot,
        mut operator,
        rig_options,
        ..
    } = setup::open(&request, operator, &|n| progress(Progress::Note(n))).map_err(|e| match e {
        RigError::Open(e) => ExperimentError::from(e),
        e => bad(e),
    })?;
    let spot_model = spot.info().model;
    let mut output = OutputPolicy::new(true);
    if let Some(p) = &m.plan {
        output.input(p);
    }
    let options = Options {
        output,
        dir: dir.to_path_buf(),
        plan,
        stage: None,
        resume,
        rig_options,
        details: BoxDetails {
            spectral: m.spectral.to_string(),
            spot: m.spot.to_string(),
        },
        run: run.clone(),
    };
    let mut sink = |p: &StepProgress<'_>| {
        progress(Progress::Readings {
            done: p.done,
            total: p.total,
        })
    };
    let outcome = measure_box::run(
        &options,
        Instruments {
            spectral: spectral.as_mut(),
            spot: spot.as_mut(),
        },
        operator.as_mut(),
        &mut sink,
    )
    .map_err(bad)?;
    let summary = match outcome {
        Outcome::Finished(summary) => summary,
        Outcome::Incomplete {
            done, total, log, ..
        } => {
            return Err(ExperimentError::Incomplete {
                stage: "box",
                done,
                total,
                journal: log,
            })
        }
        Outcome::StagesMissing(stages) => {
            let names: Vec<&str> = stages.iter().map(|s| s.name()).collect();
            return Err(bad(format!("stage(s) {} not measured", names.join(", "))));
        }
    };
    // Each spot's scatter in X, Y and Z together, over the repeats the reduction kept;
    // a spot read once carries the meter's stated repeatability. The meter's model is the
    // one it reports, not a guess from its spec: `replay:box-spots.jsonl` names none.
    let stated = Repeatability::emissive_of(&spot_model);
    let stats: Vec<(usize, PatchReading)> = summary
        .spot_xyz
        .iter()
        .zip(summary.spots.iter())
        .map(|((patch, xyz), r)| {
            let n = r.stats.n - r.stats.outliers.len();
            let cov = match (n, stated.and_then(|s| s.covariance(*xyz))) {
                (1, Some(c)) => c,
                _ => r.stats.cov,
            };
            (*patch, PatchReading::stated(*xyz, cov, n, 0.0))
        })
        .collect();
    write_readings(&dir.join(SPOTS_FILE), &stats)?;
    Ok(["scene.json", "light.json", "summary.json", SPOTS_FILE]
        .into_iter()
        .map(String::from)
        .collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A replayed CS-100A whose file name says nothing of the model: the spec names no
    /// meter, the opened instrument does, and its stated repeatability is the CS-100A's.
    #[test]
    fn a_replayed_meter_is_known_by_the_model_it_reports() {
        let dir = std::env::temp_dir().join(format!("metamer-box-stage-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("spot.jsonl");
        let transcript = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/protocols/cs100a/transcripts/normal_session.jsonl"
        );
        std::fs::copy(transcript, &file).unwrap();
        let spec = Spec::replay(&file);
        assert!(Repeatability::emissive_of(spec.as_str()).is_none());
        let meter = spec.open(None).unwrap();
        let stated = Repeatability::emissive_of(&meter.info().model).unwrap();
        let cs100a = Repeatability::stated("cs100a", metamer_drivers::MeasureMode::Emissive);
        assert_eq!(stated, cs100a);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
