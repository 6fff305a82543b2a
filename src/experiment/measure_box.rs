//! The box stage: the box measured into the experiment's `box/` directory by the one call
//! `metamer measure-box` makes too ([`crate::measure_box::job::measure`]), on the simulated
//! truth box when both instruments are simulated, on the real box otherwise; its measured
//! scene and spot readings are what the later stages read.

use std::path::{Path, PathBuf};

use metamer_drivers::Spec;
use serde::Serialize;

use super::error::ExperimentError;
use super::progress::Progress;
use crate::measure_box::job::{self, MeasureBoxJobError, MeasureBoxRequest};
use crate::measure_box::setup::RigError;
use crate::measure_box::{BoxPlanError, Outcome};
use crate::rig::Scenario;
use crate::session::{Attendance, RunOptions, StepProgress};
use crate::validation::sequential::RepeatRule;

pub use crate::measure_box::job::SPOTS_FILE;

/// How the box is measured.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MeasureBox {
    /// The spectral instrument (tiles, materials) and the spot meter (fall-off, spots).
    pub spectral: Spec,
    pub spot: Spec,
    /// A plan file; None: the paper's plan.
    pub plan: Option<PathBuf>,
    pub repeats: Option<usize>,
    /// Read the tiles and the fall-off adaptively; left out of the stage's hash when not,
    /// so a fixed plan's box stage stays valid.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub adaptive: bool,
    /// How each spot is read where the plan file names no rule (the measuring plan's),
    /// and the white its CIELAB is relative to where the plan file names none; left out
    /// of the stage's hash when None, so the paper's plan's box stage stays valid.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub spot_rule: Option<RepeatRule>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub spot_white: Option<[f64; 3]>,
    /// The simulated box's seed (and its instruments').
    pub seed: u64,
    /// The simulated box's light (None: the default). A real box has its own light, so it
    /// is refused with real instruments; left out of the stage's hash when None, so a real
    /// rig's box stage stays valid.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub light: Option<Scenario>,
}

pub const SCENE_FILE: &str = "scene.json";

fn bad(message: impl std::fmt::Display) -> ExperimentError {
    ExperimentError::Box(message.to_string())
}

impl MeasureBox {
    /// The box measurement the stage asks for in `dir`: every stage of the plan, into a
    /// directory that is the stage's own, at the terminal unless `unattended` (the
    /// experiment's request refused a real instrument with nobody at the rig before its
    /// first stage), and the spots' readings file the later stages read.
    pub fn request(
        &self,
        dir: &Path,
        resume: bool,
        unattended: bool,
        run: &RunOptions,
    ) -> MeasureBoxRequest {
        MeasureBoxRequest {
            out: dir.to_path_buf(),
            spectral: self.spectral.clone(),
            spot: self.spot.clone(),
            plan: self.plan.clone(),
            repeats: self.repeats,
            adaptive: self.adaptive,
            spot_rule: self.spot_rule.clone(),
            spot_white: self.spot_white,
            resume,
            stage: None,
            seed: self.seed,
            scenario: self.light,
            force: true,
            unattended,
            run: run.clone(),
            attendance: Some(if unattended {
                Attendance::Unattended
            } else {
                Attendance::Terminal
            }),
            spot_readings: true,
        }
    }
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
    let request = m.request(dir, resume, unattended, run);
    let outcome = job::measure(&request, &|n| progress(Progress::Note(n)), &mut |_| {
        Box::new(move |p: &StepProgress<'_>| {
            progress(Progress::Readings {
                done: p.done,
                total: p.total,
            })
        })
    })
    .map_err(stage_error)?;
    match outcome {
        Outcome::Finished(_) => Ok(["scene.json", "light.json", "summary.json", SPOTS_FILE]
            .into_iter()
            .map(String::from)
            .collect()),
        Outcome::Incomplete {
            done, total, log, ..
        } => Err(ExperimentError::Incomplete {
            stage: "box",
            done,
            total,
            journal: log,
        }),
        Outcome::StagesMissing(stages) => {
            let names: Vec<&str> = stages.iter().map(|s| s.name()).collect();
            Err(bad(format!("stage(s) {} not measured", names.join(", "))))
        }
    }
}

/// The measurement's failures in the stage's words: an instrument's and the readings
/// file's as they are, the rest as the box measurements'.
fn stage_error(e: MeasureBoxJobError) -> ExperimentError {
    match e {
        MeasureBoxJobError::Rig(RigError::Open(e)) => e.into(),
        MeasureBoxJobError::SpotReadings(e) => e.into(),
        // Told apart from a bad plan file for the command's `--repeats`; the stage says it
        // as the plan's check does.
        MeasureBoxJobError::Repeats(message) => bad(BoxPlanError::Invalid {
            field: "repeats".into(),
            message,
        }),
        e => bad(e),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The stage asks for every stage of the plan, replaces what its directory holds,
    /// writes the spots' readings and asks at the terminal unless unattended.
    #[test]
    fn the_stage_asks_the_one_measurement_for_its_own_behaviour() {
        let m = MeasureBox {
            spectral: Spec::new("sim:i1pro?time_scale=0"),
            spot: Spec::new("sim:cs100a?time_scale=0"),
            plan: None,
            repeats: Some(1),
            adaptive: false,
            spot_rule: None,
            spot_white: None,
            seed: 3,
            light: Some(Scenario::default()),
        };
        let dir = Path::new("box");
        let r = m.request(dir, false, false, &RunOptions::default());
        assert_eq!(r.stage, None);
        assert!(r.force && r.spot_readings);
        assert_eq!(r.attendance, Some(Attendance::Terminal));
        assert_eq!(r.scenario, Some(Scenario::default()));
        assert_eq!((&r.spectral, r.seed), (&m.spectral, 3));
        let r = m.request(dir, true, true, &RunOptions::default());
        assert_eq!(r.attendance, Some(Attendance::Unattended));
        assert!(r.resume);
    }
}
