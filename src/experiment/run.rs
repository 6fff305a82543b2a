//! The stages in order, what each reads, and when each runs.

use std::path::{Path, PathBuf};
use std::time::Instant;

use serde::Serialize;

use super::budget::StageBudget;
use super::cache::{Inputs, StageDir, RECORD_FILE};
use super::display::{characterize_display, DisplaySetting};
use super::error::ExperimentError;
use super::measure_box::{self, MeasureBox};
use super::options::{BoxSource, ExperimentOptions};
use super::progress::Progress;
use super::reproduction::{reproduce, Reproduction};
use super::simulation::{simulate, SimulationSummary};
use super::stage::Stage;
use super::{display, display_spots, reproduction, simulation, validate};
use crate::color::Xyz;
use crate::display::Profile;
use crate::render::deadline::cancellable;
use crate::rig::ScreenSpec;
use crate::validation::job::ReadingFiles;

/// How one stage went.
#[derive(Clone, Debug, Serialize)]
pub struct StageOutcome {
    pub stage: Stage,
    /// Its inputs were unchanged and its outputs intact: nothing was run.
    pub reused: bool,
    /// This call's time on the stage (next to none where re-used).
    pub seconds: f64,
    /// How long the run that produced the stage's outputs took: this call's where it ran,
    /// the stage record's where re-used (0 for a box given as files).
    pub ran_seconds: f64,
    pub dir: PathBuf,
}

fn need(stage: Stage, path: PathBuf) -> Result<PathBuf, ExperimentError> {
    if path.exists() {
        Ok(path)
    } else {
        Err(ExperimentError::MissingInput {
            stage: stage.name(),
            missing: path,
        })
    }
}

fn read_json<T: serde::de::DeserializeOwned>(path: &Path) -> Result<T, ExperimentError> {
    let text = metamer_color::text::read_text(path).map_err(|source| ExperimentError::Io {
        file: path.to_path_buf(),
        source,
    })?;
    serde_json::from_str(&text).map_err(|e| ExperimentError::BadFile {
        file: path.to_path_buf(),
        message: e.to_string(),
    })
}

/// The box's scene and spot readings.
fn box_files(opts: &ExperimentOptions) -> (PathBuf, PathBuf) {
    match &opts.box_source {
        BoxSource::Existing { scene, spots } => (scene.clone(), spots.clone()),
        BoxSource::Measure(_) => {
            let d = opts.dir.join(Stage::Box.name());
            (
                d.join(measure_box::SCENE_FILE),
                d.join(measure_box::SPOTS_FILE),
            )
        }
    }
}

/// A finished stage whose inputs changed holds measurements of another configuration: it
/// is moved aside whole (never deleted) so the stage starts afresh.
fn set_aside_stale(sd: &StageDir) -> Result<Option<PathBuf>, ExperimentError> {
    if !sd.path(RECORD_FILE).exists() {
        return Ok(None);
    }
    let mut n = 1;
    let aside = loop {
        let p = sd.dir.with_file_name(format!("{}.old-{n}", sd.name));
        if !p.exists() {
            break p;
        }
        n += 1;
    };
    std::fs::rename(&sd.dir, &aside).map_err(|source| ExperimentError::Io {
        file: sd.dir.clone(),
        source,
    })?;
    Ok(Some(aside))
}

/// Runs the experiment's stages in order, re-using each whose inputs are unchanged.
pub fn run(
    opts: &ExperimentOptions,
    progress: &dyn Fn(Progress),
) -> Result<Vec<StageOutcome>, ExperimentError> {
    let root = &opts.dir;
    if let BoxSource::Existing { scene, spots } = &opts.box_source {
        for (what, file) in [("scene", scene), ("spot readings", spots)] {
            if !file.exists() {
                return Err(ExperimentError::GivenBoxMissing {
                    what,
                    file: file.clone(),
                });
            }
        }
    }
    super::preflight::check(opts)?;
    let planned = super::budget::budget(opts);
    say_budget(opts, &planned, progress);
    // The user's box files are this run's inputs: no stage may write onto them, by any
    // name (a link, a hard link), whatever policy it writes with.
    let _given = match &opts.box_source {
        BoxSource::Existing { scene, spots } => Some(crate::output::guard_inputs([
            scene.as_path(),
            spots.as_path(),
        ])),
        BoxSource::Measure(_) => None,
    };
    let mut outcomes = Vec::new();
    for stage in Stage::ALL {
        if opts.stage.is_some_and(|s| s != stage) {
            continue;
        }
        let sd = StageDir::new(root, stage.name());
        let start = Instant::now();
        let inputs = inputs_of(stage, opts)?;
        if let Some(outcome) = reuse(stage, opts, &sd, &inputs, start, progress) {
            outcomes.push(outcome);
            continue;
        }
        outcomes.push(run_afresh(
            stage, opts, &sd, &inputs, &planned, start, progress,
        )?);
    }
    Ok(outcomes)
}

