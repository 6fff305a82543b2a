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
//! loading, backlight dimming). A third way keeps the picture and the meter still: the
//! image is slid so each patch in turn lies under the meter ([`SpotsShown::UnderMeter`],
//! [`shown`]). `display-spots.json` records which was shown.
//!
//! **Until decided.** With a verdict rule ([`DisplayRule`]) each patch is read at least
//! twice and at most `most` times, until the 95 % interval of its ΔE*ab against the box's
//! reading of the patch (relative to the display profile's white, as the validation
//! compares them) lies the margin or more beyond the JND
//! ([`crate::validation::sequential::verdict`]), the meter's stated repeatability scaled by
//! the figure pooled across the patches read before it. Each patch's row in `spots.csv`
//! then carries the figure pooled across all patches, its degrees of freedom and `most`, so
//! the validation takes the repeated interval, valid at whatever count the rule stopped.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use metamer_drivers::{MeasureMode, Spec};
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

mod plan;
pub mod shown;
pub use plan::{aim_prompt, aims_on, image_plan, plan, PatchAim, SpotStep};
pub use shown::under_meter_plan;
mod spots_shown;
pub use spots_shown::{SpotsShown, UnknownSpotsShown};

use super::display::{open_meter, open_screen, DisplaySetting};
use super::error::ExperimentError;
use super::progress::Progress;
use super::readings::{write_readings, PatchReading, ReadingSet};
use super::reproduction::{PatchDrive, PatchRegion};
use crate::color::Xyz;
use crate::image::{Drive8Image, ScreenSpot};
use crate::rig::MeterAim;
use crate::session::budget::{srgb_assumption, srgb_luminance, SRGB_WHITE_CD_M2};
use crate::session::{
    patch_so_far, Answer, CostReport, Entry, InstrumentRecord, Meter, Operator, OperatorError,
    PlacementReadings, Prepare, Recheck, Rig, RunEnd, RunOptions, Screen, ScriptedOperator,
    Session, SessionPlan, Step, StepProgress, Stopping, TerminalOperator,
};
use crate::validation::covariance;
use crate::validation::repeatability::{self, Repeatability};
use crate::validation::sequential::{verdict, Pool, Reference};

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

/// What `display-spots.json` holds.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SpotRecord {
    /// `image` (the reproduced image, the meter aimed patch by patch), `image moved under
    /// the meter` (the image slid so each patch lies under the meter, which stays at the
    /// middle of the screen; each aim's `shift` says by how much) or `patch colours` (each
    /// patch's drive values full-screen).
    pub shown: String,
    /// Why, when it is not the image.
    pub note: Option<String>,
    pub aims: Vec<PatchAim>,
    /// The readings' budget before the first of this run and what the run took.
    #[serde(default)]
    pub cost: Option<CostReport>,
}

/// How many times each patch is read.
#[derive(Clone, Debug, PartialEq)]
pub enum DisplayRule {
    /// Always this many readings.
    Fixed(usize),
    /// Until the patch's ΔE*ab against the box is decided: the rule, the box's readings of
    /// the patches and the white the comparison is relative to.
    Verdict {
        margin: f64,
        most: usize,
        references: BTreeMap<usize, Reference>,
        white: Xyz,
    },
}

impl DisplayRule {
    /// The most readings of one patch.
    pub fn most(&self) -> usize {
        match self {
            DisplayRule::Fixed(n) => (*n).max(1),
            DisplayRule::Verdict { most, .. } => *most,
        }
    }

    /// The verdict rule against the box's readings `reference` of the patches, relative to
    /// `white`.
    pub fn verdict(margin: f64, most: usize, reference: &ReadingSet, white: Xyz) -> DisplayRule {
        let references = reference
            .patches
            .iter()
            .map(|(k, p)| {
                let r = Reference {
                    xyz: p.xyz,
                    cov_mean: covariance::of_factors(&p.u_factors),
                    dof: p.dof.map(|d| d as f64),
                    lab_var: p.u_lab * p.u_lab,
                };
                (*k, r)
            })
            .collect();
        DisplayRule::Verdict {
            margin,
            most,
            references,
            white,
        }
    }

