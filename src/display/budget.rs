//! Speed against accuracy for display characterization: how well each
//! model reproduces colours on each simulated monitor as the number of measured patches
//! grows.
//!
//! Every measured patch costs the user a reading (≈0.1–0.5 s with a CS-100A, more with
//! settling), so the cost axis is the patch count. For each budget the patch set is the
//! one `characterize` would measure with that many ramp steps, plus, from the larger budgets
//! on, an evenly spaced RGB cube that the models which do not assume additivity need. The
//! patches are read by the simulated CS-100A with its noise (±0.2 % in Y, ±0.001 in x, y),
//! every model is fitted to the same readings, and the fit is judged as reproduction is
//! used: for in-gamut targets (the noiseless XYZ of seeded random drive values) the model's
//! inverse gives drive values, the monitor shows them (8-bit), and ΔE00 between what it
//! shows and the target is the error (CIELAB relative to the monitor's true white).

use std::sync::Arc;
use std::time::Instant;

use metamer_drivers::{Request, SharedWorld, Spec};
use serde::Serialize;

use super::characterize::plan::random_patches;
use super::characterize::{default_grid_steps, DriveStep, Plan, PlanOptions, Purpose};
use super::diagnostics::percentile;
use super::model::Sample;
use super::scattered::scattered_patches;
use super::{fit_profile, ModelKind};
use crate::color::{delta_e2000, Xyz};
use crate::output::{OutputError, OutputPolicy};
use crate::plot::{log_log_svg, LogLogChart, Series};
use crate::rig::virtual_display::{Preset, VirtualPanel};

/// The series name of the ramp-only plan with a grid added.
pub const RAMPS_PLUS_GRID: &str = "ramps+grid";

/// One patch budget: ramp steps per channel (including 0 and full drive) and the points
/// per axis of the RGB cube (0 for none).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct Budget {
    pub ramp_steps: usize,
    pub cube: usize,
}

/// The ramp steps charted. Each model gets the plan `characterize` would measure for it
/// with that many steps: the ramps, plus for the LUT the grid of the ramps' levels (see
/// [`default_grid_steps`]), so a model's curve is what a user of that model pays.
pub const RAMP_STEPS: [usize; 8] = [2, 3, 4, 5, 7, 9, 13, 17];

/// Sizes of the seeded space-filling sets (the cube's corners and a rotated Halton
/// sequence, like ArgyllCMS's `targen` spreads them) charted for the models that fit any
/// patch set; they are charted as `MODEL scattered`.
pub const SCATTERED_SIZES: [usize; 3] = [50, 200, 1000];

/// The models that fit scattered sets: the joint shaper + matrix and the LUT fitted by
/// regularised least squares (a grid-only model needs the grid, a ramp model ramps).
pub const SCATTERED_MODELS: [ModelKind; 2] = [ModelKind::ShaperMatrix, ModelKind::Lut];

/// The models charted on the ramp-only plan with a grid added ([`ADDED_GRIDS`]): PLVC, the
/// best a ramp-only set supports, and the LUT, which learns the mixtures the grid measures.
pub const MIXTURE_MODELS: [ModelKind; 2] = [ModelKind::Plvc, ModelKind::Lut];

/// Points per axis of the grids added to the ramp-only plan (0: none); charted as
/// `MODEL ramps+grid`.
pub const ADDED_GRIDS: [usize; 5] = [0, 2, 3, 4, 5];

/// The paper's and PsychoPy's plan: black, white and 16 steps of each primary (1/16 … 16/16
/// of full drive as 8-bit codes), 50 patches and no mixture but the white.
pub fn ramp_only_plan() -> Vec<[u8; 3]> {
    let mut codes = vec![[0, 0, 0], [255, 255, 255]];
    for c in 0..3 {
        for k in 1..=16u32 {
            let mut rgb = [0u8; 3];
            rgb[c] = (f64::from(255 * k) / 16.0).round() as u8;
            codes.push(rgb);
        }
    }
    codes
}

