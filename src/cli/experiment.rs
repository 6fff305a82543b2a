//! `metamer experiment`: the paper's whole chain, stage by stage, resumable, each finished
//! stage re-used while its inputs are unchanged.

use std::cell::RefCell;
use std::path::{Path, PathBuf};

use indicatif::{ProgressBar, ProgressStyle};
use metamer::display::gamut::GamutMapping;
use metamer::display::ModelKind;
use metamer::experiment::display::DisplayOptions;
use metamer::experiment::reproduction::ReproductionOptions;
use metamer::experiment::simulation::SimulationOptions;
use metamer::experiment::{
    BoxRequest, ExperimentError, Progress, Request, RequestError, Stage, StageOutcome,
};
use metamer::rig::{Scenario, ScreenSpec};
use metamer::session::{on_ctrl_c, RunOptions};
use metamer_drivers::Spec;

use super::plan_choice::{BoxPlanKind, PlanKind, RuleArgs};
use super::{CliError, CliResult};

#[derive(clap::Args)]
pub struct Args {
    /// Output directory; each stage writes into its own subdirectory.
    #[arg(short = 'o', long = "out", value_name = "DIR")]
    out: PathBuf,
    /// The spectral instrument that measures the box's light tiles and materials (the box
    /// stage is the `measure-box` session; sim:i1pro measures the simulated box).
    #[arg(long, value_name = "SPEC", required_unless_present = "box_scene")]
    spectral: Option<Spec>,
    /// The box measurement plan (see `metamer measure-box --help`); default: the paper's.
    #[arg(long, value_name = "PLAN.json")]
    plan: Option<PathBuf>,
    /// Readings per target in the box (default: the plan's).
    #[arg(long, value_name = "N")]
    box_repeats: Option<usize>,
    /// The box's tiles and fall-off: fixed (every tile and angle, the paper's) or adaptive
    /// (a subset first, then where the spatial and distribution models leave the spots
    /// most in doubt, up to a cap).
    #[arg(long, value_enum, default_value = "fixed")]
    box_plan: BoxPlanKind,
    /// Instead of measuring the box here: its measured scene (`scene.json` of
    /// `metamer measure-box`) …
    #[arg(
        long,
        value_name = "SCENE",
        requires = "box_spots",
        conflicts_with = "spectral"
    )]
    box_scene: Option<PathBuf>,
    /// … and its spot readings: any readings file `validate` reads (an earlier
    /// experiment's box/spots.csv, a CSV `patch,X,Y,Z`, a journal, `spot --json`).
    #[arg(long, value_name = "READINGS", requires = "box_scene")]
    box_spots: Option<PathBuf>,
    /// The monitor that shows the simulation: window:N (a real monitor) or virtual:PRESET.
    #[arg(long, default_value = "virtual:ips-lcd", value_name = "DISPLAY")]
    display: ScreenSpec,
    /// The spot meter that reads the box (fall-off, spots) and the display.
    #[arg(long, default_value = metamer::experiment::DEFAULT_SPOT, value_name = "SPEC")]
    spot: Spec,
    /// Display model (see `metamer fit --help`).
    #[arg(long, default_value = "lut", value_name = "MODEL")]
    model: ModelKind,
    /// Out-of-gamut colours: nearest-lab or clip.
    #[arg(long, default_value = "nearest-lab", value_name = "MAPPING")]
    gamut: GamutMapping,
    /// The simulation's accuracy: every patch's ΔE*ab uncertainty below this.
    #[arg(long, default_value_t = 0.1, value_name = "ΔE")]
    target_de: f64,
    /// Side of the square camera image rendered, reproduced and shown on the display for
    /// the spot readings (the paper's 1014; 0: spots only, each patch's colour shown
    /// full-screen instead).
    #[arg(long, default_value_t = 1014, value_name = "PIXELS")]
    image_size: usize,
    /// Samples per pixel of the image when the path tracer renders it (the radiosity image
    /// is noise-free).
    #[arg(long, default_value_t = 16, value_name = "N")]
    image_spp: u64,
    /// Another renderer's XYZ image (.exr or .pfm, absolute cd/m²) of the measured scene's
    /// camera: the simulation stage reads the 24 meter readings back from it (as `render
    /// spots-from-image`) instead of rendering, and the display shows it.
    #[arg(
        long,
        value_name = "IMAGE",
        conflicts_with_all = ["image_size", "image_spp"]
    )]
    simulation_image: Option<PathBuf>,
    /// The simulated box's light (simulated instruments only; default display-white):
    /// display-white (the ips-lcd display's white, as the paper's box was lit by an LCD)
    /// or led-rgb1 (CIE LED-RGB1, whose saturated colours no virtual display can show).
    #[arg(long, value_name = "LIGHT", conflicts_with = "box_scene")]
    scenario: Option<Scenario>,
    /// Spot readings averaged per patch on the display.
    #[arg(long, default_value_t = 3, value_name = "K")]
    repeats: usize,
    /// Read each patch on the display until its ΔE*ab against the box is decided at 95 %
    /// with this margin beyond the JND (ΔE*ab 2.3), at least twice and at most --repeats
    /// times (e.g. 0.1); without it every patch is read --repeats times.
    #[arg(long, value_name = "ΔE")]
    until_decided: Option<f64>,
    /// Another run's folder (an experiment's or `lab`'s, measured with another plan on the
    /// same rig), whose measuring cost and accuracy the report's cost section sets beside
    /// this run's; read from its saved files, nothing measured again.
    #[arg(long, value_name = "DIR")]
    compare_with: Option<PathBuf>,
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Run only this stage (again): box, simulation, display, reproduction, display-spots,
    /// validation.
    #[arg(long, value_name = "STAGE")]
    stage: Option<Stage>,
    /// Continue an interrupted measuring stage from its journal.
    #[arg(long)]
    resume: bool,
    /// Do not mirror the reproduced image (the paper views the display in a mirror).
    #[arg(long)]
    no_mirror: bool,
    /// The operator's time per placement the budget printed before the first reading
    /// assumes, seconds (default 30: a person's half minute to place, aim and confirm).
    #[arg(long, value_name = "S", value_parser = super::parse_placement_seconds)]
    placement_seconds: Option<f64>,
    /// Nobody is at the rig: take every reading without asking anyone to place, aim or
    /// calibrate the instruments. Real instruments without a terminal on stdin need it.
    #[arg(long)]
    unattended: bool,
    /// The display's characterization: fixed (the paper's patches) or adaptive (patches
    /// where the candidate models disagree at the rendered colours).
    #[arg(long, value_enum, default_value = "fixed")]
    display_plan: PlanKind,
    #[command(flatten)]
    rule: RuleArgs,
}

