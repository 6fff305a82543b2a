//! The simulated lab: the experiment ([`crate::experiment`]) on the simulated rig, so the
//! paper's whole chain (Bärz, Henrich, Müller, Fig. 1) runs on any machine with nobody at
//! it. The box is the simulated truth box measured by the `measure-box` session with the
//! simulated i1Pro and CS-100A, the display a virtual monitor characterized and read by
//! the simulated CS-100A; every stage writes the same directories and files as
//! `metamer experiment`, and is re-used while its inputs are unchanged. `lab.json` sums the
//! validation up.

pub mod compare;
mod error;

pub use error::LabError;

use std::path::{Path, PathBuf};

use metamer_drivers::Spec;
use serde::Serialize;

use crate::color::Xyz;
use crate::display::gamut::GamutMapping;
use crate::display::ModelKind;
use crate::experiment::budget::{total, StageBudget};
use crate::experiment::display::DisplayOptions;
use crate::experiment::display_spots::SpotsShown;
use crate::experiment::measuring::MeasuringPlan;
use crate::experiment::reproduction::ReproductionOptions;
use crate::experiment::request::{check_dir, check_image_size, check_repeats, check_target_de};
use crate::experiment::simulation::SimulationOptions;
use crate::experiment::validate::{ValidationResult, FILE as COMPARISONS_FILE};
use crate::experiment::{BoxRequest, Progress, Request, RequestError, Stage, StageOutcome};
use crate::measure_box::BoxPlan;
use crate::output::OutputPolicy;
use crate::rig::{Preset, Scenario, ScreenSpec};
use crate::session::{CostReport, RunOptions};
use crate::validation::assess::{Assessment, JndCount, JndVerdict, Stat};
use crate::validation::export::HTML_FILE;
use crate::validation::propagate::Interval;
use crate::validation::sequential::RepeatRule;

/// What a lab run is made of.
#[derive(Clone, Debug, Serialize)]
pub struct LabOptions {
    /// The measuring plan the measuring options below were expanded from
    /// ([`MeasuringPlan::expand`]: `box_adaptive`, `box_spot_rule`, `adaptive`, `repeats`,
    /// `until_decided`).
    pub measuring: MeasuringPlan,
    /// The simulated box's light.
    pub scenario: Scenario,
    /// The simulated monitor.
    #[serde(serialize_with = "preset_name")]
    pub display: Preset,
    pub model: ModelKind,
    pub gamut: GamutMapping,
    /// The simulation's target: 95 % half-width of every patch's ΔE*ab.
    pub target_de: f64,
    /// Spot readings averaged per patch on the display: with `until_decided`, the most.
    pub repeats: usize,
    /// Read each display patch until its verdict against the box is decided, this margin
    /// beyond the JND; None: always `repeats` readings.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub until_decided: Option<f64>,
    /// How each patch is put in front of the meter on the display.
    #[serde(default, skip_serializing_if = "is_aimed")]
    pub spots_shown: SpotsShown,
    /// Another run's folder, measured with another plan on the same rig: the report's
    /// cost section sets its measuring cost and accuracy beside this run's, from its saved
    /// files alone.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub compare_with: Option<PathBuf>,
    /// The box plan file; None: the paper's plan.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub plan: Option<PathBuf>,
    /// Readings of each tile and spot in the box; None: the box plan's (`lab.json` records
    /// the number used).
    pub box_repeats: Option<usize>,
    /// Read the box's tiles and fall-off adaptively (the box plan's rule, or the default).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub box_adaptive: bool,
    /// How each box spot is read where the box plan file names no rule; its CIELAB is
    /// relative to the simulated monitor's nominal white.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub box_spot_rule: Option<RepeatRule>,
    pub seed: u64,
    /// The simulated instruments' time scale (1 = their real pace).
    pub time_scale: f64,
    /// The camera image's side in pixels, shown whole on the display for the spot
    /// readings; 0: no image (each patch's colour is shown full-screen instead).
    pub image_size: usize,
    /// The display's characterization plan: None the fixed plan, Some the adaptive plan
    /// with this rule (its targets the rendered readings).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub adaptive: Option<crate::display::characterize::adaptive::Rule>,
}

fn is_aimed(s: &SpotsShown) -> bool {
    *s == SpotsShown::Aimed
}

/// Samples per pixel of the image where the path tracer renders it (scenes the radiosity
/// solver does not take); the experiment's default.
const IMAGE_SPP: u64 = 16;

fn preset_name<S: serde::Serializer>(p: &Preset, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_str(p.name())
}

/// The summary of a lab run, [`LAB_FILE`] in its directory.
pub const LAB_FILE: &str = "lab.json";

