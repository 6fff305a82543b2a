//! `metamer spot`: spot readings from an instrument (real, replayed or simulated), with the
//! instrument's calibrations negotiated at the terminal.

use std::path::PathBuf;

use clap::ValueEnum;
use metamer::spot::{self, SpotEvent, SpotRequest, SpotRunError};
use metamer::validation::readings::spot_line;
use metamer_drivers::{MeasureMode, Reading, Spec, Speed};

use super::{CliError, CliResult};

#[derive(Clone, Copy, ValueEnum)]
enum SpeedArg {
    /// The instrument's short response (CS-100A ≈100 ms).
    Fast,
    /// The long response for dark or flickering targets (CS-100A ≈400 ms).
    Slow,
}

#[derive(Clone, Copy, ValueEnum)]
enum ModeArg {
    /// Light from a source: XYZ in cd/m².
    Emissive,
    /// A surface under the instrument's lamp: XYZ with Y = 100 for white (D65).
    Reflective,
    /// Light falling on the diffuser: XYZ in lux.
    Ambient,
}

#[derive(clap::Args)]
pub struct Args {
    /// cs100a:PORT (e.g. cs100a:/dev/ttyUSB0), i1pro[:SERIAL], replay:FILE.jsonl, sim:cs100a
    /// or sim:i1pro (options: sim:i1pro?time_scale=0.01&seed=N&noise=off&rev=d|e).
    #[arg(long, value_name = "SPEC")]
    instrument: String,
    /// What to measure.
    #[arg(long, value_enum, default_value = "emissive")]
    mode: ModeArg,
    /// Response speed of instruments that have one (the CS-100A); default: the
    /// instrument's (fast).
    #[arg(long, value_enum)]
    speed: Option<SpeedArg>,
    /// Integration time in seconds, or auto, for instruments that have one (the i1Pro);
    /// default: auto.
    #[arg(long, value_name = "S")]
    integration: Option<String>,
    /// Number of readings.
    #[arg(long, default_value_t = 1, value_name = "N")]
    count: u32,
    /// One JSON object per reading per line.
    #[arg(long)]
    json: bool,
    /// Write the readings' spectra to this CSV (nm and one column per reading).
    #[arg(long, value_name = "FILE.csv")]
    spectrum: Option<PathBuf>,
    /// Replace the --spectrum file if it exists.
    #[arg(long)]
    force: bool,
    /// Record the exchange with the instrument to this new transcript (never overwritten).
    #[arg(long, value_name = "FILE.jsonl")]
    record: Option<PathBuf>,
    /// Nobody is at the instrument: calibrate and read without asking. A real instrument
    /// without a terminal on stdin needs it (an i1Pro would calibrate wherever it points).
    #[arg(long)]
    unattended: bool,
}

pub fn run(args: Args) -> CliResult {
    let mode = match args.mode {
        ModeArg::Emissive => MeasureMode::Emissive,
        ModeArg::Reflective => MeasureMode::Reflective,
        ModeArg::Ambient => MeasureMode::Ambient,
    };
    let request = SpotRequest {
        instrument: Spec::new(args.instrument),
        mode,
        speed: args.speed.map(|s| match s {
            SpeedArg::Fast => Speed::Fast,
            SpeedArg::Slow => Speed::Slow,
        }),
        integration: args.integration,
        count: args.count,
        spectrum: args.spectrum,
        force: args.force,
        record: args.record,
        unattended: args.unattended,
    };
    let json = args.json;
    spot::run(&request, &mut |event| match event {
        SpotEvent::Opened(info) if !json => Ok(outln!("{} on {}", info.model, info.connection)?),
        SpotEvent::Opened(_) => Ok(()),
        SpotEvent::Reading { n, reading } => {
            if json {
                outln!("{}", spot_line(reading))?;
            } else {
                outln!("{}", human_line(n, mode, reading))?;
            }
            // Each reading is shown as it arrives: a later failure must not hide earlier ones.
            Ok(super::console::flush()?)
        }
        SpotEvent::Note(text) => {
            errln!("note: {text}")?;
            Ok(())
        }
        SpotEvent::Stopped { done, of } => {
            errln!("stopped at your request after {done} of {of} readings")?;
            Ok(())
        }
    })
    .map_err(|e| match e {
        SpotRunError::Count => CliError::Usage("--count must be at least 1".into()),
        SpotRunError::NotSpectral { model } => CliError::Usage(format!(
            "--spectrum: the {model} measures no spectrum (a colorimeter); leave --spectrum out"
        )),
        SpotRunError::NoSpectrum { model } => CliError::Usage(format!(
            "--spectrum: the {model} returned readings without a spectrum"
        )),
        SpotRunError::NoIntegration { instrument } => CliError::Usage(format!(
            "--integration: the {instrument} has no integration time to set"
        )),
        SpotRunError::BadIntegration { value, message } => {
            CliError::Usage(format!("--integration {value}: {message}"))
        }
        e if e.is_bad_request() => CliError::Usage(e.to_string()),
        SpotRunError::Nobody(e) => super::rig::nobody_at_the_rig(e),
        SpotRunError::Output(e) => CliError::from(e),
        e => CliError::from(e),
    })?;
    Ok(())
}

fn human_line(i: u32, mode: MeasureMode, r: &Reading) -> String {
    // Five significant digits: one more than the CS-100A sends, so nothing it reports is
    // rounded away; "—" for what it did not measure.
    let sig = |v: f64| {
        if !v.is_finite() {
            return "—".to_string();
        }
        let digits = if v == 0.0 {
            0
        } else {
            (4 - v.abs().log10().floor() as i32).clamp(0, 8) as usize
        };
        format!("{v:.digits$}")
    };
    // Chromaticity with the four decimals the meter sends.
    let chroma = |v: f64| {
        if v.is_finite() {
            format!("{v:.4}")
        } else {
            "—".to_string()
        }
    };
    let unit = match mode {
        MeasureMode::Emissive => " cd/m²",
        MeasureMode::Ambient => " lx",
        MeasureMode::Reflective => " (white = 100)",
    };
    let [x, y, lum] = r.xyy;
    let mut line = format!(
        "#{i}  Y {}{unit}  x {}  y {}  XYZ {} {} {}",
        sig(lum),
        chroma(x),
        chroma(y),
        sig(r.xyz[0]),
        sig(r.xyz[1]),
        sig(r.xyz[2])
    );
    if let (Some(t), Some(_)) = (r.integration_s, &r.spectrum) {
        line.push_str(&format!("  ({} s)", sig(t)));
    }
    for flag in &r.flags {
        line.push_str(&format!("  [{}]", flag.name().replace('_', " ")));
    }
    line
}