/// [`ramp_only_plan`] plus an evenly spaced `grid`³ grid of the drive cube (the codes
/// `characterize --grid-steps` measures), without measuring a code twice.
pub fn ramps_with_grid(grid: usize) -> Vec<[u8; 3]> {
    let mut codes = ramp_only_plan();
    if grid >= 2 {
        let level = |i: usize| (255.0 * i as f64 / (grid - 1) as f64).round() as u8;
        for r in 0..grid {
            for g in 0..grid {
                for b in 0..grid {
                    let rgb = [level(r), level(g), level(b)];
                    if !codes.contains(&rgb) {
                        codes.push(rgb);
                    }
                }
            }
        }
    }
    codes
}

/// The budget of `model` with `ramp_steps` steps.
pub fn budget_for(model: ModelKind, ramp_steps: usize) -> Budget {
    Budget {
        ramp_steps,
        cube: default_grid_steps(model, ramp_steps),
    }
}

/// The drive values `characterize` measures for a budget, in order (the fit patches of its
/// plan: black, primaries, white, ramps, grid, and black, primaries and white once more),
/// and how many distinct patches they are.
pub fn budget_patches(b: Budget) -> (Vec<[u8; 3]>, usize) {
    let plan = Plan::new(PlanOptions {
        ramp_steps: b.ramp_steps,
        repeats: 1,
        grid_steps: b.cube,
    })
    .expect("budgets are valid plans");
    let fit = |p: &&DriveStep| p.purpose == Purpose::Fit;
    let distinct = plan.distinct.iter().filter(fit).count();
    (
        plan.patches.iter().filter(fit).map(|p| p.rgb).collect(),
        distinct,
    )
}

/// One point of the chart.
#[derive(Clone, Debug, Serialize)]
pub struct BudgetPoint {
    pub preset: String,
    pub model: String,
    pub patches: usize,
    pub ramp_steps: usize,
    pub cube: usize,
    /// ΔE00 of reproduced targets, pooled over the trials: mean, 95th percentile, maximum.
    pub mean_de00: f64,
    pub p95_de00: f64,
    pub max_de00: f64,
    /// Mean time of one fit, milliseconds.
    pub fit_ms: f64,
}