impl LabOptions {
    /// The simulated instrument `model` at this run's pace, with `seed` when given.
    fn instrument(&self, model: &str, seed: Option<u64>) -> Spec {
        let spec = Spec::simulated(model).with_option("time_scale", self.time_scale);
        match seed {
            Some(s) => spec.with_option("seed", s),
            None => spec,
        }
    }

    /// The lab's own numbers, checked before the experiment's: the box's readings per
    /// target and the instruments' pace.
    fn check(&self, dir: &Path) -> Result<(), RequestError> {
        check_target_de(self.target_de)?;
        check_repeats(self.repeats)?;
        if self.box_repeats == Some(0) {
            return Err(RequestError::BoxRepeats);
        }
        if !(self.time_scale >= 0.0 && self.time_scale.is_finite()) {
            return Err(RequestError::TimeScale);
        }
        check_image_size(self.image_size)?;
        check_dir(dir)
    }

    /// The experiment these options describe, into `dir`: the preset. The box's
    /// instruments are seeded by the box stage as `measure-box` seeds them (the spectral
    /// instrument with the seed, the spot meter with seed + 1); the meter that reads the
    /// display gets seed + 2, so its noise is independent of the box readings'. `force`
    /// runs every stage again.
    pub fn request(&self, dir: &Path, resume: bool, force: bool, run: RunOptions) -> Request {
        Request {
            dir: dir.to_path_buf(),
            measuring: self.measuring,
            box_source: BoxRequest::Measure {
                spectral: self.instrument("i1pro", None),
                spot: self.instrument("cs100a", None),
                plan: self.plan.clone(),
                repeats: self.box_repeats,
                adaptive: self.box_adaptive,
                spot_rule: self.box_spot_rule.clone(),
                seed: self.seed,
                light: Some(self.scenario),
            },
            simulation: SimulationOptions::new(
                self.target_de,
                self.seed,
                self.image_size,
                IMAGE_SPP,
                None,
            ),
            display: DisplayOptions {
                screen: ScreenSpec::Virtual(self.display),
                spot: self.instrument("cs100a", Some(self.seed.wrapping_add(2))),
                model: self.model,
                adaptive: self.adaptive,
            },
            reproduction: ReproductionOptions {
                gamut: self.gamut,
                mirror: true,
            },
            repeats: self.repeats,
            until_decided: self.until_decided,
            spots_shown: self.spots_shown,
            compare_with: self.compare_with.clone(),
            stage: None,
            rerun_all: force,
            resume,
            unattended: true,
            run,
        }
    }
}

/// One comparison in short: what the report's full tables say, in the report's words.
#[derive(Clone, Debug, Serialize)]
pub struct ComparisonSummary {
    pub reference: String,
    pub test: String,
    pub patches: usize,
    /// The verdicts at 95 % confidence: below, above, undecided.
    pub jnd: JndCount,
    /// Patches whose ΔE*ab point estimate is below the JND (no uncertainty considered).
    pub below_jnd_point: usize,
    /// The patches not shown to be below the JND, with their 95 % intervals.
    pub not_below: Vec<PatchVerdict>,
    pub mean_de76: Stat,
    pub max_de76: Stat,
    pub mean_de00: Stat,
    pub max_de00: Stat,
    /// The line the terminal shows.
    pub summary: String,
}

/// A patch's ΔE*ab, its 95 % interval and what they say of the JND.
#[derive(Clone, Debug, Serialize)]
pub struct PatchVerdict {
    pub patch: usize,
    pub de76: f64,
    pub interval: Interval,
    pub jnd: JndVerdict,
}

impl From<&Assessment> for ComparisonSummary {
    fn from(a: &Assessment) -> ComparisonSummary {
        ComparisonSummary {
            reference: a.reference.clone(),
            test: a.test.clone(),
            patches: a.patches.len(),
            jnd: a.jnd,
            below_jnd_point: a.below_jnd_point,
            not_below: a
                .failing()
                .map(|p| PatchVerdict {
                    patch: p.patch,
                    de76: p.de76,
                    interval: p.de76_interval,
                    jnd: p.jnd,
                })
                .collect(),
            mean_de76: a.mean_de76,
            max_de76: a.max_de76,
            mean_de00: a.mean_de00,
            max_de00: a.max_de00,
            summary: a.summary(),
        }
    }
}

/// How one stage went, by its directory's name.
#[derive(Clone, Debug, Serialize)]
pub struct StageSummary {
    pub stage: &'static str,
    /// Its inputs were unchanged and its outputs intact: nothing was run.
    pub reused: bool,
    /// How long the run that produced its outputs took (for a re-used stage, the time its
    /// record keeps).
    pub seconds: f64,
}