pub fn run_cli(args: Args) -> CliResult {
    let request = request(args)?;
    let shown = StageProgress::default();
    let outcome = request.run(&|p| shown.show(p));
    shown.finish();
    let outcome = outcome.map_err(refusal)?;
    print_outcomes(&outcome.stages, outcome.given_box.as_deref())?;
    print_cost(&metamer::experiment::budget::total(&outcome.budget))?;
    for line in outcome.comparison_lines() {
        outln!("{line}")?;
    }
    if let Some(report) = &outcome.report {
        outln!("report: {}", report.display())?;
    }
    Ok(())
}

/// The flags as the library's request; the library checks and completes it.
fn request(args: Args) -> Result<Request, CliError> {
    let spot = args.spot;
    Ok(Request {
        dir: args.out.clone(),
        box_source: match (args.box_scene, args.box_spots, args.spectral) {
            (Some(scene), Some(spots), _) => BoxRequest::Given { scene, spots },
            (_, _, Some(spectral)) => BoxRequest::Measure {
                spectral,
                spot: spot.clone(),
                plan: args.plan,
                repeats: args.box_repeats,
                adaptive: args.box_plan.adaptive(),
                seed: args.seed,
                light: args.scenario,
            },
            _ => {
                return Err(CliError::Usage(
                    "give --spectral (measure the box) or --box-scene with --box-spots".into(),
                ))
            }
        },
        simulation: SimulationOptions::new(
            args.target_de,
            args.seed,
            args.image_size,
            args.image_spp,
            args.simulation_image,
        ),
        display: DisplayOptions {
            screen: args.display,
            spot,
            model: args.model,
            adaptive: args.rule.rule(args.display_plan)?,
        },
        reproduction: ReproductionOptions {
            gamut: args.gamut,
            mirror: !args.no_mirror,
        },
        repeats: args.repeats,
        until_decided: args.until_decided,
        compare_with: args.compare_with,
        stage: args.stage,
        rerun_all: false,
        resume: args.resume,
        unattended: args.unattended,
        run: RunOptions {
            stop_after: None,
            interrupt: Some(on_ctrl_c()),
            placement_s: args.placement_seconds,
        },
    })
}

