//! `metamer lab`: the whole validation chain on the built-in simulated lab.

use std::path::{Path, PathBuf};

use metamer::display::gamut::GamutMapping;
use metamer::display::ModelKind;
use metamer::lab::{
    finished_run, result_files, run_lab, LabError, LabOptions, LabProgress, LabResult, Scenario,
    DISPLAY_DIR, LAB_FILE,
};
use metamer::output::OutputPolicy;
use metamer::rig::Preset;
use metamer::validation::Comparison;

use super::{CliError, CliResult};

#[derive(clap::Args)]
pub struct Args {
    /// Output directory: lab.json, the three comparisons (CSV + SVG), display/ (the display
    /// characterization: log, profile, .ti3, report).
    #[arg(short = 'o', long = "out", value_name = "DIR")]
    out: PathBuf,
    /// The box: display-white (lit by the ips-lcd display's white, as the paper's box was
    /// lit by an LCD; data/scenes/validation-box.json) or led-rgb1 (lit by CIE LED-RGB1, a
    /// warm light whose saturated colours no virtual display can show;
    /// data/scenes/validation-box-led-rgb1.json).
    #[arg(long, default_value = "display-white", value_name = "NAME")]
    scenario: String,
    /// Another box scene file instead of a named scenario.
    #[arg(long, value_name = "SCENE", conflicts_with = "scenario")]
    scene: Option<PathBuf>,
    /// The simulated monitor: ideal-crt, ips-lcd or wide-gamut-ccfl.
    #[arg(long, default_value = "ips-lcd", value_name = "PRESET")]
    display: String,
    /// Display model: lut (3D LUT, for displays where PLCC's assumptions fail, as the
    /// simulated LCDs'), plcc (paper Eq. 9), plcc-gamma, gog, gogo, matrix-lsq.
    #[arg(long, default_value = "lut", value_name = "MODEL")]
    model: String,
    /// Out-of-gamut colours: nearest-lab (least ΔE*ab the display can show) or clip.
    #[arg(long, default_value = "nearest-lab", value_name = "MAPPING")]
    gamut: String,
    /// The simulation's accuracy: 95 % half-width of every patch's ΔE*ab.
    #[arg(long, default_value_t = 0.1, value_name = "ΔE")]
    target_de: f64,
    /// Meter readings averaged per patch.
    #[arg(long, default_value_t = 3, value_name = "K")]
    repeats: usize,
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// The simulated meter's speed: 1 = the CS-100A's real ≈100 ms per reading.
    #[arg(long, default_value_t = 0.05, value_name = "F")]
    time_scale: f64,
    /// Continue an interrupted run in DIR (the display characterization resumes from its log).
    #[arg(long)]
    resume: bool,
}

