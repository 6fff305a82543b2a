//! `metamer budget`: display models' reproduction error against measured patches on the
//! simulated monitors (the patch-count chart).

use std::path::PathBuf;

use metamer::display::job::budget::{self, Error, Request};

use super::{CliError, CliResult};

#[derive(clap::Args)]
pub struct Args {
    /// Output directory: budget.csv and budget-PRESET.svg per monitor.
    #[arg(short = 'o', long = "out", value_name = "DIR")]
    out: PathBuf,
    /// Simulated monitors to study (repeatable; default all: ideal-crt, ips-lcd,
    /// wide-gamut-ccfl).
    #[arg(long = "display", value_name = "PRESET")]
    displays: Vec<String>,
    /// Models to study (repeatable; default all).
    #[arg(long = "model", value_name = "MODEL")]
    models: Vec<String>,
    /// Fresh sets of readings per budget (the errors are pooled over them).
    #[arg(long, default_value_t = 5)]
    trials: usize,
    /// Seed of the meter noise and of the verification colours.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Replace budget.csv and the charts if they exist.
    #[arg(long)]
    force: bool,
}

pub fn run(args: Args) -> CliResult {
    let request = Request {
        out: args.out,
        displays: args.displays,
        models: args.models,
        trials: args.trials,
        seed: args.seed,
        force: args.force,
    };
    let bar = indicatif::ProgressBar::new(0);
    bar.set_style(
        indicatif::ProgressStyle::with_template("{bar:30} fit {pos}/{len} · about {eta} left")
            .expect("valid template"),
    );
    let points = budget::run(&request, &|done, total| {
        bar.set_length(total as u64);
        bar.set_position(done as u64)
    });
    bar.finish_and_clear();
    let points = points.map_err(|e| match e {
        Error::NoTrials => CliError::Usage(
            "--trials must be at least 1: each trial is one fresh set of readings".into(),
        ),
        Error::OutIsFile(path) => CliError::Usage(format!(
            "-o {}: is a file, but budget writes budget.csv and one chart per display into a \
             directory",
            path.display()
        )),
        Error::UnknownName(text) => CliError::Usage(text),
        e => CliError::from(e),
    })?;
    outln!("preset            model                   patches  mean ΔE00  p95 ΔE00  max ΔE00")?;
    for p in &points {
        outln!(
            "{:<17} {:<23} {:>7}  {:>9.3}  {:>8.3}  {:>8.3}",
            p.preset,
            p.model,
            p.patches,
            p.mean_de00,
            p.p95_de00,
            p.max_de00
        )?;
    }
    outln!("wrote {}", request.out.display())?;
    Ok(())
}
