//! `metamer measure-box`: the guided, resumable measurement of the validation box.

use std::collections::BTreeMap;
use std::io::Write;
use std::path::PathBuf;
use std::sync::Arc;

use metamer::boxmeasure::{
    self, BoxDetails, BoxPlan, Instruments, MeasureBoxError, Options, Outcome, PlanError, Stage,
    Summary,
};
use metamer::output::OutputPolicy;
use metamer::rig::sim_scene_box::{BoxOperator, TruthBox};
use metamer::rig::Scenario;
use metamer::session::{
    attendance, on_ctrl_c, Attendance, BarProgress, JournalError, NobodyAtTheRig, Operator, RunEnd,
    RunOptions, SessionError,
};
use metamer_drivers::{DriverError, Instrument, SharedWorld, Spec, View, World};

use super::{CliError, CliResult};

#[derive(clap::Args)]
pub struct Args {
    /// Output directory: the stage journals, scene.json, light.json/.svg/.ies/.ldt,
    /// summary.json.
    #[arg(short = 'o', long = "out", value_name = "DIR")]
    out: PathBuf,
    /// The spectral instrument: i1pro, i1pro:SERIAL, replay:FILE.jsonl or sim:i1pro.
    #[arg(long, value_name = "SPEC")]
    spectral: String,
    /// The spot meter: cs100a:PORT, replay:FILE.jsonl or sim:cs100a.
    #[arg(long, value_name = "SPEC")]
    spot: String,
    /// A plan file (JSON) changing counts, angles and geometry; default the paper's plan.
    #[arg(long, value_name = "FILE.json")]
    plan: Option<PathBuf>,
    /// Readings of each tile and each spot (default 5, or the plan file's).
    #[arg(long, value_name = "N")]
    repeats: Option<usize>,
    /// Continue the journals in DIR (after a crash, Ctrl-C or kill).
    #[arg(long)]
    resume: bool,
    /// Run only this stage (again from the start, the earlier journal set aside, unless
    /// --resume): tiles, falloff, materials or spots.
    #[arg(long, value_name = "STAGE")]
    stage: Option<String>,
    /// Seed of the simulated box's truth and of its instruments' noise (sim: only).
    #[arg(long, default_value_t = 1, value_name = "N")]
    seed: u64,
    /// The simulated box's light (sim: only; default display-white): display-white (the
    /// ips-lcd display's white, as the paper's box was lit by an LCD) or led-rgb1 (CIE
    /// LED-RGB1, a warm light whose saturated colours no virtual display can show).
    #[arg(long, value_name = "LIGHT")]
    scenario: Option<String>,
    /// Replace an existing scene.json, light.json/.svg/.ies/.ldt or summary.json in DIR.
    #[arg(long)]
    force: bool,
    /// Nobody is at the rig: take every reading without asking anyone to place, aim or
    /// calibrate the instruments. Real instruments without a terminal on stdin need it.
    #[arg(long)]
    unattended: bool,
    /// Stop after N new readings, as if interrupted (tests; splitting a long session).
    #[arg(long, value_name = "N", hide = true)]
    stop_after: Option<usize>,
}

fn usage(e: impl std::fmt::Display) -> CliError {
    CliError::Usage(e.to_string())
}

/// A simulated instrument's spec with the session's seed unless it names its own.
fn open(spec: &Spec, world: Option<Arc<dyn World>>) -> Result<Box<dyn Instrument>, CliError> {
    spec.open(world).map_err(|e| match e {
        DriverError::UnknownSpec { .. } | DriverError::BadSpecOption { .. } => usage(e),
        e => CliError::from(e),
    })
}

/// The simulated box's light named by `--scenario`; refused with real instruments, whose
/// box is lit by whatever light it has.
pub(super) fn box_light(name: Option<&str>, simulated: bool) -> Result<Option<Scenario>, CliError> {
    match (name, simulated) {
        (None, _) => Ok(None),
        (Some(n), true) => n.parse().map(Some).map_err(usage),
        (Some(_), false) => Err(usage(
            "--scenario sets the light of the simulated box; real instruments (--spectral/--spot not sim:…) measure the real box under its own light",
        )),
    }
}