/// What the study could not do.
#[derive(Debug, thiserror::Error)]
pub enum BudgetError {
    #[error("the simulated meter failed: {0}")]
    Meter(#[from] metamer_drivers::DriverError),
    #[error("{0}")]
    Output(#[from] OutputError),
    #[error("cannot draw {file}: {message}")]
    Chart {
        file: std::path::PathBuf,
        message: String,
    },
}

/// Runs the study on `presets` with `models`, each budget measured `trials` times;
/// `progress` gets (done, total) as each model is finished at each budget.
pub fn run_budget_study(
    presets: &[Preset],
    models: &[ModelKind],
    trials: usize,
    seed: u64,
    progress: &dyn Fn(usize, usize),
) -> Result<Vec<BudgetPoint>, BudgetError> {
    let targets_rgb = random_patches(200, seed ^ 0xB0D6E7);
    let scattered: Vec<ModelKind> = models
        .iter()
        .copied()
        .filter(|k| SCATTERED_MODELS.contains(k))
        .collect();
    let mixture: Vec<ModelKind> = models
        .iter()
        .copied()
        .filter(|k| MIXTURE_MODELS.contains(k))
        .collect();
    let total = presets.len()
        * (RAMP_STEPS.len() * models.len()
            + SCATTERED_SIZES.len() * scattered.len()
            + ADDED_GRIDS.len() * mixture.len());
    let mut done = 0;
    let mut points = Vec::new();
    for &preset in presets {
        let panel = VirtualPanel::preset(preset);
        let white = panel.xyz([255; 3]);
        let targets: Vec<Xyz> = targets_rgb.iter().map(|&c| panel.xyz(c)).collect();
        let stimulus = Arc::new(SharedWorld::new([0.0; 3]));
        let mut meter = cs100a_at_once(seed).open(Some(stimulus.clone()))?;
        let mut study = Study {
            panel: &panel,
            white,
            targets: &targets,
            stimulus: &stimulus,
            meter: meter.as_mut(),
            trials: trials.max(1),
        };
        for &kind in models {
            for steps in RAMP_STEPS {
                done += 1;
                let budget = budget_for(kind, steps);
                let (drive, distinct) = budget_patches(budget);
                let outcome = study.measure(kind, &drive)?;
                progress(done, total);
                if let Some((errors, fit_ms)) = outcome {
                    points.push(point(
                        preset,
                        kind.name().to_string(),
                        distinct,
                        budget,
                        errors,
                        fit_ms,
                    ));
                }
            }
        }
        for &kind in &scattered {
            for n in SCATTERED_SIZES {
                done += 1;
                let drive = scattered_patches(n, seed);
                let outcome = study.measure(kind, &drive)?;
                progress(done, total);
                if let Some((errors, fit_ms)) = outcome {
                    let none = Budget {
                        ramp_steps: 0,
                        cube: 0,
                    };
                    points.push(point(
                        preset,
                        format!("{kind} scattered"),
                        n,
                        none,
                        errors,
                        fit_ms,
                    ));
                }
            }
        }
    }
    let mut done_before = done;
    points.extend(run_mixture_study(
        presets,
        &mixture,
        trials,
        seed,
        &|d, _| {
            progress(done_before + d, total);
        },
    )?);
    done_before += presets.len() * ADDED_GRIDS.len() * mixture.len();
    debug_assert_eq!(done_before, total);
    Ok(points)
}

/// The ramp-only plan with each of [`ADDED_GRIDS`] added, fitted with `models` (those of
/// [`MIXTURE_MODELS`]), each set read `trials` times by a meter seeded with `seed` (its own
/// meter, so these points do not depend on what else the study measured); `progress` gets
/// (done, total).
pub fn run_mixture_study(
    presets: &[Preset],
    models: &[ModelKind],
    trials: usize,
    seed: u64,
    progress: &dyn Fn(usize, usize),
) -> Result<Vec<BudgetPoint>, BudgetError> {
    let targets_rgb = random_patches(200, seed ^ 0xB0D6E7);
    let total = presets.len() * ADDED_GRIDS.len() * models.len();
    let mut done = 0;
    let mut points = Vec::new();
    for &preset in presets {
        let panel = VirtualPanel::preset(preset);
        let targets: Vec<Xyz> = targets_rgb.iter().map(|&c| panel.xyz(c)).collect();
        let stimulus = Arc::new(SharedWorld::new([0.0; 3]));
        let mut meter = cs100a_at_once(seed).open(Some(stimulus.clone()))?;
        let mut study = Study {
            panel: &panel,
            white: panel.xyz([255; 3]),
            targets: &targets,
            stimulus: &stimulus,
            meter: meter.as_mut(),
            trials: trials.max(1),
        };
        for &kind in models {
            for grid in ADDED_GRIDS {
                done += 1;
                let drive = ramps_with_grid(grid);
                let outcome = study.measure(kind, &drive)?;
                progress(done, total);
                if let Some((errors, fit_ms)) = outcome {
                    let budget = Budget {
                        ramp_steps: 17,
                        cube: grid,
                    };
                    points.push(point(
                        preset,
                        format!("{kind} {RAMPS_PLUS_GRID}"),
                        drive.len(),
                        budget,
                        errors,
                        fit_ms,
                    ));
                }
            }
        }
    }
    Ok(points)
}

/// One monitor, its meter and the reproduction targets.
struct Study<'a> {
    panel: &'a VirtualPanel,
    white: Xyz,
    targets: &'a [Xyz],
    stimulus: &'a SharedWorld,
    meter: &'a mut dyn metamer_drivers::Instrument,
    trials: usize,
}

impl Study<'_> {
    /// Reads `drive` `trials` times (fresh meter noise each time; errors pooled so one lucky
    /// or unlucky reading of a primary does not make the curve), fits `kind` to each set and
    /// returns the reproduction errors and the mean fit time in ms; None when the model
    /// needs more than the set has.
    fn measure(
        &mut self,
        kind: ModelKind,
        drive: &[[u8; 3]],
    ) -> Result<Option<(Vec<f64>, f64)>, BudgetError> {
        let mut errors = Vec::with_capacity(self.targets.len() * self.trials);
        let mut fit_ms = 0.0;
        for _ in 0..self.trials {
            let mut patches = Vec::with_capacity(drive.len());
            for rgb in drive {
                self.stimulus.set(self.panel.xyz(*rgb));
                let reading = self.meter.measure(&Request::default())?;
                patches.push(Sample {
                    rgb: rgb.map(|c| f64::from(c) / 255.0),
                    xyz: reading.xyz,
                });
            }
            let start = Instant::now();
            let Ok(profile) = fit_profile(kind, &patches, None) else {
                return Ok(None);
            };
            fit_ms += start.elapsed().as_secs_f64() * 1e3;
            errors.extend(self.targets.iter().map(|&t| {
                let rgb = profile.inverse(t).rgb;
                let shown = self.panel.xyz_of_drive(rgb);
                delta_e2000(shown.to_lab(self.white), t.to_lab(self.white))
            }));
        }
        Ok(Some((errors, fit_ms / self.trials as f64)))
    }
}

