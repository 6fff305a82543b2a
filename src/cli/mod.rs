//! The command line: argument parsing and error presentation only. Each command lives in
//! its own file and calls the library; nothing in the library depends on this module.

use std::process::ExitCode;

use clap::{Parser, Subcommand};

mod budget;
mod characterize;
mod color;
mod devices;
mod experiment;
mod export;
mod fit;
mod lab;
mod light;
mod measure_box;
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
    let cli = Cli::parse();
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
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(CliError::Usage(message)) => {
            eprintln!("error: {message}");
            ExitCode::from(2)
        }
        Err(CliError::Failed(error)) => {
            eprintln!("error: {error}");
            if needs_force(&*error) {
                eprintln!("  add --force to replace it");
            }
            let mut shown = error.to_string();
            let mut source = error.source();
            while let Some(cause) = source {
                let text = cause.to_string();
                // thiserror messages often quote their source already; say each thing once.
                if !shown.contains(&text) {
                    eprintln!("  caused by: {text}");
                    shown.push_str(&text);
                }
                source = cause.source();
            }
            ExitCode::from(1)
        }
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
