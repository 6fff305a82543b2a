//! `metamer characterize`: show and measure patches on a display, fit and verify a profile.

use std::path::PathBuf;
use std::time::Duration;

use clap::ValueEnum;
use metamer::display::characterize::adaptive::{read_targets, Adaptive, AdaptiveError, StopReason};
use metamer::display::characterize::finish::Summary;
use metamer::display::characterize::{
    self, Attend, CharacterizeError, Listener, Outcome, PlanError, PlanOptions, Request,
    SimulatedMeter, DEFAULT_RAMP_STEPS,
};
use metamer::display::ModelKind;
use metamer::rig::ScreenSpec;
use metamer::session::{on_ctrl_c, BarProgress, ProgressSink, RunOptions};
use metamer_drivers::{Spec, Speed};

use super::characterize_advice::{advice, left_to_do};
use super::plan_choice::{ModelChoice, PlanKind, RuleArgs};
use super::{CliError, CliResult};

#[derive(Clone, Copy, ValueEnum)]
enum SpeedArg {
    /// The instrument's short response (CS-100A ≈100 ms).
    Fast,
    /// The long response for dark or flickering targets (CS-100A ≈400 ms).
    Slow,
}

#[derive(clap::Args)]
pub struct Args {
    /// window (the first monitor), window:N (monitor N, from 0), virtual (= virtual:ips-lcd)
    /// or virtual:PRESET (ideal-crt, ips-lcd, wide-gamut-ccfl).
    #[arg(long, value_name = "DISPLAY")]
    display: ScreenSpec,
    /// cs100a:PORT, replay:FILE.jsonl, or sim:cs100a (options: sim:cs100a?time_scale=0.01).
    #[arg(long, value_name = "SPEC")]
    instrument: Spec,
    /// Levels per channel ramp, 0 and 255 included.
    #[arg(long, default_value_t = DEFAULT_RAMP_STEPS, value_name = "N")]
    ramp_steps: usize,
    /// Passes over all patches (readings of a patch are averaged).
    #[arg(long, default_value_t = 1, value_name = "K")]
    repeats: usize,
    /// Add an N×N×N grid of the drive cube to the fit patches (default: none; for --model lut
    /// 5, or the ramp steps when fewer: 5³ = 125 grid patches by default).
    #[arg(long, value_name = "N")]
    grid_steps: Option<usize>,
    /// Wait between showing a patch and measuring it (default: 500 for a window, 0 for a
    /// virtual display).
    #[arg(long, value_name = "MS")]
    settle_ms: Option<u64>,
    /// plcc (paper Eq. 9), plcc-gamma, plvc, gog, gogo, lut, matrix-lsq, shaper-matrix, or
    /// (--plan adaptive only) auto: chosen by cross-validation as `fit --model auto` does.
    #[arg(long, default_value = "plcc", value_name = "MODEL")]
    model: ModelChoice,
    /// fixed: ramps, the model's grid and 48 held-out colours. adaptive: a first pass (ramps,
    /// a 3³ grid), then batches where the candidate models disagree most at the --targets,
    /// until the predicted ΔE*ab there is below --stop-de or --max-readings are taken; the
    /// held-out patches at and around the targets.
    #[arg(long, value_enum, default_value = "fixed")]
    plan: PlanKind,
    /// adaptive only: the colours to reproduce, a CSV with the header X,Y,Z (cd/m²), the
    /// file `reproduce --xyz` takes.
    #[arg(long, value_name = "TARGETS.csv")]
    targets: Option<PathBuf>,
    #[command(flatten)]
    rule: RuleArgs,
    /// Response speed of instruments that have one (the CS-100A); default: the
    /// instrument's (fast).
    #[arg(long, value_enum)]
    speed: Option<SpeedArg>,
    /// Continue the session whose log is in DIR (after a crash, Ctrl-C or a pulled cable).
    #[arg(long)]
    resume: bool,
    /// Output directory: log.jsonl, profile.json, readings.ti3, report.svg, summary.json.
    #[arg(short = 'o', long = "out", value_name = "DIR")]
    out: PathBuf,
    /// Replace a profile, .ti3, report or summary already in DIR (a resumed session
    /// replaces its own without it).
    #[arg(long)]
    force: bool,
    /// Nobody is at the rig: take every reading without asking anyone to aim or calibrate
    /// the instrument. A real instrument without a terminal on stdin needs it.
    #[arg(long)]
    unattended: bool,
    /// The operator's time per placement the budget printed before the first reading
    /// assumes, seconds (default 30: a person's half minute to place, aim and confirm).
    #[arg(long, value_name = "S", value_parser = super::parse_placement_seconds)]
    placement_seconds: Option<f64>,
    /// Stop after N new readings, as if interrupted (tests; splitting a long session).
    #[arg(long, value_name = "N", hide = true)]
    stop_after: Option<usize>,
}