pub fn run(args: Args) -> CliResult {
    let display: Preset = args.display.parse().map_err(CliError::Usage)?;
    let (scene, scenario) = match args.scene {
        Some(scene) => (Some(scene), None),
        None => {
            let scenario: Scenario = args.scenario.parse().map_err(CliError::Usage)?;
            (None, Some(scenario))
        }
    };
    let model: ModelKind = args.model.parse().map_err(CliError::Usage)?;
    let gamut: GamutMapping = args.gamut.parse().map_err(CliError::Usage)?;
    if args.target_de.is_nan() || args.target_de <= 0.0 {
        return Err(CliError::Usage("--target-de must be above 0".into()));
    }
    if args.repeats == 0 {
        return Err(CliError::Usage("--repeats must be at least 1".into()));
    }
    if args.time_scale.is_nan() || args.time_scale < 0.0 {
        return Err(CliError::Usage("--time-scale must be 0 or more".into()));
    }
    let options = LabOptions {
        scene,
        scenario,
        display,
        model,
        gamut,
        target_de: args.target_de,
        repeats: args.repeats,
        seed: args.seed,
        time_scale: args.time_scale,
    };
    if args.resume {
        if let Some(json) = finished_run(&args.out, &options).map_err(translate)? {
            return print_finished(&json);
        }
    }
    let earlier = args.out.join(LAB_FILE).exists() || args.out.join(DISPLAY_DIR).exists();
    if !args.resume && earlier {
        return Err(translate(LabError::Exists { dir: args.out }));
    }
    // A resumed run replaces the files it wrote itself; a new one replaces nothing.
    let mut out = OutputPolicy::new(args.resume);
    if let Some(s) = &options.scene {
        out.input(s);
    }
    out.dir(&args.out)?;
    for f in result_files(&args.out) {
        out.check(&f)?;
    }
    let bar = indicatif::ProgressBar::new_spinner();
    bar.set_style(
        indicatif::ProgressStyle::with_template("{spinner} {prefix}: {msg} ({elapsed})")
            .expect("valid template"),
    );
    bar.enable_steady_tick(std::time::Duration::from_millis(200));
    let result = run_lab(&args.out, &options, args.resume, &|p| match p {
        LabProgress::Stage(name) => {
            bar.set_prefix(name.to_string());
            bar.set_message("");
        }
        LabProgress::Render(r) => bar.set_message(format!(
            "{} of 24 patches at target, worst ±{:.3} ΔE*ab",
            r.converged, r.worst_de
        )),
        LabProgress::Readings { done, total } => {
            bar.set_message(format!("reading {done} of {total}"))
        }
    });
    bar.finish_and_clear();
    let result = result.map_err(translate)?;
    let written = result.write(&args.out, &out)?;
    print_summary(&result);
    println!(
        "wrote {} and the display characterization in {}",
        written
            .iter()
            .map(|p| p.display().to_string())
            .collect::<Vec<_>>()
            .join(", "),
        args.out.join(DISPLAY_DIR).display()
    );
    Ok(())
}

/// A finished run resumed: its results, read back; nothing is rendered or measured.
fn print_finished(json: &Path) -> CliResult {
    let text = std::fs::read_to_string(json)?;
    let lab: serde_json::Value = serde_json::from_str(&text)?;
    println!(
        "{} holds the finished run with these options; nothing to resume",
        json.display()
    );
    for name in [
        "display_vs_box",
        "simulation_vs_box",
        "display_vs_simulation",
    ] {
        let c: Comparison = serde_json::from_value(lab[name].clone())?;
        println!("{name}: {}", c.summary());
    }
    Ok(())
}

/// The library's errors in the words of this command's flags.
fn translate(e: LabError) -> CliError {
    match e {
        // The library says what to do; here that is a flag.
        LabError::Exists { dir } => CliError::Failed(
            format!(
                "{} holds an earlier lab run; choose another directory or add --resume",
                dir.display()
            )
            .into(),
        ),
        LabError::Incomplete { missing } => CliError::Failed(
            format!(
                "the display characterization stopped with {missing} readings missing; run \
                 the same command with --resume"
            )
            .into(),
        ),
        LabError::OptionDiffers {
            dir,
            option,
            logged,
            now,
        } => CliError::Failed(
            format!(
                "{} holds a finished lab run whose --{} is {logged}, this one's is {now}; run \
                 with the options it was made with, or choose another directory",
                dir.display(),
                option.replace('_', "-")
            )
            .into(),
        ),
        e => CliError::from(e),
    }
}

fn print_summary(r: &LabResult) {
    let v = &r.display_characterization.verification;
    println!(
        "box: {} readings per patch; simulation: {:.1} s of rendering to ΔE*ab ±{} (95 %)",
        r.options.repeats, r.render_seconds, r.options.target_de
    );
    let scene = r.options.scenario.map_or_else(
        || {
            r.options
                .scene
                .as_ref()
                .map_or("the built-in box".into(), |p| p.display().to_string())
        },
        |s| format!("scenario {}", s.name()),
    );
    println!("box: {scene}");
    println!(
        "display: virtual:{} at {:.1} cd/m² white, model {} (held-out ΔE00 mean {:.2}, max {:.2}); {}",
        r.options.display.name(),
        r.display_white_cd_m2,
        r.options.model,
        v.mean,
        v.max,
        r.display_characterization.verdict
    );
    println!(
        "{} of 24 simulated colours out of the display's gamut ({} mapping)",
        r.out_of_gamut, r.options.gamut
    );
    for (name, c) in r.comparisons() {
        println!("{name}: {}", c.summary());
    }
    println!("total {:.1} s", r.seconds);
}
