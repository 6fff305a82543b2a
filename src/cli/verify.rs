//! `metamer verify`: a profile's predictions against measured patches.

use std::path::PathBuf;

use super::CliResult;
use metamer::display::job::verify::{self, Request};

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
    let request = Request {
        profile: args.profile,
        measurements: args.measurements,
    };
    let report = verify::run(&request, &mut |text| {
        super::console::reported_at_exit(errln!("warning: {text}"))
    })?;
    let v = &report.verification;
    if args.json {
        outln!(
            "{}",
            serde_json::to_string(v).expect("a verification always serialises")
        )?;
    } else {
        outln!(
            "{} ({}) against {}",
            request.profile.display(),
            report.profile.model,
            request.measurements.display()
        )?;
        outln!("{v}")?;
    }
    Ok(())
}
