//! `metamer characterize`: show and measure patches on a display, fit and verify a profile.

use std::io::Write;
use std::path::PathBuf;
use std::time::Duration;

use clap::ValueEnum;
use metamer::display::characterize::finish::{files, Summary};
use metamer::display::characterize::{
    self, default_grid_steps, log_path, plan_advice, CharacterizeError, Options, Outcome, Plan,
    PlanError, PlanOptions, DEFAULT_RAMP_STEPS,
};
use metamer::display::ModelKind;
use metamer::output::OutputPolicy;
use metamer::rig::ScreenSpec;
use metamer::session::{
    attendance, on_ctrl_c, refuse_existing, Attendance, BarProgress, RunOptions, SessionError,
};
use metamer_drivers::{DriverError, Spec, Speed};

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
    display: String,
    /// cs100a:PORT, replay:FILE.jsonl, or sim:cs100a (options: sim:cs100a?time_scale=0.01).
    #[arg(long, value_name = "SPEC")]
    instrument: String,
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
    /// plcc (paper Eq. 9), plcc-gamma, gog, gogo, lut or matrix-lsq.
    #[arg(long, default_value = "plcc", value_name = "MODEL")]
    model: String,
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
    /// Stop after N new readings, as if interrupted (tests; splitting a long session).
    #[arg(long, value_name = "N", hide = true)]
    stop_after: Option<usize>,
}

pub fn run(args: Args) -> CliResult {
    let spec = ScreenSpec::parse(&args.display).map_err(|e| CliError::Usage(e.to_string()))?;
    let model: ModelKind = args.model.parse().map_err(CliError::Usage)?;
    let grid_steps = args
        .grid_steps
        .unwrap_or(default_grid_steps(model, args.ramp_steps));
    let plan = PlanOptions {
        ramp_steps: args.ramp_steps,
        repeats: args.repeats,
        grid_steps,
    };
    let planned = Plan::new(plan).map_err(|e| CliError::Usage(plan_usage(&e)))?;
    if let Some(advice) = plan_advice(&planned) {
        eprintln!("note: {advice}");
    }
    // Before anything is opened: a real meter with nobody to aim it is refused.
    let attended =
        attendance(&[&args.instrument], args.unattended).map_err(super::rig::nobody_at_the_rig)?;
    if !args.resume {
        // Before a full-screen window or an instrument is opened for nothing.
        refuse_existing(&log_path(&args.out))
            .map_err(|e| advised(CharacterizeError::Session(SessionError::Journal(e))))?;
        // Files another session left in the directory (a new directory has none).
        if args.out.is_dir() {
            let out = OutputPolicy::new(args.force);
            for f in files(&args.out, &log_path(&args.out)).outputs() {
                out.check(f)?;
            }
        }
    }

    let mut display = spec.open()?;
    for warning in display.warnings() {
        eprintln!("warning: {warning}");
    }
    let meter = Spec::new(args.instrument.as_str());
    let mut instrument = meter.open(display.stimulus()).map_err(|e| match e {
        DriverError::UnknownSpec { .. } | DriverError::BadSpecOption { .. } => {
            CliError::Usage(e.to_string())
        }
        e => CliError::from(e),
    })?;
    if display.stimulus().is_none() && meter.is_simulated() {
        eprintln!(
            "warning: a simulated instrument cannot see a real screen; it measures its own fixed light"
        );
    }
    if let Some(speed) = args.speed {
        let speed = match speed {
            SpeedArg::Fast => Speed::Fast,
            SpeedArg::Slow => Speed::Slow,
        };
        instrument.set_option("speed", speed.name())?;
    }
    let options = Options {
        dir: args.out.clone(),
        plan,
        model,
        instrument: args.instrument.clone(),
        settle: args.settle_ms.map(Duration::from_millis),
        resume: args.resume,
        force: args.force,
        run: RunOptions {
            stop_after: args.stop_after,
            interrupt: Some(on_ctrl_c()),
        },
    };
    let outcome = characterize::run(
        &options,
        display.as_mut(),
        instrument.as_mut(),
        attended.operator().as_mut(),
        &mut BarProgress::new("patch").attended(attended == Attendance::Terminal),
    )
    .map_err(advised)?;
    match (&outcome, outcome.left_to_do()) {
        (Outcome::Finished(summary), _) => print_summary(summary),
        (_, Some(text)) if outcome.is_interrupted() => Err(CliError::Failed(text.into())),
        (_, text) => {
            println!("{}", text.unwrap_or_default());
            Ok(())
        }
    }
}

/// The library's error with its advice in this command's flags, where it has one.
fn advised(e: CharacterizeError) -> CliError {
    match e.advice() {
        Some(t) => CliError::Failed(t.into()),
        None => CliError::from(e),
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
    let mut out = std::io::stdout().lock();
    let v = &s.verification;
    writeln!(
        out,
        "measured {} readings of {} with {} ({})",
        s.readings, s.display, s.instrument_info.model, s.instrument
    )?;
    writeln!(
        out,
        "white {:.2} cd/m², black {:.3} cd/m²",
        s.white_xyz[1], s.black_xyz[1]
    )?;
    writeln!(
        out,
        "model {}: fit on {} patches, ΔE00 mean {:.2}, max {:.2}",
        s.model, s.fit_patches, s.fit_residuals.mean_de00, s.fit_residuals.max_de00
    )?;
    writeln!(
        out,
        "verification on {} held-out patches: ΔE00 mean {:.2}, p95 {:.2}, max {:.2}",
        v.patches.len(),
        v.mean,
        v.p95,
        v.max
    )?;
    // The verdict already names every failed assumption.
    writeln!(out, "verdict: {}", s.verdict)?;
    writeln!(
        out,
        "wrote {}, {}, {}, {} (log {})",
        s.files.profile.display(),
        s.files.ti3.display(),
        s.files.report.display(),
        s.files.summary.display(),
        s.files.log.display()
    )?;
    Ok(())
}