/// The stage's outcome when it is not run: its record matches its inputs (or its box is
/// given as files) and it was not asked for by name.
fn reuse(
    stage: Stage,
    opts: &ExperimentOptions,
    sd: &StageDir,
    inputs: &Inputs,
    start: Instant,
    progress: &dyn Fn(Progress),
) -> Option<StageOutcome> {
    let forced = opts.stage == Some(stage);
    let given_box = matches!(opts.box_source, BoxSource::Existing { .. });
    let record = if forced || (stage == Stage::Box && given_box) {
        None
    } else {
        sd.reusable(inputs, super::products::products(stage))
    };
    if forced || !((stage == Stage::Box && given_box) || record.is_some()) {
        return None;
    }
    if let (Stage::Box, BoxSource::Existing { scene, spots }) = (stage, &opts.box_source) {
        progress(Progress::Note(format!(
            "box: given, measured earlier or elsewhere ({} and {})",
            scene.display(),
            spots.display()
        )));
    } else {
        progress(Progress::Stage {
            stage,
            reused: true,
        });
    }
    Some(StageOutcome {
        stage,
        reused: true,
        seconds: start.elapsed().as_secs_f64(),
        ran_seconds: record.map_or(0.0, |r| r.seconds),
        dir: sd.dir.clone(),
    })
}

/// Runs the stage from the start (a measuring stage resumes its journal), its earlier
/// outputs set aside or invalidated first, and records it.
fn run_afresh(
    stage: Stage,
    opts: &ExperimentOptions,
    sd: &StageDir,
    inputs: &Inputs,
    planned: &[StageBudget],
    start: Instant,
    progress: &dyn Fn(Progress),
) -> Result<StageOutcome, ExperimentError> {
    if interrupted(opts) {
        return Err(ExperimentError::InterruptedBefore {
            stage: stage.name(),
        });
    }
    progress(Progress::Stage {
        stage,
        reused: false,
    });
    if stage.measures() {
        if let Some(aside) = set_aside_stale(sd)? {
            progress(Progress::Note(format!(
                "the {stage} stage's inputs changed: its earlier measurements are kept in {}",
                aside.display()
            )));
        }
    } else {
        sd.invalidate()?;
    }
    let files = run_stage(stage, opts, sd, progress);
    // A stage that takes no readings is cut short by Ctrl-C (the render stops at its
    // next check, with a result or with "no result in time"): what it wrote is not
    // this stage's result, so it is not recorded. A measuring stage says itself where
    // its journal stopped.
    if interrupted(opts) && !stage.measures() {
        return Err(ExperimentError::Interrupted {
            stage: stage.name(),
        });
    }
    let files = files?;
    if stage.measures() {
        let kept = super::budget::recorded(&opts.dir, planned);
        if let Some(c) = kept.iter().find(|c| c.stage == stage.name()) {
            if let Some(actual) = &c.cost.actual {
                let what = format!("the {stage} stage");
                progress(Progress::Note(actual.after(&what, &c.cost.estimate)));
            }
        }
    }
    let seconds = start.elapsed().as_secs_f64();
    sd.finish(inputs, &files, seconds, opts.measuring)?;
    Ok(StageOutcome {
        stage,
        reused: false,
        seconds,
        ran_seconds: seconds,
        dir: sd.dir.clone(),
    })
}