impl From<&StageOutcome> for StageSummary {
    fn from(o: &StageOutcome) -> StageSummary {
        StageSummary {
            stage: o.stage.name(),
            reused: o.reused,
            seconds: o.ran_seconds,
        }
    }
}

/// What `lab.json` holds.
#[derive(Clone, Debug, Serialize)]
pub struct LabSummary {
    pub options: LabOptions,
    pub stages: Vec<StageSummary>,
    /// Each measuring stage's budget before its first reading and what it took, as the
    /// stage's files keep them.
    pub budget: Vec<StageBudget>,
    /// Their sum (what was taken only where every stage keeps it).
    pub budget_total: CostReport,
    /// Wall time of this call, s (a fully re-used run takes next to none).
    pub seconds: f64,
    /// CIELAB's reference white: the display's measured white, cd/m².
    pub white: Xyz,
    pub out_of_gamut_patches: Vec<usize>,
    pub display_vs_box: ComparisonSummary,
    pub simulation_vs_box: ComparisonSummary,
    pub display_vs_simulation: ComparisonSummary,
    /// The validation report, relative to the run's directory.
    pub report: PathBuf,
}

/// Runs the lab into `dir`: every stage whose inputs changed (all of them with `force`),
/// then `lab.json`. `resume` continues an interrupted measuring stage from its journal.
/// Returns how each stage went and what `lab.json` says.
///
/// # Examples
///
/// The whole lab with its defaults (about a minute: the paper's 1014-pixel image is
/// rendered, reproduced and shown):
///
/// ```no_run
/// use metamer::display::ModelKind;
/// use metamer::experiment::lab::{run_lab, LabOptions};
/// use metamer::rig::{Preset, Scenario};
/// use metamer::session::RunOptions;
///
/// let options = LabOptions {
///     measuring: Default::default(),
///     scenario: Scenario::default(),
///     display: "ips-lcd".parse::<Preset>()?,
///     model: ModelKind::Lut,
///     gamut: "nearest-lab".parse()?,
///     target_de: 0.1,
///     repeats: 3,
///     until_decided: None,
///     spots_shown: Default::default(),
///     compare_with: None,
///     plan: None,
///     box_repeats: None,
///     box_adaptive: false,
///     box_spot_rule: None,
///     seed: 1,
///     time_scale: 0.0,
///     image_size: 1014,
///     adaptive: None,
/// };
/// let dir = std::path::Path::new("lab");
/// let (stages, summary) = run_lab(dir, &options, false, false, RunOptions::default(), &|_| {})?;
/// assert_eq!(stages.len(), 6);
/// println!("{}", summary.display_vs_box.summary);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn run_lab(
    dir: &Path,
    opts: &LabOptions,
    resume: bool,
    force: bool,
    run: RunOptions,
    progress: &dyn Fn(Progress),
) -> Result<(Vec<StageOutcome>, LabSummary), LabError> {
    let start = std::time::Instant::now();
    opts.check(dir)?;
    let outcome = opts.request(dir, resume, force, run).run(progress)?;
    let stages = outcome.stages;
    let file = dir.join(Stage::Validation.name()).join(COMPARISONS_FILE);
    let bad = |message: String| LabError::BadResult {
        file: file.clone(),
        message,
    };
    let text = std::fs::read_to_string(&file).map_err(|e| bad(e.to_string()))?;
    let v: ValidationResult = serde_json::from_str(&text).map_err(|e| bad(e.to_string()))?;
    // The box's readings per target as the box stage took them: given, or the plan's.
    let options = LabOptions {
        box_repeats: Some(opts.box_repeats.unwrap_or(BoxPlan::default().repeats)),
        ..opts.clone()
    };
    let summary = LabSummary {
        options,
        stages: stages.iter().map(StageSummary::from).collect(),
        budget_total: total(&outcome.budget),
        budget: outcome.budget,
        seconds: start.elapsed().as_secs_f64(),
        white: v.white,
        out_of_gamut_patches: v.out_of_gamut_patches.clone(),
        display_vs_box: (&v.display_vs_box).into(),
        simulation_vs_box: (&v.simulation_vs_box).into(),
        display_vs_simulation: (&v.display_vs_simulation).into(),
        report: Path::new(Stage::Validation.name()).join(HTML_FILE),
    };
    let text = serde_json::to_string_pretty(&summary).expect("the lab's summary serializes");
    // lab.json is this command's own summary of the stages' results: every run rewrites it.
    let out = OutputPolicy::new(true);
    out.write(&dir.join(LAB_FILE), text.as_bytes())?;
    Ok((stages, summary))
}
