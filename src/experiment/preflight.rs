//! What an experiment can know before its first reading or rendering, checked first: a
//! plan the fall-off fit or the validation cannot use, a user's files that a stage would
//! replace, another renderer's image the simulation cannot read back, a screen that cannot
//! be reached or a meter that cannot see it, fail now with the reason instead of after
//! hours of measuring. Each stage states its own checks; this calls them all, in the
//! order of the stages.

use std::path::Path;

use super::error::ExperimentError;
use super::measure_box::MeasureBox;
use super::options::{BoxSource, ExperimentOptions};
use super::readings::{read_readings, ReadingSet};
use super::stage::Stage;
use crate::measure_box::BoxPlan;
use crate::render::Scene;

/// Every check, in the order a user would fix them.
pub fn check(opts: &ExperimentOptions) -> Result<(), ExperimentError> {
    given_files_outside_stages(opts)?;
    let camera = match &opts.box_source {
        BoxSource::Measure(m) => {
            measured_box(m)?;
            Some(crate::measure_box::scene::CAMERA_PIXELS)
        }
        BoxSource::Existing { scene, spots } => {
            given_box(scene, spots, opts.given_readings.as_ref())?
        }
    };
    let runs = |stage: Stage| opts.stage.is_none_or(|s| s == stage);
    if runs(Stage::Simulation) {
        let dir = opts.dir.join(Stage::Simulation.name());
        super::simulation::preflight(&opts.simulation, camera, &dir)?;
    }
    if runs(Stage::Display) || runs(Stage::DisplaySpots) {
        super::display::preflight(&opts.display)?;
    }
    Ok(())
}

/// A given box's files may not lie in a stage directory the run writes or moves aside:
/// the stage would replace them (`--box-spots ex/simulation/spots.csv --stage simulation`
/// overwrote the box's readings with simulated ones).
fn given_files_outside_stages(opts: &ExperimentOptions) -> Result<(), ExperimentError> {
    let BoxSource::Existing { scene, spots } = &opts.box_source else {
        return Ok(());
    };
    for stage in Stage::ALL {
        // A given box's own stage runs only when asked for by name.
        if stage == Stage::Box && opts.stage != Some(Stage::Box) {
            continue;
        }
        let Ok(dir) = std::fs::canonicalize(opts.dir.join(stage.name())) else {
            continue;
        };
        for (what, file) in [("scene", scene), ("spot readings", spots)] {
            if std::fs::canonicalize(file).is_ok_and(|f| f.starts_with(&dir)) {
                return Err(ExperimentError::GivenInStage {
                    what,
                    file: file.clone(),
                    stage: stage.name(),
                    dir: opts.dir.join(stage.name()),
                });
            }
        }
    }
    Ok(())
}

/// The plan's own rules (the fall-off angles the fit needs among them), and the patches:
/// the measured scene holds the whole chart, so the simulation renders all 24 patches,
/// the display shows them, and the validation compares the box's spots with each.
fn measured_box(m: &MeasureBox) -> Result<(), ExperimentError> {
    let bad = |e: &dyn std::fmt::Display| ExperimentError::Box(e.to_string());
    let mut plan = match &m.plan {
        Some(p) => BoxPlan::load(p).map_err(|e| bad(&e))?,
        None => BoxPlan::default(),
    };
    if let Some(n) = m.repeats {
        plan.repeats = n;
    }
    plan.validate().map_err(|e| bad(&e))?;
    let mut patches = plan.patches.clone();
    patches.sort_unstable();
    if patches != (1..=24).collect::<Vec<_>>() {
        return Err(ExperimentError::Box(format!(
            "plan{}: patches: the experiment validates every patch of the chart (the simulation renders all 24 and the display shows them, and each is compared with the box's spot reading), but the plan reads the spots of only {patches:?}: list all 24 patches, or leave `patches` out of the plan",
            shown(m.plan.as_deref())
        )));
    }
    Ok(())
}

fn shown(plan: Option<&Path>) -> String {
    plan.map(|p| format!(" {}", p.display()))
        .unwrap_or_default()
}

/// A given box's readings (`given`: as the request's checks read them, else read here, by
/// the validation's reader either way) must hold the patches its scene has, which are
/// those the simulation renders and the validation compares. Returns the size of the
/// scene's camera image, if it has a camera. Whatever else the validation
/// stage needs of the file its reader checks: patches 1–24 (or `white`), finite and
/// plausible values; a repeated row is a repeat of its patch.
fn given_box(
    scene: &Path,
    spots: &Path,
    given: Option<&ReadingSet>,
) -> Result<Option<[usize; 2]>, ExperimentError> {
    let s = Scene::load(scene)?;
    let in_scene: Vec<usize> = (1..=24).filter(|&k| s.patch_surface(k).is_some()).collect();
    let read_here;
    let set = match given {
        Some(set) => set,
        None => {
            read_here = read_readings(spots)?;
            &read_here
        }
    };
    let read: Vec<usize> = set.patches.keys().copied().collect();
    if read != in_scene {
        return Err(ExperimentError::GivenPatchesDiffer {
            spots: spots.to_path_buf(),
            read,
            scene: scene.to_path_buf(),
            in_scene,
        });
    }
    Ok(s.camera.map(|c| [c.width, c.height]))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A given box's spot readings are taken in every form the validation stage reads,
    /// and must still hold the patches of its scene.
    #[test]
    fn a_given_box_is_read_as_the_validation_reads_it() {
        let exp = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/report/experiment");
        let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/scenes/validation-box.json");
        let rows: Vec<Vec<String>> = std::fs::read_to_string(exp.join("box/spots.csv"))
            .unwrap()
            .lines()
            .skip(1)
            .map(|r| r.split(',').take(4).map(String::from).collect())
            .collect();
        assert_eq!(rows.len(), 24);
        let dir = std::env::temp_dir().join(format!("metamer-preflight-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let plain = dir.join("plain.csv");
        let csv: String = rows.iter().map(|r| r.join(",") + "\n").collect();
        std::fs::write(&plain, format!("patch,X,Y,Z\n{csv}")).unwrap();
        let spot_json = dir.join("spot.jsonl");
        let lines: String = rows
            .iter()
            .map(|r| {
                format!(
                    "{{\"patch\":{},\"XYZ\":[{},{},{}]}}\n",
                    r[0], r[1], r[2], r[3]
                )
            })
            .collect();
        std::fs::write(&spot_json, lines).unwrap();
        for file in [&plain, &spot_json] {
            given_box(&scene, file, None).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
        }
        // Read once by the request's checks and passed in: the same verdict.
        let set = read_readings(&plain).unwrap();
        given_box(&scene, &plain, Some(&set)).unwrap();
        // Patch 24 left out: the scene has it, the readings do not.
        let short = dir.join("short.csv");
        let first23: String = rows[..23].iter().map(|r| r.join(",") + "\n").collect();
        std::fs::write(&short, format!("patch,X,Y,Z\n{first23}")).unwrap();
        match given_box(&scene, &short, None) {
            Err(ExperimentError::GivenPatchesDiffer { read, in_scene, .. }) => {
                assert_eq!(read, (1..=23).collect::<Vec<_>>());
                assert_eq!(in_scene, (1..=24).collect::<Vec<_>>());
            }
            other => panic!("{other:?}"),
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
