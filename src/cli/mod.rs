//! The command line: argument parsing and error presentation only. Each command lives in
//! its own file and calls the library; nothing in the library depends on this module.

use std::process::ExitCode;

use clap::{Parser, Subcommand};
use metamer::output::console;

/// A line on standard output: `Err` (never a panic) when it cannot be written, as behind a
/// full disk. Every command prints through these macros (see `metamer::output::console`).
macro_rules! outln {
    () => { metamer::output::console::out_fmt(format_args!("")) };
    ($($arg:tt)*) => { metamer::output::console::out_fmt(format_args!($($arg)*)) };
}

/// Text on standard output without a newline.
macro_rules! out {
    ($($arg:tt)*) => { metamer::output::console::out_part(format_args!($($arg)*)) };
}

/// A line on standard error, as `outln!`.
macro_rules! errln {
    () => { metamer::output::console::err_fmt(format_args!("")) };
    ($($arg:tt)*) => { metamer::output::console::err_fmt(format_args!($($arg)*)) };
}

mod budget;
mod characterize;
mod characterize_advice;
mod color;
mod devices;
mod experiment;
mod export;
mod fit;
mod lab;
mod light;
mod measure_box;
mod plan_choice;
mod render;
mod reproduce;
mod rig;
mod simulate;
mod spot;
mod validate;
mod verify;

/// metamer: prove a rendering is colour-true.
#[derive(Parser)]
#[command(name = "metamer", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Colour science on spectra and colour differences.
    Color(color::Args),
    /// Serial ports and known USB/HID instruments on this machine.
    Devices(devices::Args),
    /// Spot readings from an instrument.
    Spot(spot::Args),
    /// Render the validation box: spot readings, images, convergence charts.
    Render(render::Args),
    /// Fit a display model to measured patches.
    Fit(fit::Args),
    /// Check a display profile against measured patches (e.g. ones it was not fitted to).
    Verify(verify::Args),
    /// XYZ targets or images to display drive values through a display profile.
    Reproduce(reproduce::Args),
    /// Show and measure patches on a display, fit and verify a profile.
    Characterize(characterize::Args),
    /// Measure the validation box: tiles, fall-off, materials and spots, into a scene.
    MeasureBox(measure_box::Args),
    /// Display models' reproduction error against the number of measured patches.
    Budget(budget::Args),
    /// The paper's whole chain, stage by stage: box, simulation, display, reproduction,
    /// display spots, validation.
    Experiment(experiment::Args),
    /// The experiment on the simulated rig: the box measured, simulated, shown, validated.
    Lab(lab::Args),
    /// The light source's distribution: fit it to fall-off readings, export and read IES/LDT.
    Light(light::Args),
    /// Box vs display (vs simulation) readings in CIELAB with uncertainty: table and report.
    Validate(validate::Args),
    /// Serve a simulated instrument to other programs (a CS-100A on a pseudo-terminal).
    Simulate(simulate::Args),
    /// Write a scene for another renderer (Mitsuba 3, pbrt-v4), with a README beside it.
    Export(export::Args),
}

/// A command's failure: usage errors exit 2, data and device errors exit 1.
pub enum CliError {
    Usage(String),
    Failed(Box<dyn std::error::Error + Send + Sync>),
}

impl<E: std::error::Error + Send + Sync + 'static> From<E> for CliError {
    fn from(e: E) -> Self {
        CliError::Failed(Box::new(e))
    }
}

pub type CliResult = Result<(), CliError>;

pub fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => return clap_exit(&e),
    };
    let result = match cli.command {
        Command::Color(args) => color::run(args),
        Command::Devices(args) => devices::run(args),
        Command::Spot(args) => spot::run(args),
        Command::Render(args) => render::run(args),
        Command::Fit(args) => fit::run(args),
        Command::Verify(args) => verify::run(args),
        Command::Reproduce(args) => reproduce::run(args),
        Command::Characterize(args) => characterize::run(args),
        Command::Experiment(args) => experiment::run_cli(args),
        Command::Lab(args) => lab::run(args),
        Command::MeasureBox(args) => measure_box::run(args),
        Command::Budget(args) => budget::run(args),
        Command::Simulate(args) => simulate::run(args),
        Command::Light(args) => light::run(args),
        Command::Validate(args) => validate::run(args),
        Command::Export(args) => export::run(args),
    };
    // A write that failed inside a callback is remembered rather than returned; an
    // unflushed last line fails only here.
    let result = match (result, console::flush()) {
        (Ok(()), Err(e)) => Err(CliError::from(e)),
        (Ok(()), Ok(())) => match console::failure() {
            Some(e) => Err(CliError::from(e)),
            None => Ok(()),
        },
        (result, _) => result,
    };
    report(result)
}

/// The exit code of a command's result, with its error on standard error: one line, then
/// the hint `--force` lifts and causes that the line does not already say. If standard
/// error itself cannot be written there is nobody to tell; the exit code still says it.
fn report(result: CliResult) -> ExitCode {
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(CliError::Usage(message)) => {
            let _ = errln!("error: {message}");
            ExitCode::from(2)
        }
        Err(CliError::Failed(error)) => {
            let _ = errln!("error: {error}");
            if needs_force(&*error) {
                let _ = errln!("  add --force to replace it");
            }
            let mut shown = error.to_string();
            let mut source = error.source();
            while let Some(cause) = source {
                let text = cause.to_string();
                // thiserror messages often quote their source already; say each thing once.
                if !shown.contains(&text) {
                    let _ = errln!("  caused by: {text}");
                    shown.push_str(&text);
                }
                source = cause.source();
            }
            ExitCode::from(1)
        }
    }
}

/// clap's help, version or usage error. clap prints help and version on standard output and
/// exits 0 even when that write fails, so the write's failure is reported here instead.
fn clap_exit(e: &clap::Error) -> ExitCode {
    let code = e.exit_code();
    let stream = if e.use_stderr() {
        console::Stream::Stderr
    } else {
        console::Stream::Stdout
    };
    let written = e.print().and_then(|()| match stream {
        console::Stream::Stdout => std::io::Write::flush(&mut std::io::stdout()),
        console::Stream::Stderr => Ok(()),
    });
    match written {
        Ok(()) => ExitCode::from(u8::try_from(code).unwrap_or(1)),
        Err(source) => report(Err(CliError::from(console::ConsoleError {
            stream,
            source,
        }))),
    }
}

/// Whether the failure is an output the command refused to overwrite, which `--force` lifts.
fn needs_force(error: &(dyn std::error::Error + 'static)) -> bool {
    let mut e = Some(error);
    while let Some(cause) = e {
        if let Some(o) = cause.downcast_ref::<metamer::output::OutputError>() {
            return o.needs_force();
        }
        e = cause.source();
    }
    false
}

/// Parses `--placement-seconds` for clap: a usage error when out of range.
pub fn parse_placement_seconds(s: &str) -> Result<f64, String> {
    metamer::session::budget::placement_s(s).map_err(|e| e.to_string())
}

/// Parses `X,Y,Z` (three finite numbers) for clap.
pub fn parse_triple(s: &str) -> Result<[f64; 3], String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    if parts.len() != 3 {
        return Err(format!(
            "expected three comma-separated numbers X,Y,Z, got '{s}'"
        ));
    }
    let mut out = [0.0; 3];
    for (o, p) in out.iter_mut().zip(&parts) {
        *o = p
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| format!("'{p}' is not a number"))?;
    }
    Ok(out)
}
