//! `metamer characterize`: show and measure patches on a display, fit and verify a profile.

use std::io::{BufRead, IsTerminal, Write};
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

use clap::ValueEnum;
use metamer::display::characterize::finish::{finish, Provenance, Summary};
use metamer::display::characterize::log::refuse_existing;
use metamer::display::characterize::{
    default_grid_steps, MeasureOptions, Measured, Plan, PlanOptions, Session, DEFAULT_RAMP_STEPS,
};
use metamer::display::ModelKind;
use metamer::rig::ScreenSpec;
use metamer_drivers::{
    open_instrument, CalibrationOutcome, DriverError, Instrument, MeasureMode, Request, Speed,
};

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
    /// the ramp steps, so the grid holds the ramps' levels: 9³ = 729 patches by default).
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
    let plan = Plan::new(PlanOptions {
        ramp_steps: args.ramp_steps,
        repeats: args.repeats,
        grid_steps,
    })
    .map_err(|e| CliError::Usage(e.to_string()))?;
    if !args.resume {
        // Before a full-screen window or an instrument is opened for nothing.
        refuse_existing(&args.out)?;
    }

    let mut display = spec.open()?;
    for warning in display.warnings() {
        eprintln!("warning: {warning}");
    }
    let mut instrument =
        open_instrument(&args.instrument, display.stimulus()).map_err(|e| match e {
            DriverError::UnknownSpec { .. } | DriverError::BadSpecOption { .. } => {
                CliError::Usage(e.to_string())
            }
            e => CliError::from(e),
        })?;
    if display.stimulus().is_none() && args.instrument.starts_with("sim:") {
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
    calibrate(instrument.as_mut())?;
    let info = instrument.info();
    let mut session = Session::open(
        &args.out,
        plan,
        &spec.canonical(),
        &args.instrument,
        info.clone(),
        args.resume,
    )?;
    let total = session.plan().patches.len();
    if session.recovered > 0 || session.torn_bytes > 0 {
        eprintln!(
            "resuming: {} of {total} readings in {}{}",
            session.recovered,
            session.log_path().display(),
            if session.torn_bytes > 0 {
                format!(
                    " ({} bytes of a reading cut off by the interruption were set aside in log.torn.txt)",
                    session.torn_bytes
                )
            } else {
                String::new()
            }
        );
    }
    let display_description = display.describe();
    let missing = total - session.done();
    if missing > 0 && display.stimulus().is_none() {
        aim(display.as_mut())?;
    }
    let options = MeasureOptions {
        settle: args
            .settle_ms
            .map_or(display.default_settle(), Duration::from_millis),
        request: Request::default(),
        stop_after: args.stop_after,
        interrupt: Some(on_ctrl_c()),
    };

    let bar = indicatif::ProgressBar::new(total as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{bar:30} patch {pos}/{len} · {msg} · {elapsed} elapsed, about {eta} left",
        )
        .expect("valid template"),
    );
    bar.set_position(session.done() as u64);
    bar.reset_eta();
    let outcome = session.measure(display.as_mut(), instrument.as_mut(), &options, &mut |p| {
        bar.set_message(format!(
            "{} → Y {:.3} cd/m²",
            p.patch.label, p.reading.xyz[1]
        ));
        bar.set_position(p.done as u64);
    });
    bar.finish_and_clear();
    // The window goes before the (possibly slow) fit, so the user gets their screen back.
    drop(display);
    match outcome? {
        Measured::Stopped { missing } => {
            println!(
                "stopped with {missing} of {total} readings still to take; continue with --resume (log: {})",
                session.log_path().display()
            );
            return Ok(());
        }
        Measured::Interrupted { missing } => {
            return Err(CliError::Failed(
                format!(
                    "interrupted with {missing} of {total} readings still to take; the others are safe in {}: continue with --resume",
                    session.log_path().display()
                )
                .into(),
            ));
        }
        Measured::Complete => {}
    }
    let readings = session
        .complete_readings()
        .expect("a complete session has every reading");
    let summary = finish(
        &args.out,
        session.log_path(),
        &readings,
        model,
        &Provenance {
            display: &spec.canonical(),
            display_description: &display_description,
            instrument: &args.instrument,
            instrument_info: &info,
        },
    )?;
    print_summary(&summary)?;
    Ok(())
}

/// Set by the first Ctrl-C; the session stops before its next patch (the readings are on
/// disk already). A second Ctrl-C ends the process at once.
static INTERRUPTED: std::sync::OnceLock<Arc<AtomicBool>> = std::sync::OnceLock::new();

extern "C" fn ctrl_c(_: libc::c_int) {
    if let Some(flag) = INTERRUPTED.get() {
        flag.store(true, Ordering::SeqCst);
    }
    // SAFETY: signal() is async-signal-safe (POSIX.1-2008 §2.4.3); SIG_DFL is always valid.
    unsafe {
        libc::signal(libc::SIGINT, libc::SIG_DFL);
    }
}

fn on_ctrl_c() -> Arc<AtomicBool> {
    let flag = INTERRUPTED
        .get_or_init(|| Arc::new(AtomicBool::new(false)))
        .clone();
    // SAFETY: the handler only stores to an atomic and resets the disposition, both
    // async-signal-safe; the flag is initialised before the handler is installed.
    unsafe {
        libc::signal(
            libc::SIGINT,
            ctrl_c as extern "C" fn(libc::c_int) as libc::sighandler_t,
        );
    }
    flag
}

/// Runs the instrument's calibration negotiation, asking the user for each condition.
fn calibrate(instrument: &mut dyn Instrument) -> Result<(), CliError> {
    // Instruments ask for at most a few conditions in a row (dark, then white tile); more
    // means the user's action did not satisfy it.
    for _ in 0..5 {
        let Some(condition) = instrument.calibration_needed(MeasureMode::Emissive)? else {
            return Ok(());
        };
        prompt(&format!(
            "calibration: {}, then press Enter",
            condition.prompt()
        ))?;
        if instrument.calibrate(MeasureMode::Emissive, &condition)? == CalibrationOutcome::Done {
            return Ok(());
        }
    }
    Err(CliError::Failed(
        "the instrument still asks for calibration after five attempts".into(),
    ))
}

/// Shows white and lets the user aim the instrument (on a real screen only).
fn aim(display: &mut dyn metamer::rig::Screen) -> Result<(), CliError> {
    display.show([255; 3])?;
    prompt(&format!(
        "aim the instrument at the middle of the white {} and press Enter",
        display.describe()
    ))
}

fn prompt(text: &str) -> Result<(), CliError> {
    if !std::io::stdin().is_terminal() {
        // Unattended (scripts, CI): nobody can act on a prompt, go on.
        return Ok(());
    }
    eprint!("{text} ");
    std::io::stderr().flush()?;
    let mut line = String::new();
    std::io::stdin().lock().read_line(&mut line)?;
    Ok(())
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