fn point(
    preset: Preset,
    model: String,
    patches: usize,
    budget: Budget,
    mut errors: Vec<f64>,
    fit_ms: f64,
) -> BudgetPoint {
    errors.sort_by(f64::total_cmp);
    BudgetPoint {
        preset: preset.name().to_string(),
        model,
        patches,
        ramp_steps: budget.ramp_steps,
        cube: budget.cube,
        mean_de00: errors.iter().sum::<f64>() / errors.len() as f64,
        p95_de00: percentile(&errors, 0.95),
        max_de00: errors[errors.len() - 1],
        fit_ms,
    }
}

/// Writes `budget.csv` and one SVG chart per preset (`budget-PRESET.svg`) into `dir`
/// under the output policy `out`; every file is checked before the first is written, so a
/// refusal leaves the directory as it was.
pub fn write_budget(
    dir: &std::path::Path,
    points: &[BudgetPoint],
    out: &OutputPolicy,
) -> Result<(), BudgetError> {
    out.dir(dir)?;
    let csv = dir.join("budget.csv");
    // Each preset once, in the order of its first point: the study lists the mixture
    // points after every preset's own, so a preset's points are not adjacent, and writing
    // its chart twice would refuse the file the run itself had just written.
    let mut presets: Vec<&str> = Vec::new();
    for p in points {
        if !presets.contains(&p.preset.as_str()) {
            presets.push(&p.preset);
        }
    }
    out.check(&csv)?;
    for preset in &presets {
        out.check(&dir.join(format!("budget-{preset}.svg")))?;
    }
    let mut text =
        String::from("preset,model,patches,ramp_steps,cube,mean_de00,p95_de00,max_de00,fit_ms\n");
    for p in points {
        text.push_str(&format!(
            "{},{},{},{},{},{:.4},{:.4},{:.4},{:.3}\n",
            p.preset,
            p.model,
            p.patches,
            p.ramp_steps,
            p.cube,
            p.mean_de00,
            p.p95_de00,
            p.max_de00,
            p.fit_ms
        ));
    }
    out.write(&csv, text.as_bytes())?;
    for preset in presets {
        let mut models: Vec<&str> = points
            .iter()
            .filter(|p| p.preset == preset)
            .map(|p| p.model.as_str())
            .collect();
        models.sort();
        models.dedup();
        let series: Vec<Series> = models
            .iter()
            .map(|m| {
                let mut pts: Vec<(f64, f64)> = points
                    .iter()
                    .filter(|p| p.preset == preset && p.model == *m)
                    .map(|p| (p.patches as f64, p.mean_de00))
                    .collect();
                pts.sort_by(|a, b| a.0.total_cmp(&b.0));
                Series {
                    name: m.to_string(),
                    points: pts,
                }
            })
            .collect();
        let title = format!("{preset}: mean ΔE00 of reproduced colours vs measured patches");
        let file = dir.join(format!("budget-{preset}.svg"));
        let chart = LogLogChart {
            title: &title,
            x_desc: "measured patches",
            y_desc: "mean ΔE00 (200 in-gamut targets)",
            series: &series,
            target: Some((0.5, "ΔE00 0.5")),
            size: (900, 520),
        };
        let svg = log_log_svg(&chart).map_err(|message| BudgetError::Chart {
            file: file.clone(),
            message,
        })?;
        out.write(&file, svg.as_bytes())?;
    }
    Ok(())
}