    /// The plan's options: the count, and for a verdict rule the rule with what it decides
    /// against (every value, so a journal is resumed only by the same decisions).
    fn options(&self) -> BTreeMap<String, String> {
        let mut options = BTreeMap::new();
        options.insert("repeats".to_string(), self.most().to_string());
        if let DisplayRule::Verdict {
            margin,
            references,
            white,
            ..
        } = self
        {
            options.insert("rule".into(), format!("verdict, margin {margin}"));
            let against: Vec<String> = references
                .iter()
                .map(|(k, r)| format!("{k}: {r:?}"))
                .collect();
            options.insert(
                "against".into(),
                crate::digest::hex(&Sha256::digest(format!("{white:?} {against:?}").as_bytes())),
            );
        }
        options
    }
}

/// Passes every request on to the operator; on a simulated screen it also aims the
/// simulated meter where an aiming request says.
struct Aiming<'a> {
    aims: BTreeMap<String, ScreenSpot>,
    meter: Option<MeterAim>,
    inner: &'a mut dyn Operator,
}

impl<'a> Aiming<'a> {
    fn new(aims: &[PatchAim], meter: Option<MeterAim>, inner: &'a mut dyn Operator) -> Self {
        let aims = aims
            .iter()
            .map(|a| {
                let spot = ScreenSpot {
                    x: a.x,
                    y: a.y,
                    radius: a.radius,
                };
                (a.prompt.clone(), spot)
            })
            .collect();
        Aiming { aims, meter, inner }
    }
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

/// The display spots' stopping rule: a patch's repeats end once its verdict against the
/// box is decided; everything it decides follows from the journal's entries, so a resumed
/// session skips exactly what the first run skipped.
struct VerdictStopping {
    margin: f64,
    most: usize,
    references: BTreeMap<usize, Reference>,
    white: Xyz,
    stated: Repeatability,
}

impl VerdictStopping {
    /// The stopping of a verdict rule, for readings by a meter of `model`; None for a fixed
    /// count.
    fn of(rule: &DisplayRule, model: &str) -> Option<VerdictStopping> {
        let DisplayRule::Verdict {
            margin,
            most,
            references,
            white,
        } = rule
        else {
            return None;
        };
        Some(VerdictStopping {
            margin: *margin,
            most: *most,
            references: references.clone(),
            white: *white,
            stated: repeatability::stated(model, MeasureMode::Emissive),
        })
    }
}

impl Stopping<SpotStep> for VerdictStopping {
    fn skip(
        &self,
        index: usize,
        steps: &[Step<SpotStep>],
        entries: &[Option<Entry<SpotStep>>],
    ) -> bool {
        let Some((patch, first, this)) =
            patch_so_far(index, steps, entries, |s| Some(s.data.patch))
        else {
            return false;
        };
        let Some(reference) = self.references.get(&patch) else {
            return false;
        };
        let pool = pool_by_patch(entries[..first].iter().flatten(), &self.stated);
        verdict(
            self.margin,
            self.most,
            reference,
            &this,
            &pool.noise(self.stated),
            self.white,
        )
        .is_some_and(|look| look.decided)
    }
}

/// The stated repeatability pooled across `entries`, each patch its readings.
fn pool_by_patch<'a>(
    entries: impl Iterator<Item = &'a Entry<SpotStep>>,
    stated: &Repeatability,
) -> Pool {
    let mut by_patch: BTreeMap<usize, Vec<Xyz>> = BTreeMap::new();
    for e in entries {
        by_patch
            .entry(e.data.patch)
            .or_default()
            .push(e.reading.xyz);
    }
    let mut pool = Pool::default();
    for readings in by_patch.values() {
        pool.add(readings, stated);
    }
    pool
}

