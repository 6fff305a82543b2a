//! `metamer experiment`: the paper's whole chain, stage by stage, resumable, each finished
//! stage re-used while its inputs are unchanged.

use std::cell::RefCell;
use std::path::{Path, PathBuf};

use indicatif::{ProgressBar, ProgressStyle};
use metamer::display::ModelKind;
use metamer::experiment::display::DisplayOptions;
use metamer::experiment::measure_box::MeasureBox;
use metamer::experiment::reproduction::ReproductionOptions;
use metamer::experiment::simulation::{ImageSpec, SimulationOptions};
use metamer::experiment::validate::{ValidationResult, FILE};
use metamer::experiment::{run, BoxSource, ExperimentOptions, Progress, Stage, StageOutcome};
use metamer::render::scene::Scene;
use metamer::session::{on_ctrl_c, RunOptions};
use metamer::validation::export::HTML_FILE;
use metamer_drivers::Spec;

use super::{CliError, CliResult};

#[derive(clap::Args)]
pub struct Args {
    /// Output directory; each stage writes into its own subdirectory.
    #[arg(short = 'o', long = "out", value_name = "DIR")]
    out: PathBuf,
    /// The spectral instrument that measures the box's light tiles and materials (the box
    /// stage is the `measure-box` session; sim:i1pro measures the simulated box).
    #[arg(long, value_name = "SPEC", required_unless_present = "box_scene")]
    spectral: Option<String>,
    /// The box measurement plan (see `metamer measure-box --help`); default: the paper's.
    #[arg(long, value_name = "PLAN.json")]
    plan: Option<PathBuf>,
    /// Readings per target in the box (default: the plan's).
    #[arg(long, value_name = "N")]
    box_repeats: Option<usize>,
    /// Instead of measuring the box here: its measured scene (`scene.json` of
    /// `metamer measure-box`) …
    #[arg(
        long,
        value_name = "SCENE",
        requires = "box_spots",
        conflicts_with = "spectral"
    )]
    box_scene: Option<PathBuf>,
    /// … and its spot readings (`patch,X,Y,Z,sd_X,sd_Y,sd_Z,n`).
    #[arg(long, value_name = "CSV", requires = "box_scene")]
    box_spots: Option<PathBuf>,
    /// The monitor that shows the simulation: window:N (a real monitor) or virtual:PRESET.
    #[arg(long, default_value = "virtual:ips-lcd", value_name = "DISPLAY")]
    display: String,
    /// The spot meter that reads the box (fall-off, spots) and the display.
    #[arg(long, default_value = "sim:cs100a?time_scale=0", value_name = "SPEC")]
    spot: String,
    /// Display model (see `metamer fit --help`).
    #[arg(long, default_value = "lut", value_name = "MODEL")]
    model: String,
    /// Out-of-gamut colours: nearest-lab or clip.
    #[arg(long, default_value = "nearest-lab", value_name = "MAPPING")]
    gamut: String,
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
    /// The simulated box's light (simulated instruments only; default display-white):
    /// display-white (the ips-lcd display's white, as the paper's box was lit by an LCD)
    /// or led-rgb1 (CIE LED-RGB1, whose saturated colours no virtual display can show).
    #[arg(long, value_name = "LIGHT", conflicts_with = "box_scene")]
    scenario: Option<String>,
    /// Spot readings averaged per patch on the display.
    #[arg(long, default_value_t = 3, value_name = "K")]
    repeats: usize,
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Run only this stage (again): box, simulation, display, reproduction, display-spots,
    /// validation.
    #[arg(long, value_name = "STAGE")]
    stage: Option<String>,
    /// Continue an interrupted measuring stage from its journal.
    #[arg(long)]
    resume: bool,
    /// Do not mirror the reproduced image (the paper views the display in a mirror).
    #[arg(long)]
    no_mirror: bool,
    /// Nobody is at the rig: take every reading without asking anyone to place, aim or
    /// calibrate the instruments. Real instruments without a terminal on stdin need it.
    #[arg(long)]
    unattended: bool,
}