/// The measuring stages' budget before the first stage, each as if it ran in full, and
/// their sum; a stage that is re-used or resumed takes less.
fn say_budget(opts: &ExperimentOptions, planned: &[StageBudget], progress: &dyn Fn(Progress)) {
    let runs = |s: &StageBudget| opts.stage.is_none_or(|only| only.name() == s.stage);
    let shown: Vec<StageBudget> = planned.iter().filter(|s| runs(s)).cloned().collect();
    for s in &shown {
        let what = format!("the {} stage", s.stage);
        progress(Progress::Note(s.cost.estimate.before(&what)));
    }
    if shown.len() > 1 {
        let total = super::budget::total(&shown);
        progress(Progress::Note(total.estimate.before(
            "the measuring stages (each in full; a stage re-used or resumed takes less)",
        )));
    }
}

fn interrupted(opts: &ExperimentOptions) -> bool {
    opts.run
        .interrupt
        .as_ref()
        .is_some_and(|f| f.load(std::sync::atomic::Ordering::SeqCst))
}

fn stage_path(opts: &ExperimentOptions, stage: Stage, file: &str) -> PathBuf {
    opts.dir.join(stage.name()).join(file)
}

/// What `stage` reads, hashed.
fn inputs_of(stage: Stage, opts: &ExperimentOptions) -> Result<Inputs, ExperimentError> {
    let p = |s: Stage, f: &str| need(stage, stage_path(opts, s, f));
    let (scene, box_spots) = box_files(opts);
    Ok(match stage {
        Stage::Box => {
            let i = Inputs::new().value("source", &opts.box_source);
            match &opts.box_source {
                BoxSource::Measure(MeasureBox {
                    plan: Some(plan), ..
                }) => i.file("plan", plan)?,
                _ => i,
            }
        }
        Stage::Simulation => {
            let i = Inputs::new()
                .file("scene", &need(stage, scene)?)?
                .value("options", &opts.simulation);
            // The image's bytes, not only its name: a re-rendered image is a new input.
            match &opts.simulation.external_image {
                Some(image) => i.file("external image", image)?,
                None => i,
            }
        }
        Stage::Display => {
            let i = Inputs::new().value("options", &opts.display);
            // A simulated monitor's white is set for the rendering; a real one is not.
            if matches!(opts.display.screen, ScreenSpec::Virtual(_)) {
                i.file("spots", &p(Stage::Simulation, simulation::SPOTS_FILE)?)?
            } else {
                i
            }
        }
        Stage::Reproduction => {
            let mut i = Inputs::new()
                .file("profile", &p(Stage::Display, display::PROFILE_FILE)?)?
                .file(
                    "simulation",
                    &p(Stage::Simulation, simulation::SUMMARY_FILE)?,
                )?
                .value("options", &opts.reproduction);
            let image = stage_path(opts, Stage::Simulation, simulation::IMAGE_FILE);
            if image.exists() {
                i = i.file("image", &image)?;
            }
            i
        }
        Stage::DisplaySpots => {
            let i = Inputs::new()
                .file("drives", &p(Stage::Reproduction, reproduction::FILE)?)?
                .file("display", &p(Stage::Display, display::SETTING_FILE)?)?
                .value("spot", &opts.display.spot)
                .value("repeats", &opts.repeats);
            // A verdict rule decides against the box's readings relative to the profile's
            // white: both are its inputs (a fixed count's hash stays as it was).
            let i = match opts.until_decided {
                Some(margin) => i
                    .value("until_decided", &margin)
                    .file("box", &need(stage, box_spots.clone())?)?
                    .file("profile", &p(Stage::Display, display::PROFILE_FILE)?)?,
                None => i,
            };
            // Another way of showing the spots than the paper's is an input too (the
            // paper's hash stays as it was).
            let i = match opts.spots_shown {
                display_spots::SpotsShown::Aimed => i,
                shown => i.value("shown", &shown),
            };
            let image = stage_path(opts, Stage::Reproduction, reproduction::IMAGE_FILE);
            if image.exists() {
                i.file("image", &image)?
            } else {
                i
            }
        }
        Stage::Validation => {
            let i = Inputs::new()
                .file("box", &need(stage, box_spots)?)?
                .file("simulation", &p(Stage::Simulation, simulation::SPOTS_FILE)?)?
                .file(
                    "display",
                    &p(Stage::DisplaySpots, display_spots::SPOTS_FILE)?,
                )?
                .file("profile", &p(Stage::Display, display::PROFILE_FILE)?)?
                .file("reproduction", &p(Stage::Reproduction, reproduction::FILE)?)?
                .value("result", &validate::RESULT_VERSION);
            // The compared run's files the report reads, so the report is drawn again when
            // they change; without one the hash stays as it was.
            match &opts.compare_with {
                Some(other) => {
                    let mut i = i.value("compare_with", other);
                    for (name, path) in super::report_input::compared_files(other) {
                        i = i.file(&name, &path)?;
                    }
                    i
                }
                None => i,
            }
        }
    })
}

