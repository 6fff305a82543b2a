//! `metamer verify`: a profile's predictions against measured patches.

use std::path::PathBuf;

use super::CliResult;
use metamer::display::{read_measurement_file, verify_profile, Profile};

#[derive(clap::Args)]
pub struct Args {
    /// The display profile (JSON, as `metamer fit` writes it).
    #[arg(long, value_name = "PROFILE.json")]
    profile: PathBuf,
    /// Measured patches: ArgyllCMS `.ti3` or CSV `r,g,b,X,Y,Z` (drive 0–1, XYZ cd/m²).
    #[arg(long, value_name = "FILE")]
    measurements: PathBuf,
    /// Print one JSON object instead of the text report.
    #[arg(long)]
    json: bool,
}

pub fn run(args: Args) -> CliResult {
    let profile = Profile::load(&args.profile)?;
    let m = read_measurement_file(&args.measurements)?;
    if !m.absolute {
        eprintln!(
            "warning: {} holds white-relative XYZ (no LUMINANCE_XYZ_CDM2): taken as if the \
             white had 100 cd/m²",
            args.measurements.display()
        );
    }
    let v = verify_profile(&profile, &m.patches)?;
    if args.json {
        println!(
            "{}",
            serde_json::to_string(&v).expect("a verification always serialises")
        );
    } else {
        println!(
            "{} ({}) against {}",
            args.profile.display(),
            profile.model,
            args.measurements.display()
        );
        println!("{v}");
    }
    Ok(())
}
