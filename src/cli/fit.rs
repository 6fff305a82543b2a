//! `metamer fit`: fit a display model to measured patches, print its diagnostics and save
//! the profile.

use std::path::PathBuf;

use super::{CliError, CliResult};
use metamer::display::icc::{agreement, encode_icc, inverse_agreement, IccVersion};
use metamer::display::{
    fit_profile_with, read_measurement_file, select_model, FitOptions, ModelKind,
};
use metamer::output::OutputPolicy;

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
    /// The ICC version of --icc: 4 (default) or 2.4.
    #[arg(long, value_name = "4|2.4")]
    icc_version: Option<IccVersion>,
}

/// A model by name, or `auto`.
#[derive(Clone, Copy, Debug, PartialEq)]
enum ModelChoice {
    Auto,
    Kind(ModelKind),
}

impl std::str::FromStr for ModelChoice {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        if s.trim().eq_ignore_ascii_case("auto") {
            return Ok(ModelChoice::Auto);
        }
        s.parse::<ModelKind>()
            .map(ModelChoice::Kind)
            .map_err(|e| format!("{e}, or auto"))
    }
}

pub fn run(args: Args) -> CliResult {
    if args.output.is_dir() {
        return Err(CliError::Usage(format!(
            "-o {}: is a directory; give the profile file to write",
            args.output.display()
        )));
    }
    let mut out = OutputPolicy::new(args.force);
    out.input(&args.measurements);
    // Before the fit, which may take a while: a refused output is found now.
    out.check(&args.output)?;
    if let Some(g) = args.gamma {
        if args.model != ModelChoice::Kind(ModelKind::PlccGamma) {
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
    if args.icc_version.is_some() && args.icc.is_none() {
        return Err(CliError::Usage("--icc-version needs --icc OUT.icc".into()));
    }
    // The ICC profile follows the output policy: never onto the measurements or the JSON
    // profile, never over an existing file; checked before the fit so no work is lost.
    let mut icc_policy = OutputPolicy::new(args.force);
    icc_policy.inputs([args.measurements.as_path(), args.output.as_path()]);
    if let Some(path) = &args.icc {
        icc_policy.check(path)?;
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
    if args.folds < 2 {
        return Err(CliError::Usage(format!(
            "--folds must be at least 2, got {}",
            args.folds
        )));
    }
    let kind = match args.model {
        ModelChoice::Kind(kind) => kind,
        ModelChoice::Auto => {
            let selection = select_model(&m.patches, args.folds, &options)?;
            println!("{selection}");
            selection.model
        }
    };
    let profile = fit_profile_with(kind, &m.patches, Some(&args.measurements), &options)?;
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
    profile.save(&args.output, &out)?;
    println!("profile written to {}", args.output.display());
    if let Some(path) = &args.icc {
        let version = args.icc_version.unwrap_or(IccVersion::V4);
        let name = args
            .measurements
            .file_name()
            .unwrap_or_default()
            .to_string_lossy();
        let icc = encode_icc(
            &profile,
            version,
            &format!("metamer {} ({name})", profile.model),
        )?;
        icc_policy.write(path, &icc.bytes)?;
        let drives: Vec<[f64; 3]> = m.patches.iter().map(|p| p.rgb).collect();
        let check = agreement(&icc.bytes, &profile, &drives)?;
        println!(
            "ICC {} profile ({}) written to {}; read back, it follows the model to ΔE00 mean \
             {:.4}, max {:.4} over the {} patches",
            icc.summary.version,
            icc.summary.form,
            path.display(),
            check.mean_de00,
            check.max_de00,
            check.points
        );
        if let Ok(inverse) = inverse_agreement(&icc.bytes, &profile, &drives) {
            println!(
                "its B2A0 inverts the model to ΔE00 mean {:.4}, max {:.4} over the same patches",
                inverse.mean_de00, inverse.max_de00
            );
        }
        let clipped = icc.summary.clipped_black;
        if clipped.iter().any(|&v| v > 0.0) {
            println!(
                "note: the black lies outside the primaries' cone; the ICC curves clip it by \
                 Y {:.2e} {:.2e} {:.2e} of the white (R, G, B)",
                clipped[0], clipped[1], clipped[2]
            );
        }
    }
    Ok(())
}