fn run_stage(
    stage: Stage,
    opts: &ExperimentOptions,
    sd: &StageDir,
    progress: &dyn Fn(Progress),
) -> Result<Vec<String>, ExperimentError> {
    let owned = |v: Vec<&'static str>| v.into_iter().map(String::from).collect::<Vec<_>>();
    let sim_summary = || -> Result<SimulationSummary, ExperimentError> {
        read_json(&stage_path(
            opts,
            Stage::Simulation,
            simulation::SUMMARY_FILE,
        ))
    };
    match stage {
        Stage::Box => match &opts.box_source {
            BoxSource::Measure(m) => measure_box::measure(
                &sd.dir,
                m,
                opts.resume,
                opts.unattended,
                &opts.run,
                progress,
            ),
            BoxSource::Existing { .. } => Ok(Vec::new()),
        },
        Stage::Simulation => {
            let (scene, _) = box_files(opts);
            let (_, files) = cancellable(opts.run.interrupt.as_ref(), || {
                match &opts.simulation.external_image {
                    Some(image) => super::external_image::read_back(
                        &scene,
                        image,
                        &opts.simulation,
                        &sd.dir,
                        progress,
                    ),
                    None => simulate(&scene, &opts.simulation, &sd.dir, progress),
                }
            })?;
            Ok(owned(files))
        }
        Stage::Display => {
            let targets: Vec<Xyz> = sim_summary()?.spots.iter().map(|s| s.xyz).collect();
            let (_, files) = characterize_display(
                &sd.dir,
                &opts.display,
                &targets,
                opts.resume,
                opts.unattended,
                &opts.run,
                progress,
            )?;
            Ok(owned(files))
        }
        Stage::Reproduction => {
            let profile = Profile::load(&stage_path(opts, Stage::Display, display::PROFILE_FILE))?;
            let sim = sim_summary()?;
            let image = sim
                .image
                .as_ref()
                .map(|f| stage_path(opts, Stage::Simulation, f));
            let (_, files) = reproduce(
                &sd.dir,
                &profile,
                &sim.spots,
                image.as_deref().map(|p| (p, sim.image_patches.as_slice())),
                &opts.reproduction,
            )?;
            Ok(owned(files))
        }
        Stage::DisplaySpots => Ok(owned(display_spots_stage(opts, sd, progress)?)),
        Stage::Validation => validation_stage(opts, sd),
    }
}

/// The display-spots stage: the reproduction shown and read, each patch by the rule
/// the options give.
fn display_spots_stage(
    opts: &ExperimentOptions,
    sd: &StageDir,
    progress: &dyn Fn(Progress),
) -> Result<Vec<&'static str>, ExperimentError> {
    let r: Reproduction = read_json(&stage_path(opts, Stage::Reproduction, reproduction::FILE))?;
    let setting: DisplaySetting =
        read_json(&stage_path(opts, Stage::Display, display::SETTING_FILE))?;
    let png = stage_path(opts, Stage::Reproduction, reproduction::IMAGE_FILE);
    let rule = match opts.until_decided {
        Some(margin) => {
            let (_, box_spots) = box_files(opts);
            let profile = Profile::load(&stage_path(opts, Stage::Display, display::PROFILE_FILE))?;
            let box_readings = super::readings::read_readings(&box_spots)?;
            display_spots::DisplayRule::verdict(
                margin,
                opts.repeats,
                &box_readings,
                profile.white_xyz,
            )
        }
        None => display_spots::DisplayRule::Fixed(opts.repeats),
    };
    let session = display_spots::SpotSession {
        setting: &setting,
        spot_spec: &opts.display.spot,
        drives: &r.patches,
        image: (png.exists() && !r.image_patches.is_empty()).then(|| display_spots::ShownImage {
            file: &png,
            regions: &r.image_patches,
        }),
        shown: opts.spots_shown,
        rule: &rule,
        resume: opts.resume,
        unattended: opts.unattended,
        run: &opts.run,
    };
    let (_, files) = display_spots::measure(&sd.dir, &session, progress)?;
    Ok(files)
}

