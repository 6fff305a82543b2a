//! `metamer validate`: the box's readings against the display's (and the simulation's) in
//! CIELAB relative to the display's white, with uncertainty; prints the per-patch table
//! and writes `validation.json`, `validation.csv` and `report.html`.

use std::path::PathBuf;

use clap::ValueEnum;
use metamer::color::Xyz;
use metamer::output::OutputPolicy;
use metamer::validation::export::{comparisons, to_json};
use metamer::validation::plausible;
use metamer::validation::readings::Format;
use metamer::validation::report::{InputFile, InstrumentUsed};
use metamer::validation::{
    assess, read_readings, write_report_files, AssessOptions, Assessment, Propagation, ReadingSet,
    ReportInput, ValidationError,
};

use super::{parse_triple, CliError, CliResult};

#[derive(Clone, Copy, ValueEnum)]
enum PropagationArg {
    /// Seeded Monte Carlo draws of the readings' noise, the interval by inverting the test
    /// of each true difference (bias-aware; right near ΔE = 0 too).
    MonteCarlo,
    /// ΔE ± 1.96 σ by first-order propagation.
    Linear,
}

/// Most Monte Carlo draws per patch.
const MAX_DRAWS: usize = 10_000_000;
/// Largest model term: CIELAB's whole gamut spans a few hundred ΔE*ab.
const MAX_MODEL_TERM: f64 = 1000.0;

#[derive(clap::Args)]
pub struct Args {
    /// The box's readings: a session journal (.jsonl), `metamer spot --json` output, or a
    /// CSV patch,X,Y,Z[,sd_X,sd_Y,sd_Z[,cov_XY,cov_XZ,cov_YZ]][,n][,u_lab][,out_of_gamut].
    #[arg(long, value_name = "READINGS")]
    reference: PathBuf,
    /// The display's readings of the rendering (same formats).
    #[arg(long, value_name = "READINGS")]
    test: PathBuf,
    /// The simulation's readings (also `metamer render spots --json` output): adds box vs
    /// simulation (Fig. 6) and display vs simulation.
    #[arg(long, value_name = "READINGS")]
    simulation: Option<PathBuf>,
    /// CIELAB's white: X,Y,Z, or `test` / `reference` for that file's `white` reading (else
    /// its brightest reading). Default: test, the display's white.
    #[arg(long, default_value = "test", value_name = "X,Y,Z|test|reference")]
    white: String,
    /// Output directory for validation.json, validation.csv and report.html.
    #[arg(short = 'o', long = "out", value_name = "DIR")]
    out: PathBuf,
    /// Replace report files already in DIR.
    #[arg(long)]
    force: bool,
    /// Print validation.json to stdout instead of the table.
    #[arg(long)]
    json: bool,
    /// How uncertainty reaches ΔE.
    #[arg(long, value_enum, default_value = "monte-carlo")]
    propagation: PropagationArg,
    /// Monte Carlo draws per patch.
    #[arg(long, default_value_t = 4000, value_name = "N")]
    draws: usize,
    /// Monte Carlo seed.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// A standard uncertainty in ΔE*ab for the display model (e.g. its RMS verification
    /// error), added to every display reading.
    #[arg(long, default_value_t = 0.0, value_name = "DE")]
    model_term: f64,
    /// Patches the display cannot show (comma-separated numbers), besides those the
    /// readings mark; marked in the comparisons with the display on one side.
    #[arg(long, value_delimiter = ',', value_name = "LIST")]
    out_of_gamut: Vec<usize>,
    /// The report's title.
    #[arg(long, default_value = "Validation: box, display and simulation")]
    title: String,
}

