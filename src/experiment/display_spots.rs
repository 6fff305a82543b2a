//! The display-spots stage: each patch's reproduced drive values shown over the whole
//! measured area of the monitor and read with the spot meter, `repeats` times, as a
//! journalled session (resumable after any interruption).
//!
//! The paper shows the whole reproduced image and aims the meter at each patch. A patch
//! region of the image is uniform where the meter's 1° spot falls, so showing that colour
//! full-screen puts the same light in front of the meter; it also spares the operator 24
//! aimings. What it leaves out is the display's dependence on the rest of the picture
//! (power-supply loading, backlight dimming), which the report names as a limit.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use metamer_drivers::MeasureMode;
use serde::{Deserialize, Serialize};

use super::display::{open_meter, open_screen, DisplaySetting};
use super::error::ExperimentError;
use super::progress::Progress;
use super::readings::{write_readings, PatchStat};
use super::reproduction::PatchDrive;
use crate::session::{
    DisplayScreen, InstrumentRecord, Prepare, Rig, RunEnd, RunOptions, ScriptedOperator, Session,
    SessionPlan, Step, StepProgress,
};

/// A display-spot step's own data in the journal.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SpotStep {
    pub patch: usize,
    pub repeat: usize,
}

/// The journal header's caller part.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SpotHeader {
    pub screen: String,
    pub virtual_white_cd_m2: Option<f64>,
}

pub const JOURNAL_FILE: &str = "journal.jsonl";
pub const SPOTS_FILE: &str = "spots.csv";

/// The plan: every patch, `repeats` times, in patch order.
pub fn plan(drives: &[PatchDrive], repeats: usize) -> SessionPlan<SpotStep> {
    let mut steps = Vec::new();
    for d in drives {
        for repeat in 1..=repeats {
            steps.push(Step {
                label: format!("patch {} reading {repeat}", d.patch),
                role: "spot".into(),
                mode: MeasureMode::Emissive,
                prepare: Prepare::Show { rgb: d.rgb8 },
                settle: std::time::Duration::ZERO,
                data: SpotStep {
                    patch: d.patch,
                    repeat,
                },
            });
        }
    }
    let mut options = BTreeMap::new();
    options.insert("repeats".to_string(), repeats.to_string());
    SessionPlan {
        kind: "display-spots".into(),
        options,
        steps,
    }
}

/// What the display-spots session reads, and how.
pub struct SpotSession<'a> {
    pub setting: &'a DisplaySetting,
    /// The spot meter as named by the user.
    pub spot_spec: &'a str,
    pub drives: &'a [PatchDrive],
    pub repeats: usize,
    pub resume: bool,
    pub run: &'a RunOptions,
}

/// Shows and reads every patch into `dir`.
// Eight plain inputs of one stage; bundling them would only move the list into a struct.
#[allow(clippy::too_many_arguments)]
pub fn measure(
    dir: &Path,
    s: &SpotSession<'_>,
    progress: &dyn Fn(Progress),
) -> Result<(Vec<PatchStat>, Vec<&'static str>), ExperimentError> {
    let SpotSession {
        setting,
        spot_spec,
        drives,
        repeats,
        resume,
        run,
    } = *s;
    let mut screen = open_screen(&setting.screen, setting.virtual_white_cd_m2)?;
    let mut meter = open_meter(spot_spec, screen.as_ref())?;
    // A real monitor takes a moment to settle after a change; a simulated one does not.
    let settle = if setting.virtual_white_cd_m2.is_some() {
        std::time::Duration::ZERO
    } else {
        screen.default_settle()
    };
    let mut plan = plan(drives, repeats.max(1));
    plan.steps.iter_mut().for_each(|s| s.settle = settle);
    let mut instruments = BTreeMap::new();
    instruments.insert("spot".to_string(), InstrumentRecord::of(meter.as_ref()));
    let journal: PathBuf = dir.join(JOURNAL_FILE);
    let mut session = Session::open(
        &journal,
        plan,
        SpotHeader {
            screen: setting.screen.clone(),
            virtual_white_cd_m2: setting.virtual_white_cd_m2,
        },
        instruments,
        resume,
    )?;
    let mut operator = ScriptedOperator::confirming();
    let mut shown = DisplayScreen(screen.as_mut());
    let mut rig = Rig {
        screen: Some(&mut shown),
        instruments: vec![("spot".to_string(), meter.as_mut())],
        operator: &mut operator,
    };
    let mut sink = |p: &StepProgress<'_>| {
        progress(Progress::Readings {
            done: p.done,
            total: p.total,
        })
    };
    let end = session.run(&mut rig, run, &mut sink)?;
    if end != RunEnd::Complete {
        return Err(ExperimentError::Incomplete {
            stage: "display-spots",
            done: session.done(),
            total: session.plan().steps.len(),
            journal,
        });
    }
    let entries = session.complete_entries().unwrap_or_default();
    let readings: Vec<(usize, &metamer_drivers::Reading)> =
        entries.iter().map(|e| (e.data.patch, &e.reading)).collect();
    let stats = PatchStat::group(&readings);
    write_readings(&dir.join(SPOTS_FILE), &stats)?;
    Ok((stats, vec![JOURNAL_FILE, SPOTS_FILE]))
}
