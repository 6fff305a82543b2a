//! `metamer reproduce`: XYZ targets (CSV) or an XYZ image (.exr/.pfm) → display drive values
//! through a profile's inverse model, with out-of-gamut values counted.

use std::path::PathBuf;
use std::time::Instant;

use super::{CliError, CliResult};
use metamer::display::gamut::GamutMapping;
use metamer::display::reproduce::{
    read_targets, reproduce_image, reproduce_targets, write_drive_csv, write_drive_png,
};
use metamer::display::Profile;
use metamer::output::OutputPolicy;
use metamer::render::image_io::read_xyz_image;

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
    let bits = args.bits.unwrap_or(8);
    if bits != 8 && bits != 16 {
        return Err(CliError::Usage(format!(
            "--bits must be 8 or 16, got {bits}"
        )));
    }
    if args.bits.is_some() && args.xyz.is_some() {
        return Err(CliError::Usage(
            "--bits sets the PNG depth of --image; --xyz writes drive values as CSV numbers".into(),
        ));
    }
    if args.output.is_dir() {
        return Err(CliError::Usage(format!(
            "-o {}: is a directory; give the file to write",
            args.output.display()
        )));
    }
    let mut out = OutputPolicy::new(args.force);
    out.input(&args.profile);
    out.inputs(args.xyz.iter().chain(&args.image).map(PathBuf::as_path));
    out.check(&args.output)?;
    let profile = Profile::load(&args.profile)?;
    match (&args.xyz, &args.image) {
        (Some(targets), None) => {
            if args.mirror {
                return Err(CliError::Usage("--mirror applies to --image only".into()));
            }
            let xyz = read_targets(targets)?;
            let drives = reproduce_targets(&profile, &xyz, args.gamut);
            write_drive_csv(&args.output, &drives, &out)?;
            let out = drives.iter().filter(|d| d.out_of_gamut).count();
            eprintln!(
                "{} targets, {out} out of gamut ({}); written to {}",
                drives.len(),
                if out > 0 && args.gamut == GamutMapping::Clip {
                    "clipped"
                } else if out > 0 {
                    "mapped to the nearest CIELAB colour"
                } else {
                    "none to handle"
                },
                args.output.display()
            );
            Ok(())
        }
        (None, Some(image)) => {
            let img = read_xyz_image(image)?;
            let start = Instant::now();
            let drive = reproduce_image(&profile, &img, args.mirror, args.gamut);
            let elapsed = start.elapsed();
            write_drive_png(&args.output, &drive, bits, &out)?;
            let total = img.width * img.height;
            eprintln!(
                "{}×{} pixels converted in {:.1} ms; {} out of gamut ({:.3} %); {}-bit PNG \
                 written to {}",
                img.width,
                img.height,
                elapsed.as_secs_f64() * 1e3,
                drive.out_of_gamut,
                100.0 * drive.out_of_gamut as f64 / total.max(1) as f64,
                bits,
                args.output.display()
            );
            Ok(())
        }
        _ => Err(CliError::Usage(
            "give exactly one of --xyz TARGETS.csv or --image XYZ.exr|XYZ.pfm".into(),
        )),
    }
}