/// What the measuring stages cost against their budget, when every one of them says.
pub(super) fn print_cost(total: &metamer::session::CostReport) -> CliResult {
    if let Some(actual) = &total.actual {
        outln!("{}", actual.after("the measuring stages", &total.estimate))?;
    }
    Ok(())
}

/// A refusal of the request in the words of the command line (exit 2), or what stopped
/// the experiment.
pub(super) fn refusal(e: RequestError) -> CliError {
    match e {
        RequestError::NobodyAtTheRig(e) => super::rig::nobody_at_the_rig(e),
        RequestError::BoxLight(e) => {
            super::rig::box_light_refusal(e, Some(metamer::experiment::DEFAULT_SPOT))
        }
        RequestError::Experiment(ExperimentError::ImageInStage { file, dir }) => CliError::Failed(
            format!(
                "--simulation-image {}: lies in the simulation stage's directory {}, which \
                     the experiment replaces: copy it elsewhere and give that copy",
                file.display(),
                dir.display()
            )
            .into(),
        ),
        e if e.is_usage() => CliError::Usage(usage(&e)),
        e => CliError::from(e),
    }
}

/// A refusal of the request's own values, naming the flag that gave the value.
fn usage(e: &RequestError) -> String {
    match e {
        RequestError::TargetDe => "--target-de must be above 0".into(),
        RequestError::Repeats { most, got } => {
            format!("--repeats must be from 1 to {most}, got {got}")
        }
        RequestError::BoxRepeats => "--box-repeats must be at least 1".into(),
        RequestError::UntilDecided(why) => format!("--until-decided with --repeats: {why}"),
        RequestError::TimeScale => "--time-scale must be 0 or more".into(),
        RequestError::ImageSize => format!(
            "--image-size must be at most {}",
            metamer::experiment::MAX_IMAGE_SIZE
        ),
        RequestError::ImageSpp => "--image-spp must be at least 1".into(),
        e => e.to_string(),
    }
}

/// The experiment's progress on the terminal: a line per stage, a bar while measuring.
#[derive(Default)]
pub(super) struct StageProgress {
    bar: RefCell<Option<ProgressBar>>,
}

impl StageProgress {
    pub(super) fn show(&self, p: Progress) {
        match p {
            Progress::Stage { stage, reused } => {
                self.finish();
                if reused {
                    super::console::reported_at_exit(errln!("{stage}: unchanged inputs, re-used"));
                } else {
                    super::console::reported_at_exit(errln!("{stage}: running"));
                }
            }
            Progress::Readings { done, total } => {
                let mut b = self.bar.borrow_mut();
                let b = b.get_or_insert_with(|| {
                    let b = ProgressBar::new(total as u64);
                    b.set_style(
                        ProgressStyle::with_template("  {bar:40} {pos}/{len} readings, {eta} left")
                            .unwrap_or_else(|_| ProgressStyle::default_bar()),
                    );
                    b
                });
                b.set_length(total as u64);
                b.set_position(done as u64);
            }
            // A hidden bar (no terminal) prints nothing, not even its println.
            Progress::Note(text) => match self.bar.borrow().as_ref() {
                Some(b) if !b.is_hidden() => b.println(format!("  {text}")),
                _ => super::console::reported_at_exit(errln!("  {text}")),
            },
        }
    }

    pub(super) fn finish(&self) {
        if let Some(b) = self.bar.borrow_mut().take() {
            b.finish_and_clear();
        }
    }
}

/// One line per stage: ran, re-used or (a box measured earlier or elsewhere) given, how
/// long, where.
pub(super) fn print_outcomes(outcomes: &[StageOutcome], given_box: Option<&Path>) -> CliResult {
    for o in outcomes {
        let (how, dir) = match given_box {
            Some(spots) if o.stage == Stage::Box => ("given", spots),
            _ => (if o.reused { "re-used" } else { "ran" }, o.dir.as_path()),
        };
        outln!(
            "{:<14} {:<8} {:>8.1} s  {}",
            o.stage.name(),
            how,
            o.seconds,
            dir.display()
        )?;
    }
    Ok(())
}