/// The simulated CS-100A at no delay, its noise drawn from `seed`.
fn cs100a_at_once(seed: u64) -> Spec {
    Spec::simulated("cs100a")
        .with_option("time_scale", 0)
        .with_option("seed", seed)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Sample counts by hand: ramps of s steps give black + 4 (s − 1); a cube of g points per
    /// axis adds g³ minus what the ramps already hold; five of them are read twice.
    #[test]
    fn budget_patch_counts_match_a_hand_count() {
        let count = |ramp_steps, cube| {
            let (drive, distinct) = budget_patches(Budget { ramp_steps, cube });
            assert_eq!(drive.len(), distinct + 5);
            distinct
        };
        assert_eq!(count(2, 0), 5);
        assert_eq!(count(3, 0), 9);
        assert_eq!(count(9, 0), 33);
        // Ramps of 3 hold black, the 3 primaries, white, the 3 half-level channels and the
        // half grey: 9 of the 27 points of a 3-cube.
        assert_eq!(count(3, 3), 27);
        // Ramps of 2 hold black, 3 primaries and white: 5 of the 8 corners of a 2-cube.
        assert_eq!(count(2, 2), 8);
    }

    #[test]
    fn targets_are_fixed_and_spread() {
        let a = random_patches(200, 7);
        assert_eq!(a, random_patches(200, 7));
        let mean: f64 = a.iter().map(|c| f64::from(c[0])).sum::<f64>() / 200.0;
        assert!((mean - 127.5).abs() < 15.0, "{mean}");
    }

    /// The study lists each preset's ramp and scattered points, then the mixture points of
    /// every preset: points of one preset that are not adjacent still make one chart, and
    /// nothing is written twice (a second chart of a preset was refused as an existing
    /// file, after minutes of study).
    #[test]
    fn interleaved_presets_make_one_chart_each() {
        let dir = std::env::temp_dir().join(format!("metamer-budget-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let pt = |preset: &str, model: &str, patches: usize, mean: f64| BudgetPoint {
            preset: preset.into(),
            model: model.into(),
            patches,
            ramp_steps: 3,
            cube: 0,
            mean_de00: mean,
            p95_de00: mean,
            max_de00: mean,
            fit_ms: 1.0,
        };
        let points = [
            pt("ideal-crt", "plcc", 9, 0.1),
            pt("ips-lcd", "plcc", 9, 1.0),
            pt("ideal-crt", "lut ramps+grid", 50, 0.2),
            pt("ips-lcd", "lut ramps+grid", 50, 0.5),
        ];
        write_budget(&dir, &points, &OutputPolicy::new(false)).unwrap();
        let mut files: Vec<String> = std::fs::read_dir(&dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        files.sort();
        assert_eq!(
            files,
            ["budget-ideal-crt.svg", "budget-ips-lcd.svg", "budget.csv"]
        );
        let crt = std::fs::read_to_string(dir.join("budget-ideal-crt.svg")).unwrap();
        assert!(crt.contains("lut ramps+grid") && crt.contains("plcc"));
        let csv = std::fs::read_to_string(dir.join("budget.csv")).unwrap();
        assert_eq!(csv.lines().count(), 1 + points.len());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    /// On the display that satisfies PLCC, PLCC reproduces colours within the error the
    /// meter's noise and 8-bit quantisation allow once its ramps are dense enough.
    #[test]
    fn plcc_reproduces_the_ideal_crt_within_the_noise() {
        let points =
            run_budget_study(&[Preset::IdealCrt], &[ModelKind::Plcc], 2, 3, &|_, _| {}).unwrap();
        let best = points
            .iter()
            .filter(|p| p.ramp_steps >= 9)
            .map(|p| p.mean_de00)
            .fold(f64::MAX, f64::min);
        assert!(best < 0.5, "PLCC on ideal-crt: mean ΔE00 {best}");
    }
}
