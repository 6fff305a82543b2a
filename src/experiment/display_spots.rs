//! The display-spots stage: the reproduced image shown whole on the monitor, as in the
//! paper, and each patch read with the spot meter `repeats` times, the operator guided
//! patch by patch to where the patch lies on the screen (mirrored with the image); a
//! journalled session, resumable after any interruption.
//!
//! A simulated meter aimed at a simulated screen sees the mean emission under its spot, so
//! a wrong mirror or a non-uniform screen shows in its readings. Without an image (none
//! rendered) each patch's drive values are shown over the whole screen instead: a patch
//! region is uniform where the 1° spot falls, so that puts the same light in front of the
//! meter, but leaves out the display's dependence on the rest of the picture (power-supply
//! loading, backlight dimming). `display-spots.json` records which was shown.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use metamer_drivers::{MeasureMode, Spec};
use serde::{Deserialize, Serialize};

use super::display::{open_meter, open_screen, DisplaySetting};
use super::error::ExperimentError;
use super::progress::Progress;
use super::readings::{write_readings, PatchReading};
use super::reproduction::{PatchDrive, PatchRegion};
use crate::image::{Drive8Image, ScreenSpot};
use crate::rig::{MeterAim, Placement};
use crate::session::budget::{srgb_assumption, srgb_luminance, SRGB_WHITE_CD_M2};
use crate::session::{
    Answer, CostReport, InstrumentRecord, Meter, Operator, OperatorError, PlacementReadings,
    Prepare, Recheck, Rig, RunEnd, RunOptions, Screen, ScriptedOperator, Session, SessionPlan,
    Step, StepProgress, TerminalOperator,
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
/// What was shown and where the meter was aimed.
pub const RECORD_FILE: &str = "display-spots.json";

/// Where the operator aims the meter for one patch.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PatchAim {
    pub patch: usize,
    /// The spot on the screen (fractions of its width and height from the top-left).
    pub x: f64,
    pub y: f64,
    pub radius: f64,
    pub prompt: String,
}

/// What `display-spots.json` holds.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SpotRecord {
    /// `image` (the reproduced image, the meter aimed patch by patch) or `patch colours`
    /// (each patch's drive values full-screen).
    pub shown: String,
    /// Why, when it is not the image.
    pub note: Option<String>,
    pub aims: Vec<PatchAim>,
    /// The readings' budget before the first of this run and what the run took.
    #[serde(default)]
    pub cost: Option<CostReport>,
}

/// The operator's request for patch `r` at `spot` on the screen.
pub fn aim_prompt(r: &PatchRegion, spot: ScreenSpot) -> String {
    format!(
        "aim the meter at patch {} (row {}, column {}) — at {:.1} % from the left, {:.1} % \
         from the top of the screen",
        r.patch,
        r.row,
        r.column,
        100.0 * spot.x,
        100.0 * spot.y
    )
}

/// The plan on the whole image: every patch, `repeats` times; the meter is aimed before
/// each patch's first reading and stays there for the rest.
pub fn image_plan(aims: &[PatchAim], repeats: usize) -> SessionPlan<SpotStep> {
    let mut steps = Vec::new();
    for a in aims {
        for repeat in 1..=repeats {
            steps.push(Step {
                label: format!("patch {} reading {repeat}", a.patch),
                role: "spot".into(),
                mode: MeasureMode::Emissive,
                prepare: if repeat == 1 {
                    Prepare::Operator {
                        prompt: a.prompt.clone(),
                    }
                } else {
                    Prepare::None
                },
                settle: std::time::Duration::ZERO,
                data: SpotStep {
                    patch: a.patch,
                    repeat,
                },
            });
        }
    }
    let mut options = BTreeMap::new();
    options.insert("repeats".to_string(), repeats.to_string());
    options.insert("shown".to_string(), "image".to_string());
    SessionPlan {
        kind: "display-spots".into(),
        options,
        steps,
    }
}

/// Passes every request on to the operator; on a simulated screen it also aims the
/// simulated meter where an aiming request says.
struct Aiming<'a> {
    aims: BTreeMap<String, ScreenSpot>,
    meter: Option<MeterAim>,
    inner: &'a mut dyn Operator,
}

