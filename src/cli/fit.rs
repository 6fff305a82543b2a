//! `metamer fit`: fit a display model to measured patches, print its diagnostics and save
//! the profile.

use std::path::PathBuf;

use super::plan_choice::ModelChoice;
use super::{CliError, CliResult};
use metamer::display::icc::IccVersion;
use metamer::display::job::fit::{self, Event, Request};
use metamer::display::FitOptions;

#[derive(clap::Args)]
pub struct Args {
    /// Measured patches: ArgyllCMS `.ti3` (as dispread writes) or CSV `r,g,b,X,Y,Z`
    /// (drive 0–1, XYZ cd/m²).
    #[arg(long, value_name = "FILE")]
    measurements: PathBuf,
    /// Display model: plcc, plcc-gamma, gog, gogo, lut, matrix-lsq, shaper-matrix, or auto
    /// (k-fold cross-validation over the patches picks the model and prints why).
    #[arg(long, default_value = "plcc")]
    model: ModelChoice,
    /// auto only: the number of cross-validation folds.
    #[arg(long, default_value_t = 5)]
    folds: usize,
    /// plcc-gamma only: this exponent for every channel instead of fitting (the paper: 2.2).
    #[arg(long)]
    gamma: Option<f64>,
    /// The instrument's noise, ΔE00 (1σ) of one reading, so the verdict does not blame the
    /// display for it; by default estimated from repeated patches, if any.
    #[arg(long, value_name = "DE00")]
    noise: Option<f64>,
    /// Where to write the profile (JSON).
    #[arg(short = 'o', long = "output", value_name = "PROFILE.json")]
    output: PathBuf,
    /// Replace the output file if it exists (never one of the inputs).
    #[arg(long)]
    force: bool,
    /// Also write an ICC display profile: matrix/TRC for the matrix models, lut16
    /// A2B0/B2A0 tables for lut.
    #[arg(long, value_name = "OUT.icc")]
    icc: Option<PathBuf>,
    /// auto only: also draw each candidate's held-out error, the choice marked, as SVG.
    #[arg(long, value_name = "OUT.svg")]
    chart: Option<PathBuf>,
    /// The ICC version of --icc: 4 (default) or 2.4.
    #[arg(long, value_name = "4|2.4")]
    icc_version: Option<IccVersion>,
}

pub fn run(args: Args) -> CliResult {
    let request = Request {
        measurements: args.measurements.clone(),
        model: match args.model {
            ModelChoice::Auto => None,
            ModelChoice::Kind(kind) => Some(kind),
        },
        folds: args.folds,
        options: FitOptions {
            gamma: args.gamma,
            noise_de00: args.noise,
        },
        output: args.output.clone(),
        force: args.force,
        icc: args.icc.clone(),
        icc_version: args.icc_version,
        chart: args.chart.clone(),
    };
    let report = fit::run(&request, &mut |e| {
        super::console::reported_at_exit(print_event(e))
    })
    .map_err(|e| refusal(e, &args))?;
    if let Some(icc) = &report.icc {
        outln!(
            "ICC {} profile ({}) written to {}; read back, it follows the model to ΔE00 mean \
             {:.4}, max {:.4} over the {} patches",
            icc.summary.version,
            icc.summary.form,
            icc.path.display(),
            icc.forward.mean_de00,
            icc.forward.max_de00,
            icc.forward.points
        )?;
        if let Some(inverse) = &icc.inverse {
            outln!(
                "its B2A0 inverts the model to ΔE00 mean {:.4}, max {:.4} over the same patches",
                inverse.mean_de00,
                inverse.max_de00
            )?;
        }
        let clipped = icc.summary.clipped_black;
        if clipped.iter().any(|&v| v > 0.0) {
            outln!(
                "note: the black lies outside the primaries' cone; the ICC curves clip it by \
                 Y {:.2e} {:.2e} {:.2e} of the white (R, G, B)",
                clipped[0],
                clipped[1],
                clipped[2]
            )?;
        }
    }
    Ok(())
}

fn print_event(event: Event<'_>) -> Result<(), super::console::ConsoleError> {
    match event {
        Event::Warning(text) => errln!("warning: {text}"),
        Event::Selected(selection) => outln!("{selection}"),
        Event::ChartWritten(path) => outln!("selection chart written to {}", path.display()),
        Event::Fitted {
            patches,
            measurements,
            profile,
        } => {
            outln!(
                "{patches} patches from {}; model {}",
                measurements.display(),
                profile.model
            )?;
            let (w, k) = (profile.white_xyz, profile.black_xyz);
            outln!(
                "white XYZ {:.3} {:.3} {:.3} cd/m², black XYZ {:.4} {:.4} {:.4} cd/m²",
                w[0],
                w[1],
                w[2],
                k[0],
                k[1],
                k[2]
            )?;
            outln!("{}", profile.diagnostics())
        }
        Event::ProfileWritten(path) => outln!("profile written to {}", path.display()),
    }
}

/// The library's refusals of options in this command's flags.
fn refusal(e: fit::Error, args: &Args) -> CliError {
    let usage = |text: String| CliError::Usage(text);
    match e {
        fit::Error::OutputIsDirectory(path) => usage(format!(
            "-o {}: is a directory; give the profile file to write",
            path.display()
        )),
        fit::Error::GammaWithoutPlccGamma => {
            usage("--gamma applies to --model plcc-gamma only".into())
        }
        fit::Error::BadGamma(g) => usage(format!("--gamma must be a positive number, got {g}")),
        fit::Error::IccVersionWithoutIcc => usage("--icc-version needs --icc OUT.icc".into()),
        fit::Error::ChartWithoutSelection => {
            usage("--chart draws the model selection: it needs --model auto".into())
        }
        fit::Error::BadNoise(n) => usage(format!("--noise must be a non-negative number, got {n}")),
        fit::Error::Folds(_) => usage(format!("--folds must be at least 2, got {}", args.folds)),
        fit::Error::Chart { .. } => CliError::Failed(e.to_string().into()),
        e => CliError::from(e),
    }
}
