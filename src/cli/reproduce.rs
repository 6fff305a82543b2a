//! `metamer reproduce`: XYZ targets (CSV) or an XYZ image (.exr/.pfm) → display drive values
//! through a profile's inverse model, with out-of-gamut values counted.

use std::path::PathBuf;

use super::{CliError, CliResult};
use metamer::display::gamut::GamutMapping;
use metamer::display::job::reproduce::{self, Error, Report, Request};

#[derive(clap::Args)]
pub struct Args {
    /// Display profile written by `metamer fit`.
    #[arg(long, value_name = "PROFILE.json")]
    profile: PathBuf,
    /// Targets: CSV with the header X,Y,Z (cd/m²); writes r,g,b,out_of_gamut.
    #[arg(long, value_name = "TARGETS.csv", conflicts_with = "image")]
    xyz: Option<PathBuf>,
    /// An absolute XYZ image (.exr or .pfm); writes a PNG of drive values.
    #[arg(long, value_name = "XYZ.exr|XYZ.pfm")]
    image: Option<PathBuf>,
    /// Output: RGB.csv for --xyz, OUT.png for --image.
    #[arg(short = 'o', long = "output")]
    output: PathBuf,
    /// Replace the output file if it exists (never one of the inputs).
    #[arg(long)]
    force: bool,
    /// PNG bits per channel (8 or 16; default 8), for --image only.
    #[arg(long)]
    bits: Option<u8>,
    /// Flip the image left–right, for the paper's set-up where the display is seen in a
    /// mirror.
    #[arg(long)]
    mirror: bool,
    /// Out-of-gamut values: clip the drive values, or the nearest colour in CIELAB.
    #[arg(long, default_value = "clip")]
    gamut: GamutMapping,
}

pub fn run(args: Args) -> CliResult {
    let request = Request {
        profile: args.profile,
        xyz: args.xyz,
        image: args.image,
        output: args.output,
        force: args.force,
        bits: args.bits,
        mirror: args.mirror,
        gamut: args.gamut,
    };
    let usage = |text: &str| CliError::Usage(text.into());
    let report = reproduce::run(&request).map_err(|e| match e {
        Error::Bits(bits) => usage(&format!("--bits must be 8 or 16, got {bits}")),
        Error::BitsForTargets => {
            usage("--bits sets the PNG depth of --image; --xyz writes drive values as CSV numbers")
        }
        Error::OutputIsDirectory(path) => usage(&format!(
            "-o {}: is a directory; give the file to write",
            path.display()
        )),
        Error::MirrorForTargets => usage("--mirror applies to --image only"),
        Error::NoInput => usage("give exactly one of --xyz TARGETS.csv or --image XYZ.exr|XYZ.pfm"),
        e => CliError::from(e),
    })?;
    let output = request.output.display();
    match report {
        Report::Targets {
            count,
            out_of_gamut: out,
        } => errln!(
            "{count} targets, {out} out of gamut ({}); written to {output}",
            if out > 0 && request.gamut == GamutMapping::Clip {
                "clipped"
            } else if out > 0 {
                "mapped to the nearest CIELAB colour"
            } else {
                "none to handle"
            },
        ),
        Report::Image {
            width,
            height,
            elapsed,
            out_of_gamut,
            bits,
        } => errln!(
            "{width}×{height} pixels converted in {:.1} ms; {out_of_gamut} out of gamut ({:.3} \
             %); {bits}-bit PNG written to {output}",
            elapsed.as_secs_f64() * 1e3,
            100.0 * out_of_gamut as f64 / (width * height).max(1) as f64,
        ),
    }?;
    Ok(())
}