pub fn run(args: Args) -> CliResult {
    let mut plan = match &args.plan {
        Some(p) => BoxPlan::load(p).map_err(|e| match e {
            PlanError::Io { .. } => CliError::from(e),
            e => usage(e),
        })?,
        None => BoxPlan::default(),
    };
    if let Some(n) = args.repeats {
        plan.repeats = n;
    }
    plan.validate().map_err(|e| match e {
        PlanError::Invalid { field, message } if field == "repeats" => {
            usage(format!("--repeats {message}"))
        }
        e => usage(e),
    })?;
    let stage: Option<Stage> = args
        .stage
        .as_deref()
        .map(str::parse)
        .transpose()
        .map_err(usage)?;
    let specs = [&args.spectral, &args.spot].map(Spec::new);
    let simulated = specs.each_ref().map(Spec::is_simulated);
    if simulated[0] != simulated[1] {
        return Err(usage(
            "--spectral and --spot must both be simulated (sim:…) or both real: a simulated instrument sees only the simulated box",
        ));
    }
    let light = box_light(args.scenario.as_deref(), simulated[0])?;
    // Before anything is opened: a real rig with nobody to ask is refused.
    let attended =
        attendance(&[&args.spectral, &args.spot], args.unattended).map_err(nobody_at_the_rig)?;
    let mut rig_options = BTreeMap::new();
    let (mut spectral, mut spot, mut operator): (_, _, Box<dyn Operator>) = if simulated[0] {
        let light = light.unwrap_or_default();
        rig_options.insert("seed".to_string(), args.seed.to_string());
        rig_options.insert("light".to_string(), light.name().to_string());
        eprintln!("simulating the box (seed {}, lit by {light})…", args.seed);
        let truth = TruthBox::new(&plan, args.seed, light)?;
        let world = Arc::new(SharedWorld::new(View::Capped));
        let spectral = open(
            &specs[0].with_seed_unless_set(args.seed),
            Some(world.clone()),
        )?;
        let spot = open(
            &specs[1].with_seed_unless_set(args.seed.wrapping_add(1)),
            Some(world.clone()),
        )?;
        let operator = BoxOperator::new(truth, world);
        (spectral, spot, Box::new(operator))
    } else {
        (
            open(&specs[0], None)?,
            open(&specs[1], None)?,
            attended.operator(),
        )
    };
    let mut output = OutputPolicy::new(args.force);
    if let Some(p) = &args.plan {
        output.input(p);
    }
    let options = Options {
        output,
        dir: args.out.clone(),
        plan,
        stage,
        resume: args.resume,
        rig_options,
        details: BoxDetails {
            spectral: args.spectral.clone(),
            spot: args.spot.clone(),
        },
        run: RunOptions {
            stop_after: args.stop_after,
            interrupt: Some(on_ctrl_c()),
        },
    };
    let outcome = boxmeasure::run(
        &options,
        Instruments {
            spectral: spectral.as_mut(),
            spot: spot.as_mut(),
        },
        operator.as_mut(),
        &mut BarProgress::new("reading")
            .attended(!simulated[0] && attended == Attendance::Terminal),
    )
    .map_err(translate)?;
    match outcome {
        Outcome::Finished(summary) => print_summary(&summary),
        Outcome::StagesMissing(stages) => {
            let names: Vec<&str> = stages.iter().map(|s| s.name()).collect();
            println!(
                "stage(s) {} still to measure before the scene can be assembled (--stage NAME, or the whole session with --resume)",
                names.join(", ")
            );
            Ok(())
        }
        Outcome::Incomplete {
            stage,
            end,
            done,
            total,
            log,
        } => {
            let missing = total - done;
            let log = log.display();
            let text = if done == 0 {
                format!(
                    "stage {stage}: none of its {total} readings taken yet: continue with --resume"
                )
            } else {
                format!(
                    "stage {stage}: {missing} of {total} readings still to take; the others are safe in {log}: continue with --resume"
                )
            };
            match end {
                RunEnd::Stopped { .. } | RunEnd::Complete => {
                    println!("stopped: {text}");
                    Ok(())
                }
                RunEnd::Interrupted { .. } => {
                    Err(CliError::Failed(format!("interrupted: {text}").into()))
                }
                RunEnd::Aborted { .. } => {
                    println!("stopped at your request: {text}");
                    Ok(())
                }
            }
        }
    }
}

