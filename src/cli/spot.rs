//! `metamer spot`: spot readings from an instrument (real, replayed or simulated).

use std::io::Write;
use std::path::PathBuf;

use clap::ValueEnum;
use metamer_drivers::{open_instrument_with, DriverError, OpenOptions, Reading, Request, Speed};

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
    /// cs100a:PORT (e.g. cs100a:/dev/ttyUSB0), replay:FILE.jsonl, or sim:cs100a
    /// (options: sim:cs100a?time_scale=0.01&seed=N&noise=off).
    #[arg(long, value_name = "SPEC")]
    instrument: String,
    /// Response speed of instruments that have one (the CS-100A); default: the
    /// instrument's (fast).
    #[arg(long, value_enum)]
    speed: Option<SpeedArg>,
    /// Number of readings.
    #[arg(long, default_value_t = 1, value_name = "N")]
    count: u32,
    /// One JSON object per reading per line.
    #[arg(long)]
    json: bool,
    /// Record the exchange with the instrument to this new transcript (never overwritten).
    #[arg(long, value_name = "FILE.jsonl")]
    record: Option<PathBuf>,
}

pub fn run(args: Args) -> CliResult {
    if args.count == 0 {
        return Err(CliError::Usage("--count must be at least 1".into()));
    }
    if let Some(path) = &args.record {
        if path.exists() {
            return Err(CliError::Usage(format!(
                "{} exists; a recording is never overwritten, choose another file name",
                path.display()
            )));
        }
    }
    let options = OpenOptions {
        stimulus: None,
        record: args.record.clone(),
    };
    let mut instrument = open_instrument_with(&args.instrument, &options).map_err(|e| match e {
        DriverError::UnknownSpec { .. } | DriverError::BadSpecOption { .. } => {
            CliError::Usage(e.to_string())
        }
        e => CliError::from(e),
    })?;
    if let Some(speed) = args.speed {
        let speed = match speed {
            SpeedArg::Fast => Speed::Fast,
            SpeedArg::Slow => Speed::Slow,
        };
        instrument.set_option("speed", speed.name())?;
    }
    let request = Request::default();
    let info = instrument.info();
    let mut out = std::io::stdout().lock();
    if !args.json {
        writeln!(out, "{} on {}", info.model, info.connection)?;
    }
    for i in 1..=args.count {
        let reading = instrument.measure(&request)?;
        if args.json {
            writeln!(out, "{}", json_line(&reading))?;
        } else {
            writeln!(out, "{}", human_line(i, &reading))?;
        }
        // Each reading is shown as it arrives: a later failure must not hide earlier ones.
        out.flush()?;
    }
    Ok(())
}

/// `{"XYZ":[X,Y,Z],"xyY":[x,y,Y],"flags":[…],"instrument":"cs100a"}`; values the instrument
/// did not measure are null.
fn json_line(r: &Reading) -> String {
    // A struct, not json!(), to keep the documented key order.
    #[derive(serde::Serialize)]
    struct Line<'a> {
        #[serde(rename = "XYZ")]
        xyz: [f64; 3],
        #[serde(rename = "xyY")]
        xyy: [f64; 3],
        flags: Vec<&'static str>,
        instrument: &'a str,
    }
    let line = Line {
        xyz: r.xyz,
        xyy: r.xyy,
        flags: r.flags.iter().map(|f| f.name()).collect(),
        instrument: &r.instrument,
    };
    serde_json::to_string(&line).expect("a reading serializes")
}

fn human_line(i: u32, r: &Reading) -> String {
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
    let [x, y, lum] = r.xyy;
    let mut line = format!(
        "#{i}  Y {} cd/m²  x {}  y {}  XYZ {} {} {}",
        sig(lum),
        chroma(x),
        chroma(y),
        sig(r.xyz[0]),
        sig(r.xyz[1]),
        sig(r.xyz[2])
    );
    for flag in &r.flags {
        line.push_str(&format!("  [{}]", flag.name().replace('_', " ")));
    }
    line
}