pub fn run(args: Args) -> CliResult {
    let auto = args.model == ModelChoice::Auto;
    let model = match args.model {
        ModelChoice::Auto if args.plan == PlanKind::Fixed => {
            return Err(CliError::Usage(
                "--model auto chooses the model between batches: it needs --plan adaptive \
                 (for the fixed plan, fit the readings.ti3 with `metamer fit --model auto`)"
                    .into(),
            ));
        }
        ModelChoice::Auto => ModelKind::Lut,
        ModelChoice::Kind(kind) => kind,
    };
    let adaptive = match (args.rule.rule(args.plan)?, &args.targets) {
        (None, None) => None,
        (None, Some(_)) => {
            return Err(CliError::Usage(
                "--targets names the colours an adaptive plan measures around: it needs --plan adaptive"
                    .into(),
            ))
        }
        (Some(_), None) => {
            return Err(CliError::Usage(
                "--plan adaptive needs --targets TARGETS.csv (X,Y,Z in cd/m²)".into(),
            ))
        }
        (Some(rule), Some(file)) => {
            if args.grid_steps.is_some() {
                return Err(CliError::Usage(
                    "--grid-steps sets the fixed plan's grid; the adaptive plan's first pass has a 3³ grid"
                        .into(),
                ));
            }
            Some(Adaptive {
                rule,
                targets: read_targets(file).map_err(|e| CliError::Failed(e.into()))?,
                auto,
            })
        }
    };
    let request = Request {
        out: args.out.clone(),
        screen: args.display,
        virtual_white_cd_m2: None,
        instrument: args.instrument,
        speed: args.speed.map(|s| match s {
            SpeedArg::Fast => Speed::Fast,
            SpeedArg::Slow => Speed::Slow,
        }),
        plan: PlanOptions::for_model(model, args.ramp_steps, args.repeats, args.grid_steps),
        adaptive,
        model,
        settle: args.settle_ms.map(Duration::from_millis),
        resume: args.resume,
        force: args.force,
        attend: Attend::Terminal {
            unattended: args.unattended,
        },
        simulated_meter: SimulatedMeter::Warn,
        run: RunOptions {
            stop_after: args.stop_after,
            interrupt: Some(on_ctrl_c()),
            placement_s: args.placement_seconds,
        },
    };
    let outcome = characterize::characterize(&request, &mut Printer(None)).map_err(refusal)?;
    match (&outcome, left_to_do(&outcome)) {
        (Outcome::Finished(summary), _) => print_summary(summary),
        (_, Some(text)) if outcome.is_interrupted() => Err(CliError::Failed(text.into())),
        (_, text) => {
            outln!("{}", text.unwrap_or_default())?;
            Ok(())
        }
    }
}

/// Notes and warnings on stderr, the session's progress as a bar.
struct Printer(Option<BarProgress>);

impl Listener for Printer {
    fn note(&mut self, text: &str) {
        super::console::reported_at_exit(errln!("note: {text}"));
    }
    fn warning(&mut self, text: &str) {
        super::console::reported_at_exit(errln!("warning: {text}"));
    }
    fn progress(&mut self, attended: bool) -> &mut dyn ProgressSink {
        self.0.insert(BarProgress::new("patch").attended(attended))
    }
}

/// The library's refusal in this command's words: its flags' errors are usage errors.
fn refusal(e: CharacterizeError) -> CliError {
    match e {
        CharacterizeError::Plan(e) => CliError::Usage(plan_usage(&e)),
        CharacterizeError::Adaptive(e @ AdaptiveError::Cap { .. }) => {
            CliError::Usage(format!("--max-readings: {e}"))
        }
        CharacterizeError::NobodyAtTheRig(e) => super::rig::nobody_at_the_rig(e),
        CharacterizeError::Instrument(e) if e.is_spec() => CliError::Usage(e.to_string()),
        e => match advice(&e) {
            Some(t) => CliError::Failed(t.into()),
            None => CliError::from(e),
        },
    }
}

/// A plan option's error in the words of this command's flags.
fn plan_usage(e: &PlanError) -> String {
    match e {
        PlanError::RampSteps(n) => format!(
            "--ramp-steps must be between 2 and 256 (levels per ramp, 0 and 255 included), got {n}"
        ),
        PlanError::Repeats(n) => format!("--repeats must be at least 1, got {n}"),
        PlanError::GridSteps(n) => {
            format!("--grid-steps must be 0 (no grid) or between 2 and 64, got {n}")
        }
    }
}

fn print_summary(s: &Summary) -> Result<(), CliError> {
    let v = &s.verification;
    outln!(
        "measured {} readings of {} with {} ({})",
        s.readings,
        s.display,
        s.instrument_info.model,
        s.instrument
    )?;
    outln!(
        "white {:.2} cd/m², black {:.3} cd/m²",
        s.white_xyz[1],
        s.black_xyz[1]
    )?;
    outln!(
        "model {}: fit on {} patches, ΔE00 mean {:.2}, max {:.2}",
        s.model,
        s.fit_patches,
        s.fit_residuals.mean_de00,
        s.fit_residuals.max_de00
    )?;
    outln!(
        "verification on {} held-out patches: ΔE00 mean {:.2}, p95 {:.2}, max {:.2}",
        v.patches.len(),
        v.de00.mean,
        v.de00.p95,
        v.de00.max
    )?;
    if let Some(a) = &s.adaptive {
        outln!(
            "adaptive plan: {} fit readings in {} batch{} after the first pass, model {}; \
             predicted ΔE*ab at the worst of {} targets {:.2} ({})",
            a.fit_readings,
            a.batches.len(),
            if a.batches.len() == 1 { "" } else { "es" },
            s.model,
            a.targets,
            a.predicted_de,
            match a.stop {
                StopReason::Converged => format!("below {}", a.rule.stop_de),
                StopReason::Cap => format!("stopped at the cap of {}", a.rule.max_readings),
                StopReason::NothingLeft => "no patch near the targets left to measure".into(),
            }
        )?;
    }
    // The verdict already names every failed assumption.
    outln!("verdict: {}", s.verdict)?;
    outln!(
        "wrote {}, {}, {}, {} (log {})",
        s.files.profile.display(),
        s.files.ti3.display(),
        s.files.report.display(),
        s.files.summary.display(),
        s.files.log.display()
    )?;
    Ok(())
}