impl Operator for Aiming<'_> {
    fn ask(&mut self, prompt: &str) -> Result<Answer, OperatorError> {
        if let (Some(meter), Some(spot)) = (&self.meter, self.aims.get(prompt)) {
            meter.set(Some(*spot));
        }
        self.inner.ask(prompt)
    }

    // The operator's own placement prompt (with its reading count) and re-aim question,
    // not the plain defaults a wrapper would otherwise fall back to.
    fn ask_placement(
        &mut self,
        what: &str,
        readings: PlacementReadings,
    ) -> Result<Answer, OperatorError> {
        if let (Some(meter), Some(spot)) = (&self.meter, self.aims.get(what)) {
            meter.set(Some(*spot));
        }
        self.inner.ask_placement(what, readings)
    }

    fn recheck(&mut self, why: &str) -> Result<Recheck, OperatorError> {
        self.inner.recheck(why)
    }
}

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

/// The light a display spot is budgeted at: its patch's drive values as the screen shows
/// them (a simulated monitor), else on an sRGB display; and what that assumes.
pub fn patch_light<'a>(
    drives: &'a [PatchDrive],
    screen: &'a dyn Screen,
) -> (impl Fn(&Step<SpotStep>) -> f64 + 'a, String) {
    let light = move |step: &Step<SpotStep>| {
        let rgb = drives
            .iter()
            .find(|d| d.patch == step.data.patch)
            .map_or([255; 3], |d| d.rgb8);
        screen
            .expected_cd_m2(rgb)
            .unwrap_or_else(|| srgb_luminance(rgb, SRGB_WHITE_CD_M2))
    };
    let assumption = if screen.expected_cd_m2([255; 3]).is_some() {
        format!(
            "a spot's luminance from its patch's drive values as the simulated {} shows them",
            screen.spec()
        )
    } else {
        srgb_assumption(SRGB_WHITE_CD_M2)
    };
    (light, assumption)
}

/// The reproduced image and each patch's spot on it.
pub struct ShownImage<'a> {
    pub file: &'a Path,
    pub regions: &'a [PatchRegion],
}

/// What the display-spots session reads, and how.
pub struct SpotSession<'a> {
    pub setting: &'a DisplaySetting,
    /// The spot meter as named by the user.
    pub spot_spec: &'a Spec,
    pub drives: &'a [PatchDrive],
    /// None: each patch's colour full-screen.
    pub image: Option<ShownImage<'a>>,
    pub repeats: usize,
    pub resume: bool,
    /// Nobody at the rig: every request counts as done.
    pub unattended: bool,
    pub run: &'a RunOptions,
}

