//! `metamer fit`: fit a display model to measured patches, print its diagnostics and save
//! the profile.

use std::path::PathBuf;

use super::{CliError, CliResult};
use metamer::display::{fit_profile_with, read_measurement_file, FitOptions, ModelKind};

#[derive(clap::Args)]
pub struct Args {
    /// Measured patches: ArgyllCMS `.ti3` (as dispread writes) or CSV `r,g,b,X,Y,Z`
    /// (drive 0–1, XYZ cd/m²).
    #[arg(long, value_name = "FILE")]
    measurements: PathBuf,
    /// Display model: plcc, plcc-gamma, gog, gogo, lut, matrix-lsq.
    #[arg(long, default_value = "plcc")]
    model: ModelKind,
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
}

pub fn run(args: Args) -> CliResult {
    if let Some(g) = args.gamma {
        if args.model != ModelKind::PlccGamma {
            return Err(CliError::Usage(
                "--gamma applies to --model plcc-gamma only".into(),
            ));
        }
        if !(g.is_finite() && g > 0.0) {
            return Err(CliError::Usage(format!(
                "--gamma must be a positive number, got {g}"
            )));
        }
    }
    let m = read_measurement_file(&args.measurements)?;
    if !m.absolute {
        eprintln!(
            "warning: {} holds white-relative XYZ (no LUMINANCE_XYZ_CDM2): taken as if the \
             white had 100 cd/m²",
            args.measurements.display()
        );
    }
    if let Some(n) = args.noise {
        if !(n.is_finite() && n >= 0.0) {
            return Err(CliError::Usage(format!(
                "--noise must be a non-negative number, got {n}"
            )));
        }
    }
    let options = FitOptions {
        gamma: args.gamma,
        noise_de00: args.noise,
    };
    let profile = fit_profile_with(args.model, &m.patches, Some(&args.measurements), &options)?;
    println!(
        "{} patches from {}; model {}",
        m.patches.len(),
        args.measurements.display(),
        profile.model
    );
    println!(
        "white XYZ {:.3} {:.3} {:.3} cd/m², black XYZ {:.4} {:.4} {:.4} cd/m²",
        profile.white_xyz[0],
        profile.white_xyz[1],
        profile.white_xyz[2],
        profile.black_xyz[0],
        profile.black_xyz[1],
        profile.black_xyz[2]
    );
    println!("{}", profile.diagnostics());
    profile.save(&args.output)?;
    println!("profile written to {}", args.output.display());
    Ok(())
}