/// Each patch's readings reduced: by a verdict rule, its mean with the figure pooled
/// across every patch, that figure's degrees of freedom and the rule's `most`; else its
/// own scatter.
fn reduce(
    entries: &[&Entry<SpotStep>],
    rule: &DisplayRule,
    meter: &str,
) -> Vec<(usize, PatchReading)> {
    let stated = repeatability::stated(meter, MeasureMode::Emissive);
    if let DisplayRule::Verdict { most, .. } = rule {
        let pool = pool_by_patch(entries.iter().copied(), &stated);
        let noise = pool.noise(stated);
        let mut by_patch: BTreeMap<usize, Vec<Xyz>> = BTreeMap::new();
        for e in entries {
            by_patch
                .entry(e.data.patch)
                .or_default()
                .push(e.reading.xyz);
        }
        let pooled: Option<Vec<(usize, PatchReading)>> = by_patch
            .iter()
            .map(|(k, xs)| {
                let (mean, _) = covariance::sample(xs);
                let cov = noise.covariance(mean)?;
                let dof = (pool.dof > 0).then_some(pool.dof)?;
                Some((
                    *k,
                    PatchReading::pooled(mean, cov, xs.len(), dof, Some(*most)),
                ))
            })
            .collect();
        if let Some(pooled) = pooled {
            return pooled;
        }
    }
    let readings: Vec<(usize, &metamer_drivers::Reading)> =
        entries.iter().map(|e| (e.data.patch, &e.reading)).collect();
    PatchReading::group(&readings)
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
    /// How each patch is put in front of the meter (with no image, full-screen whatever
    /// this says).
    pub shown: SpotsShown,
    pub rule: &'a DisplayRule,
    pub resume: bool,
    /// Nobody at the rig: every request counts as done.
    pub unattended: bool,
    pub run: &'a RunOptions,
}