/// Each patch's readings by patch number, and the files written.
pub type Measured = (Vec<(usize, PatchReading)>, Vec<&'static str>);

/// Shows and reads every patch into `dir`.
pub fn measure(
    dir: &Path,
    s: &SpotSession<'_>,
    progress: &dyn Fn(Progress),
) -> Result<Measured, ExperimentError> {
    let SpotSession {
        setting,
        spot_spec,
        drives,
        repeats,
        resume,
        run,
        ..
    } = *s;
    let mut screen = open_screen(&setting.screen, setting.virtual_white_cd_m2)?;
    let mut meter = open_meter(spot_spec, &setting.screen, screen.as_ref())?;
    // A real monitor takes a moment to settle after a change; a simulated one does not.
    let settle = if setting.virtual_white_cd_m2.is_some() {
        std::time::Duration::ZERO
    } else {
        screen.default_settle()
    };
    let (mut plan, mut record) = match &s.image {
        Some(shown) => {
            let image =
                Drive8Image::read_png(shown.file).map_err(|e| ExperimentError::BadFile {
                    file: shown.file.to_path_buf(),
                    message: e.to_string(),
                })?;
            let placement = screen.show_image(&image)?;
            let aims = aims_on(&placement, shown.regions);
            let plan = image_plan(&aims, repeats.max(1));
            let record = SpotRecord {
                shown: "image".into(),
                note: None,
                aims,
                cost: None,
            };
            (plan, record)
        }
        None => {
            let note = "no image was rendered: each patch's drive values were shown over the \
                        whole screen instead of the reproduced image";
            progress(Progress::Note(note.into()));
            let record = SpotRecord {
                shown: "patch colours".into(),
                note: Some(note.into()),
                aims: Vec::new(),
                cost: None,
            };
            (plan(drives, repeats.max(1)), record)
        }
    };
    plan.steps.iter_mut().for_each(|s| s.settle = settle);
    let mut instruments = BTreeMap::new();
    instruments.insert("spot".to_string(), InstrumentRecord::of(meter.as_ref()));
    let journal: PathBuf = dir.join(JOURNAL_FILE);
    let mut session = Session::open(
        &journal,
        plan,
        SpotHeader {
            screen: setting.screen.canonical(),
            virtual_white_cd_m2: setting.virtual_white_cd_m2,
        },
        instruments,
        resume,
    )?;
    let mut scripted = ScriptedOperator::confirming();
    let mut terminal = TerminalOperator;
    let inner: &mut dyn Operator = if s.unattended || setting.virtual_white_cd_m2.is_some() {
        &mut scripted
    } else {
        &mut terminal
    };
    let mut operator = Aiming {
        aims: record
            .aims
            .iter()
            .map(|a| {
                let spot = ScreenSpot {
                    x: a.x,
                    y: a.y,
                    radius: a.radius,
                };
                (a.prompt.clone(), spot)
            })
            .collect(),
        meter: screen.meter_aim(),
        inner,
    };
    // A resumed session may continue mid-patch, after that patch's aiming request.
    let next = session.done();
    if let Some(step) = session.plan().steps.get(next) {
        if step.data.repeat > 1 {
            if let Some(a) = record.aims.iter().find(|a| a.patch == step.data.patch) {
                if operator.ask(&a.prompt)? == Answer::Abort {
                    return Err(ExperimentError::Incomplete {
                        stage: "display-spots",
                        done: next,
                        total: session.plan().steps.len(),
                        journal,
                    });
                }
            }
        }
    }
    let meters = [("spot".to_string(), Meter::of(meter.as_ref()))].into();
    let estimate = {
        let (light, assumption) = patch_light(drives, screen.as_ref());
        session.estimate(&meters, &light, &assumption, run.placement_s())
    };
    let mut rig = Rig {
        screen: s.image.is_none().then_some(screen.as_mut()),
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
    let spent = session.spent().clone();
    record.cost = Some(CostReport {
        estimate,
        actual: Some(spent),
    });
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
    let stats = PatchReading::group(&readings);
    write_readings(&dir.join(SPOTS_FILE), &stats)?;
    let text = serde_json::to_string_pretty(&record).map_err(ExperimentError::Json)?;
    super::cache::write_atomic(&dir.join(RECORD_FILE), text.as_bytes())?;
    Ok((stats, vec![JOURNAL_FILE, SPOTS_FILE, RECORD_FILE]))
}

/// Each patch's aim on the screen, for the image placed at `placement`.
pub fn aims_on(placement: &Placement, regions: &[PatchRegion]) -> Vec<PatchAim> {
    regions
        .iter()
        .map(|r| {
            let spot = placement.on_screen(ScreenSpot {
                x: r.x,
                y: r.y,
                radius: r.radius,
            });
            PatchAim {
                patch: r.patch,
                x: spot.x,
                y: spot.y,
                radius: spot.radius,
                prompt: aim_prompt(r, spot),
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A recheck that stops must reach the session: a wrapper that answered for the
    /// operator would keep a reading the operator wanted gone.
    struct Stopper;
    impl Operator for Stopper {
        fn ask(&mut self, _: &str) -> Result<Answer, OperatorError> {
            Ok(Answer::Confirmed)
        }
        fn recheck(&mut self, _: &str) -> Result<Recheck, OperatorError> {
            Ok(Recheck::Stop)
        }
    }

    #[test]
    fn the_aiming_wrapper_passes_on_the_reading_count_and_the_recheck() {
        let mut scripted = ScriptedOperator::confirming();
        let mut aiming = Aiming {
            aims: BTreeMap::new(),
            meter: None,
            inner: &mut scripted,
        };
        let readings = PlacementReadings { first: 1, of: 5 };
        aiming.ask_placement("aim at patch 3", readings).unwrap();
        assert_eq!(scripted.prompts, vec!["aim at patch 3 — 5 readings"]);

        let mut stopper = Stopper;
        let mut aiming = Aiming {
            aims: BTreeMap::new(),
            meter: None,
            inner: &mut stopper,
        };
        assert_eq!(aiming.recheck("Y differs").unwrap(), Recheck::Stop);
    }
}