/// The library's session errors said with this command's flags.
fn translate(e: MeasureBoxError) -> CliError {
    let text = match &e {
        MeasureBoxError::Session {
            stage,
            source: SessionError::Journal(JournalError::Exists { path, entries }),
        } => Some(format!(
            "stage {stage}: {} exists with {entries} reading(s) of an earlier session: continue it with --resume, measure the stage again with --stage {stage}, or choose another output directory",
            path.display()
        )),
        MeasureBoxError::Session {
            stage,
            source:
                SessionError::Journal(JournalError::OptionDiffers {
                    path,
                    option,
                    logged,
                    now,
                }),
        } => Some(format!(
            "stage {stage}: {} was written by another session: its {option} is {logged}, this one's is {now}; run with the same --plan/--repeats/--seed and --resume, or choose another output directory",
            path.display()
        )),
        MeasureBoxError::Session {
            stage,
            source:
                SessionError::Step {
                    index,
                    total,
                    label,
                    prepare,
                    done,
                    journal,
                    source,
                },
        } => Some(format!(
            "stage {stage}, reading {} of {total} ({label}: {prepare}): {source}\n  {done} of {total} readings are safe in {}; fix the cause and run the same command with --resume",
            index + 1,
            journal.display()
        )),
        _ => None,
    };
    match text {
        Some(t) => CliError::Failed(t.into()),
        None => CliError::from(e),
    }
}

/// A real rig with nobody to ask, refused in the words of the command line.
pub(super) fn nobody_at_the_rig(e: NobodyAtTheRig) -> CliError {
    usage(format!(
        "{e}. Run the command at a terminal, or add --unattended if the rig may measure without anyone at it; nothing was measured"
    ))
}

fn print_summary(s: &Summary) -> CliResult {
    let mut out = std::io::stdout().lock();
    let c = &s.render.comparison;
    writeln!(
        out,
        "tiles: {} · fall-off: {} angles, {} LDC (rms {}) · materials: {} · spots: {}",
        s.tiles.len(),
        s.falloff.len(),
        s.light.model,
        s.provenance
            .distribution_fit
            .rms
            .map_or("n/a".into(), |r| format!("{r:.4}")),
        s.materials.len(),
        s.spots.len()
    )?;
    let flagged = &s.provenance.outliers;
    if flagged.is_empty() {
        writeln!(
            out,
            "no outliers; every group's spread within the instruments' noise"
        )?;
    }
    for f in flagged {
        writeln!(
            out,
            "flagged: {} {}: outlier repeats {:?}{}",
            f.stage,
            f.what,
            f.outliers,
            if f.spread_exceeds_noise {
                format!(", spread {:.4} > 2 × noise {:.4}", f.sd_y, f.noise_y)
            } else {
                String::new()
            }
        )?;
    }
    writeln!(
        out,
        "measured scene rendered vs box spots: ΔE*ab mean {:.2}, max {:.2}; ΔE00 mean {:.2}, max {:.2}; {} of {} below the JND by point estimate",
        c.mean_de76,
        c.max_de76,
        c.mean_de00,
        c.max_de00,
        c.below_jnd_point,
        c.patches.len()
    )?;
    let f = &s.files;
    writeln!(
        out,
        "wrote {}, {}, {}, {}, {}, {}",
        f.scene.display(),
        f.light.display(),
        f.light_chart.display(),
        f.ies.display(),
        f.ldt.display(),
        f.summary.display()
    )?;
    Ok(())
}