/// Each patch's readings by patch number, and the files written.
pub type MeasuredPatches = (Vec<(usize, PatchReading)>, Vec<&'static str>);

/// Shows and reads every patch into `dir`.
pub fn measure(
    dir: &Path,
    s: &SpotSession<'_>,
    progress: &dyn Fn(Progress),
) -> Result<MeasuredPatches, ExperimentError> {
    let SpotSession {
        setting,
        spot_spec,
        drives,
        rule,
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
    let (mut plan, mut record) = show(s, screen.as_mut(), progress)?;
    plan.steps.iter_mut().for_each(|s| s.settle = settle);
    // The runner shows the colours, or slides the image, itself; an image the meter is
    // aimed at stays as `show` put it.
    let on_screen = plan
        .steps
        .iter()
        .any(|s| matches!(s.prepare, Prepare::Show { .. } | Prepare::ShiftImage { .. }));
    let moving = record.aims.iter().any(|a| a.shift.is_some());
    let mut instruments = BTreeMap::new();
    instruments.insert("spot".to_string(), InstrumentRecord::of(meter.as_ref()));
    let model = meter.info().model;
    let journal: PathBuf = dir.join(JOURNAL_FILE);
    let header = SpotHeader {
        screen: setting.screen.canonical(),
        virtual_white_cd_m2: setting.virtual_white_cd_m2,
    };
    let mut session = Session::open(&journal, plan, header, instruments, resume)?;
    if let Some(stopping) = VerdictStopping::of(rule, &model) {
        session = session.with_stopping(Box::new(stopping));
    }
    let mut scripted = ScriptedOperator::confirming();
    let mut terminal = TerminalOperator;
    let inner: &mut dyn Operator = if s.unattended || setting.virtual_white_cd_m2.is_some() {
        &mut scripted
    } else {
        &mut terminal
    };
    let mut operator = Aiming::new(&record.aims, screen.meter_aim(), inner);
    let incomplete = |session: &Session<SpotHeader, SpotStep>| ExperimentError::Incomplete {
        stage: "display-spots",
        done: session.done(),
        total: session.plan().steps.len(),
        journal: journal.clone(),
    };
    let meters = [("spot".to_string(), Meter::of(meter.as_ref()))].into();
    let estimate = {
        let (light, assumption) = patch_light(drives, screen.as_ref());
        let mut cost = session.estimate(&meters, &light, &assumption, run.placement_s());
        if moving && session.done() < session.plan().steps.len() {
            cost.add(&shown::aim_cost(run.placement_s()));
        }
        cost
    };
    let Some(aimed) = aim_before(&session, &record.aims, moving, &mut operator)? else {
        return Err(incomplete(&session));
    };
    let mut rig = Rig {
        screen: on_screen.then_some(screen.as_mut()),
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
    let mut spent = session.spent().clone();
    spent.add(&aimed);
    record.cost = Some(CostReport {
        estimate,
        actual: Some(spent),
    });
    if end != RunEnd::Complete {
        return Err(incomplete(&session));
    }
    let entries = session.complete_entries().unwrap_or_default();
    let stats = reduce(&entries, rule, &model);
    write_readings(&dir.join(SPOTS_FILE), &stats)?;
    let text = serde_json::to_string_pretty(&record).map_err(ExperimentError::Json)?;
    super::cache::write_atomic(&dir.join(RECORD_FILE), text.as_bytes())?;
    Ok((stats, vec![JOURNAL_FILE, SPOTS_FILE, RECORD_FILE]))
}

/// Puts the session's picture on the screen (the image, or nothing: each patch's colour
/// is shown by its step) and gives the plan for it with the record of what was shown.
fn show(
    s: &SpotSession<'_>,
    screen: &mut dyn Screen,
    progress: &dyn Fn(Progress),
) -> Result<(SessionPlan<SpotStep>, SpotRecord), ExperimentError> {
    let repeats = s.rule.most();
    let image = s
        .image
        .as_ref()
        .filter(|_| s.shown != SpotsShown::FullScreen);
    let (mut plan, record) = match image {
        Some(given) => {
            let image =
                Drive8Image::read_png(given.file).map_err(|e| ExperimentError::BadFile {
                    file: given.file.to_path_buf(),
                    message: e.to_string(),
                })?;
            let placement = screen.show_image(&image)?;
            let (aims, plan) = if s.shown == SpotsShown::UnderMeter {
                let size = (image.width, image.height);
                let aims = shown::aims_under_meter(&placement, size, given.regions);
                let plan = under_meter_plan(&aims, repeats);
                (aims, plan)
            } else {
                let aims = aims_on(&placement, given.regions);
                let plan = image_plan(&aims, repeats);
                (aims, plan)
            };
            let record = SpotRecord {
                shown: s.shown.record_name(true).into(),
                note: None,
                aims,
                cost: None,
            };
            (plan, record)
        }
        None => {
            let note = if s.image.is_some() {
                "each patch's drive values were shown over the whole screen, as asked, \
                 instead of the reproduced image"
            } else {
                "no image was rendered: each patch's drive values were shown over the \
                 whole screen instead of the reproduced image"
            };
            progress(Progress::Note(note.into()));
            let record = SpotRecord {
                shown: SpotsShown::FullScreen.record_name(false).into(),
                note: Some(note.into()),
                aims: Vec::new(),
                cost: None,
            };
            (plan(s.drives, repeats), record)
        }
    };
    plan.options.extend(s.rule.options());
    Ok((plan, record))
}

/// Has the operator aim the meter before the readings the journal lacks: for the image
/// moved under the meter (`moving`) once at the middle of the screen, whenever readings
/// remain (it may have moved since an interrupted run); else again at the patch a resumed
/// session continues mid-way. The placement that took, or None when the operator aborts.
fn aim_before(
    session: &Session<SpotHeader, SpotStep>,
    aims: &[PatchAim],
    moving: bool,
    operator: &mut dyn Operator,
) -> Result<Option<crate::session::Cost>, ExperimentError> {
    let remaining = session.done() < session.plan().steps.len();
    Ok(match (moving, remaining) {
        (true, true) => shown::aim_at_middle(operator)?,
        (true, false) => Some(Default::default()),
        (false, _) => aim_again(session, aims, operator)?.then(Default::default),
    })
}

/// A resumed session may continue mid-patch, after that patch's aiming request: asks it
/// again. False when the operator aborts.
fn aim_again(
    session: &Session<SpotHeader, SpotStep>,
    aims: &[PatchAim],
    operator: &mut dyn Operator,
) -> Result<bool, ExperimentError> {
    let Some(step) = session.plan().steps.get(session.done()) else {
        return Ok(true);
    };
    if step.data.repeat > 1 {
        if let Some(a) = aims.iter().find(|a| a.patch == step.data.patch) {
            return Ok(operator.ask(&a.prompt)? != Answer::Abort);
        }
    }
    Ok(true)
}

#[cfg(test)]
mod tests;