pub fn run_cli(args: Args) -> CliResult {
    let model: ModelKind = args.model.parse().map_err(CliError::Usage)?;
    let stage: Option<Stage> = match &args.stage {
        Some(s) => Some(s.parse().map_err(CliError::Usage)?),
        None => None,
    };
    if !(args.target_de > 0.0 && args.target_de.is_finite()) {
        return Err(CliError::Usage("--target-de must be above 0".into()));
    }
    // As many as a box plan allows a reading of one thing; a billion was accepted and
    // measured for days.
    let most = metamer::measure_box::plan::MAX_REPEATS;
    if !(1..=most).contains(&args.repeats) {
        return Err(CliError::Usage(format!(
            "--repeats must be from 1 to {most}, got {}",
            args.repeats
        )));
    }
    if args.image_size > 8192 {
        return Err(CliError::Usage("--image-size must be at most 8192".into()));
    }
    if args.image_size > 0 && args.image_spp == 0 {
        return Err(CliError::Usage("--image-spp must be at least 1".into()));
    }
    if args.out.exists() && !args.out.is_dir() {
        return Err(CliError::Usage(format!(
            "-o {}: exists and is not a directory",
            args.out.display()
        )));
    }
    check_inputs(&args)?;
    let interrupt = on_ctrl_c();
    let opts = ExperimentOptions {
        dir: args.out.clone(),
        box_source: match (args.box_scene, args.box_spots, args.spectral) {
            (Some(scene), Some(spots), _) => BoxSource::Existing { scene, spots },
            (_, _, Some(spectral)) => {
                let (spectral, spot) = (Spec::new(spectral), Spec::new(args.spot.as_str()));
                let simulated = spectral.is_simulated() && spot.is_simulated();
                let light = super::rig::box_light(args.scenario.as_deref(), simulated)?;
                BoxSource::Measure(MeasureBox {
                    spectral,
                    spot,
                    plan: args.plan,
                    repeats: args.box_repeats,
                    seed: args.seed,
                    light: if simulated {
                        Some(light.unwrap_or_default())
                    } else {
                        light
                    },
                })
            }
            _ => {
                return Err(CliError::Usage(
                    "give --spectral (measure the box) or --box-scene with --box-spots".into(),
                ))
            }
        },
        simulation: SimulationOptions {
            target_de: args.target_de,
            seed: args.seed,
            max_seconds: 600.0,
            image: (args.image_size > 0).then_some(ImageSpec {
                size: args.image_size,
                spp: args.image_spp,
            }),
        },
        display: DisplayOptions {
            screen: args.display,
            spot: Spec::new(args.spot.as_str()),
            model,
        },
        reproduction: ReproductionOptions {
            gamut: args.gamut,
            mirror: !args.no_mirror,
        },
        repeats: args.repeats,
        stage,
        resume: args.resume,
        unattended: args.unattended,
        run: RunOptions {
            stop_after: None,
            interrupt: Some(interrupt),
        },
    };
    // Before any stage runs: a real rig with nobody to ask is refused.
    let specs: Vec<&str> = match &opts.box_source {
        BoxSource::Measure(m) => vec![
            m.spectral.as_str(),
            m.spot.as_str(),
            opts.display.spot.as_str(),
        ],
        BoxSource::Existing { .. } => vec![opts.display.spot.as_str()],
    };
    metamer::session::attendance(&specs, args.unattended).map_err(super::rig::nobody_at_the_rig)?;
    let shown = StageProgress::default();
    let outcomes = run(&opts, &|p| shown.show(p));
    shown.finish();
    let given = match &opts.box_source {
        BoxSource::Existing { spots, .. } => Some(spots.as_path()),
        BoxSource::Measure(_) => None,
    };
    print_outcomes(&outcomes?, given);
    print_comparisons(&args.out);
    Ok(())
}

/// What the stages would read or open only after minutes of rendering and measuring: a
/// given box's scene and readings, and the instruments' specs, checked before any work.
fn check_inputs(args: &Args) -> CliResult {
    if let (Some(scene), Some(spots)) = (&args.box_scene, &args.box_spots) {
        Scene::load(scene)?;
        // The reader refuses readings no instrument takes (X = −1e308 made every stage run
        // and the validation draw an infinite colour difference).
        metamer::experiment::readings::read_readings(spots)?;
    }
    for spec in std::iter::once(&args.spot).chain(&args.spectral) {
        metamer_drivers::check_spec(spec)?;
    }
    Ok(())
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
                    eprintln!("{stage}: unchanged inputs, re-used");
                } else {
                    eprintln!("{stage}: running");
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
            Progress::Note(text) => match self.bar.borrow().as_ref() {
                Some(b) => b.println(format!("  {text}")),
                None => eprintln!("  {text}"),
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
pub(super) fn print_outcomes(outcomes: &[StageOutcome], given_box: Option<&Path>) {
    for o in outcomes {
        let (how, dir) = match given_box {
            Some(spots) if o.stage == Stage::Box => ("given", spots),
            _ => (if o.reused { "re-used" } else { "ran" }, o.dir.as_path()),
        };
        println!(
            "{:<14} {:<8} {:>8.1} s  {}",
            o.stage.name(),
            how,
            o.seconds,
            dir.display()
        );
    }
}

/// The validation's three comparisons in a line each, in the report's words, and where
/// the report is, when the validation stage has run.
pub(super) fn print_comparisons(dir: &Path) {
    let validation = dir.join(Stage::Validation.name());
    if let Ok(text) = std::fs::read_to_string(validation.join(FILE)) {
        if let Ok(v) = serde_json::from_str::<ValidationResult>(&text) {
            for c in [
                &v.display_vs_box,
                &v.simulation_vs_box,
                &v.display_vs_simulation,
            ] {
                println!("{}", c.summary());
            }
        }
    }
    let report = validation.join(HTML_FILE);
    if report.exists() {
        println!("report: {}", report.display());
    }
}