/// The validation stage: the box, the simulation and the display compared.
fn validation_stage(
    opts: &ExperimentOptions,
    sd: &StageDir,
) -> Result<Vec<String>, ExperimentError> {
    let (_, box_spots) = box_files(opts);
    let profile = Profile::load(&stage_path(opts, Stage::Display, display::PROFILE_FILE))?;
    let r: Reproduction = read_json(&stage_path(opts, Stage::Reproduction, reproduction::FILE))?;
    let sim_spots = stage_path(opts, Stage::Simulation, simulation::SPOTS_FILE);
    let display_spots = stage_path(opts, Stage::DisplaySpots, display_spots::SPOTS_FILE);
    let files = ReadingFiles {
        box_readings: &box_spots,
        display: &display_spots,
        simulation: Some(&sim_spots),
    };
    let (_, written) = validate::validate(
        &sd.dir,
        profile.white_xyz,
        &files,
        &r.out_of_gamut_patches,
        opts.compare_with.as_deref(),
    )?;
    Ok(written)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::display::ModelKind;
    use crate::experiment::display::DisplayOptions;
    use crate::experiment::measuring::{MeasuringChoices, MeasuringPlan};
    use crate::experiment::reproduction::ReproductionOptions;
    use crate::experiment::simulation::SimulationOptions;
    use crate::session::RunOptions;

    /// Options for a box given as files, on the simulated ips-lcd at no simulated time.
    pub(crate) fn given(dir: &Path, scene: PathBuf, spots: PathBuf) -> ExperimentOptions {
        ExperimentOptions {
            dir: dir.to_path_buf(),
            measuring: Default::default(),
            box_source: BoxSource::Existing { scene, spots },
            given_readings: None,
            simulation: SimulationOptions {
                external_image: None,
                target_de: 0.5,
                seed: 1,
                max_seconds: 60.0,
                image: None,
            },
            display: DisplayOptions {
                screen: ScreenSpec::Virtual(crate::rig::Preset::IpsLcd),
                spot: "sim:cs100a?time_scale=0".into(),
                model: ModelKind::MatrixLsq,
                adaptive: None,
            },
            reproduction: ReproductionOptions {
                gamut: crate::display::gamut::GamutMapping::Clip,
                mirror: true,
            },
            repeats: 1,
            until_decided: None,
            spots_shown: Default::default(),
            compare_with: None,
            stage: None,
            resume: false,
            unattended: true,
            run: RunOptions::default(),
        }
    }

    /// A box given as files that are not there is named as the user's file, before any
    /// stage runs (not as a file "an earlier stage writes").
    #[test]
    fn a_given_box_that_does_not_exist_is_named_before_any_stage() {
        let dir = std::env::temp_dir().join(format!("metamer-stages-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let scene = dir.join("scene.json");
        std::fs::write(&scene, "{}").unwrap();
        let missing = dir.join("nope.csv");
        let e = run(
            &given(&dir.join("exp"), scene.clone(), missing.clone()),
            &|_| {},
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("spot readings") && e.contains("nope.csv") && e.contains("does not exist"),
            "{e}"
        );
        let e = run(
            &given(&dir.join("exp"), dir.join("gone.json"), missing),
            &|_| {},
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("scene") && e.contains("gone.json"), "{e}");
        assert!(!dir.join("exp").exists(), "nothing was started");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// The lab with the measuring plan `plan`, each of `choices` in place of its own, as
    /// the command makes it.
    fn lab(plan: MeasuringPlan, choices: &MeasuringChoices) -> crate::experiment::lab::LabOptions {
        let m = plan.expand(choices);
        crate::experiment::lab::LabOptions {
            measuring: plan,
            scenario: crate::rig::Scenario::default(),
            display: crate::rig::Preset::IpsLcd,
            model: ModelKind::Lut,
            gamut: crate::display::gamut::GamutMapping::NearestLab,
            target_de: 0.1,
            repeats: m.repeats,
            until_decided: m.until_decided,
            compare_with: None,
            plan: None,
            box_repeats: None,
            box_adaptive: m.box_adaptive,
            box_spot_rule: m.box_spot_rule,
            seed: 1,
            time_scale: 0.0,
            image_size: 0,
            adaptive: m.display,
            spots_shown: m.spots_shown,
        }
    }

    /// The lean measuring plan is its options chosen one by one: the measuring stages'
    /// fingerprints (their inputs' hashes, upstream files alike) are the same, and none is
    /// the paper's plan's. The box's spots are read a fixed count, which needs no white.
    #[test]
    fn the_lean_plan_has_the_fingerprints_of_its_options_chosen_one_by_one() {
        let dir = std::env::temp_dir().join(format!("metamer-measuring-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        for (stage, file) in [
            (Stage::Box, measure_box::SPOTS_FILE),
            (Stage::Simulation, simulation::SPOTS_FILE),
            (Stage::Simulation, simulation::SUMMARY_FILE),
            (Stage::Display, display::SETTING_FILE),
            (Stage::Display, display::PROFILE_FILE),
            (Stage::Reproduction, reproduction::FILE),
        ] {
            let d = dir.join(stage.name());
            std::fs::create_dir_all(&d).unwrap();
            std::fs::write(d.join(file), file).unwrap();
        }
        let by_hand = MeasuringChoices {
            box_adaptive: Some(true),
            box_spot_rule: Some(crate::validation::sequential::RepeatRule::Fixed { repeats: 3 }),
            display_adaptive: Some(true),
            stop_de: Some(2.0),
            max_readings: Some(56),
            held_out: Some(12),
            repeats: Some(2),
            until_decided: Some(0.0),
            spots_shown: Some(display_spots::SpotsShown::UnderMeter),
            ..MeasuringChoices::default()
        };
        let fingerprints = |o: &crate::experiment::lab::LabOptions| {
            let options = o
                .request(&dir, false, false, RunOptions::default())
                .options()
                .unwrap();
            [Stage::Box, Stage::Display, Stage::DisplaySpots]
                .map(|s| inputs_of(s, &options).unwrap().0)
        };
        let lean = fingerprints(&lab(MeasuringPlan::Lean, &MeasuringChoices::default()));
        let chosen = fingerprints(&lab(MeasuringPlan::Paper, &by_hand));
        let paper = fingerprints(&lab(MeasuringPlan::Paper, &MeasuringChoices::default()));
        assert_eq!(lean, chosen);
        for (l, p) in lean.iter().zip(&paper) {
            assert_ne!(l, p);
        }
        let options = lab(MeasuringPlan::Lean, &MeasuringChoices::default())
            .request(&dir, false, false, RunOptions::default())
            .options()
            .unwrap();
        let BoxSource::Measure(m) = &options.box_source else {
            panic!("the lab measures its box")
        };
        assert_eq!(m.spot_white, None);
        assert_eq!(options.measuring, MeasuringPlan::Lean);
        // A width rule stops on CIELAB, so it is given the simulated monitor's full white.
        let width = MeasuringChoices {
            box_spot_rule: Some(crate::validation::sequential::RepeatRule::Width {
                half_width_jnd: 0.3,
                most: 10,
            }),
            ..MeasuringChoices::default()
        };
        let options = lab(MeasuringPlan::Lean, &width)
            .request(&dir, false, false, RunOptions::default())
            .options()
            .unwrap();
        let BoxSource::Measure(m) = &options.box_source else {
            panic!("the lab measures its box")
        };
        let white = crate::rig::VirtualPanel::preset(crate::rig::Preset::IpsLcd).xyz([255; 3]);
        assert_eq!(m.spot_white, Some([white.x, white.y, white.z]));
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