pub fn run(args: Args) -> CliResult {
    if args.draws < 100 {
        return Err(CliError::Usage(
            "--draws must be at least 100 for a 95 % interval".into(),
        ));
    }
    // Draws are held in memory per patch; ten million already take minutes.
    if args.draws > MAX_DRAWS {
        return Err(CliError::Usage(format!(
            "--draws {}: at most {MAX_DRAWS} (10⁵ give the 95 % interval to a few per cent)",
            args.draws
        )));
    }
    if !(0.0..=MAX_MODEL_TERM).contains(&args.model_term) {
        return Err(CliError::Usage(format!(
            "--model-term {:?}: must be a ΔE*ab from 0 to {MAX_MODEL_TERM}",
            args.model_term
        )));
    }
    if let Some(bad) = args.out_of_gamut.iter().find(|k| !(1..=24).contains(*k)) {
        return Err(CliError::Usage(format!(
            "--out-of-gamut: patch {bad} is not 1–24"
        )));
    }
    let reference = read_readings(&args.reference)?;
    let test = read_readings(&args.test)?;
    let simulation = args.simulation.as_deref().map(read_readings).transpose()?;
    let sets: Vec<&ReadingSet> = [&reference, &test].into_iter().chain(&simulation).collect();
    for set in &sets {
        plausible::check_luminance(set)?;
    }
    let (white, white_source) = match args.white.as_str() {
        "test" => test.white_or_brightest(),
        "reference" => reference.white_or_brightest(),
        s => {
            let v = parse_triple(s).map_err(|e| CliError::Usage(format!("--white: {e}")))?;
            metamer_color::check_xyz(v)
                .map_err(|e| CliError::Usage(format!("--white: not a white: {e}")))?;
            let white = Xyz::from_array(v);
            plausible::check_given_white(white)
                .and_then(|()| plausible::check_white_against(white, &sets))
                .map_err(|e| CliError::Usage(format!("--white: {e}")))?;
            (white, "given on the command line".to_string())
        }
    };
    if args.white == "test" || args.white == "reference" {
        plausible::check_white_against(white, &sets)?;
    }
    let opts = AssessOptions {
        propagation: match args.propagation {
            PropagationArg::MonteCarlo => Propagation::MonteCarlo {
                draws: args.draws,
                seed: args.seed,
            },
            PropagationArg::Linear => Propagation::Linear,
        },
        model_term_de: args.model_term,
    };
    // The display model's term and the display's gamut belong to the comparisons that
    // have the display on one side; box vs simulation never went through the display.
    let run = |r: &ReadingSet, rn: &str, t: &ReadingSet, tn: &str, display: bool| {
        let o = AssessOptions {
            model_term_de: if display { opts.model_term_de } else { 0.0 },
            ..opts
        };
        assess(rn, r, tn, t, white, &o).map(|mut a| {
            for p in &mut a.patches {
                p.out_of_gamut |= display && args.out_of_gamut.contains(&p.patch);
            }
            a
        })
    };
    let box_vs_display = run(&reference, "box", &test, "display", true).map_err(bad_white)?;
    let (box_vs_simulation, display_vs_simulation) = match &simulation {
        Some(s) => (
            Some(run(&reference, "box", s, "simulation", false).map_err(bad_white)?),
            Some(run(s, "simulation", &test, "display", true).map_err(bad_white)?),
        ),
        None => (None, None),
    };
    let mut input = ReportInput {
        title: args.title.clone(),
        white_source,
        box_vs_display: Some(box_vs_display),
        box_vs_simulation,
        display_vs_simulation,
        out_of_gamut: args.out_of_gamut.clone(),
        ..ReportInput::default()
    };
    input.notes.extend(plausible::scale_note(&reference, &test));
    for (role, set) in [
        ("box", Some(&reference)),
        ("display", Some(&test)),
        ("simulation", simulation.as_ref()),
    ] {
        let Some(set) = set else { continue };
        input.inputs.push(InputFile {
            role: role.into(),
            path: set.file.display().to_string(),
            format: set.format.name().into(),
            patches: set.patches.len(),
            sha256: metamer::digest::sha256_file(&set.file).ok(),
        });
        for name in &set.instruments {
            input.instruments.push(InstrumentUsed {
                role: role.into(),
                model: name.clone(),
                ..InstrumentUsed::default()
            });
        }
        for note in &set.notes {
            input.notes.push(format!("{}: {note}", set.file.display()));
        }
        if set.format == Format::RenderJson {
            input.render_confidence = Some(render_confidence(set));
        }
    }
    let mut policy = OutputPolicy::new(args.force);
    policy.inputs(
        [&args.reference, &args.test]
            .into_iter()
            .chain(&args.simulation)
            .map(PathBuf::as_path),
    );
    let files = write_report_files(&args.out, &input, &policy).map_err(|e| match e {
        ValidationError::Output(o) if o.needs_force() => CliError::Usage(format!(
            "{o}: pass --force to replace the report, or choose another -o directory"
        )),
        e => CliError::from(e),
    })?;
    if args.json {
        println!("{}", to_json(&input));
        return Ok(());
    }
    for note in &input.notes {
        eprintln!("note: {note}");
    }
    println!(
        "white X Y Z = {:.4} {:.4} {:.4} ({})",
        white.x, white.y, white.z, input.white_source
    );
    for (_, a) in comparisons(&input) {
        print_table(a);
    }
    for f in files {
        println!("wrote {}", f.display());
    }
    Ok(())
}

/// A white that makes CIELAB meaningless is the user's input, not a data fault.
fn bad_white(e: ValidationError) -> CliError {
    match e {
        ValidationError::BadWhite { .. } => CliError::Usage(format!("--white: {e}")),
        e => CliError::from(e),
    }
}

fn render_confidence(set: &ReadingSet) -> metamer::validation::report::RenderConfidenceSection {
    metamer::validation::report::RenderConfidenceSection {
        method: format!("{} ({})", set.file.display(), set.format.name()),
        target_de: None,
        per_patch: set
            .patches
            .iter()
            .filter_map(|(k, p)| Some((*k, p.render_de95?)))
            .collect(),
        measure: "95 % ΔE*ab half-width or error bound".into(),
        ..Default::default()
    }
}

fn print_table(a: &Assessment) {
    println!();
    println!(
        "{} vs {} (CIELAB of {} first, then of {})",
        a.test, a.reference, a.reference, a.test
    );
    println!(
        "{:>3} {:<14} {:>7} {:>7} {:>7}  {:>7} {:>7} {:>7}  {:>7} {:>15}  {:>7} {:>15}  JND",
        "#", "patch", "L*", "a*", "b*", "L*", "a*", "b*", "ΔE*ab", "95 %", "ΔE00", "95 %"
    );
    for p in &a.patches {
        let [rl, ra, rb] = p.reference.lab;
        let [tl, ta, tb] = p.test.lab;
        println!(
            "{:>3} {:<14} {rl:>7.2} {ra:>7.2} {rb:>7.2}  {tl:>7.2} {ta:>7.2} {tb:>7.2}  {:>7.2} {:>15}  {:>7.2} {:>15}  {}{}",
            p.patch,
            p.name,
            p.de76,
            format!("[{:.2}, {:.2}]", p.de76_interval.lo, p.de76_interval.hi),
            p.de00,
            format!("[{:.2}, {:.2}]", p.de00_interval.lo, p.de00_interval.hi),
            p.jnd.name(),
            if p.out_of_gamut { "  (out of gamut)" } else { "" }
        );
    }
    println!("{}", a.summary());
}
