//! `metamer export`: the scene written for another renderer (Mitsuba 3, pbrt-v4 or Blender).

use std::path::PathBuf;

use super::{CliError, CliResult};
use metamer::export::{self, ExportError, ExportRequest, Renderer};

/// The renderers `--to` names.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum To {
    Mitsuba3,
    #[value(name = "pbrt-v4")]
    PbrtV4,
    Blender,
}

#[derive(clap::Args)]
pub struct Args {
    /// The scene file, or a built-in box by name (validation-box, validation-box-led-rgb1);
    /// default: the validation box built into the program.
    scene: Option<PathBuf>,
    /// The renderer to write for.
    #[arg(long)]
    to: To,
    /// The output directory (created; refused if it holds anything, unless --force).
    #[arg(short, long, value_name = "DIR")]
    output: PathBuf,
    /// Write into a directory that holds files, replacing those of the same name.
    #[arg(long)]
    force: bool,
    /// Samples per pixel written as the scene's default.
    #[arg(long, default_value_t = 256)]
    spp: u32,
    /// Do not measure how much a non-Lambertian emitter's Lambertian form changes the
    /// 24 readings (two radiosity solves).
    #[arg(long)]
    no_difference: bool,
}

pub fn run(args: Args) -> CliResult {
    let request = ExportRequest {
        scene: args.scene,
        to: match args.to {
            To::Mitsuba3 => Renderer::Mitsuba3,
            To::PbrtV4 => Renderer::PbrtV4,
            To::Blender => Renderer::Blender,
        },
        output: args.output,
        force: args.force,
        spp: args.spp,
        measure_difference: !args.no_difference,
    };
    let report = export::run(&request).map_err(|e| match e {
        ExportError::BadSpp => CliError::Usage("--spp must be at least 1".into()),
        ExportError::NotEmpty { dir } => CliError::Failed(
            format!(
                "refusing to export into {}: the directory is not empty (add --force to write \
                 into it)",
                dir.display()
            )
            .into(),
        ),
        e => e.into(),
    })?;
    for f in &report.files {
        outln!("wrote {}", f.display())?;
    }
    outln!("{}", report.summary)?;
    Ok(())
}
