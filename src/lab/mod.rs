//! The simulated lab: the paper's whole validation chain (Bärz, Henrich, Müller, Fig. 1) on
//! simulated hardware, so it runs on any machine and every stage is exercised end to end.
//!
//! 1. The box: the validation-box scene read patch by patch with the simulated CS-100A
//!    ([`crate::rig::sim_box`]).
//! 2. The simulation: the spectral path tracer's 24 spot readings (paper Eq. 8).
//! 3. The display: a simulated monitor whose peak luminance is set so the rendered values
//!    fit (the paper sets the display's maximum luminance; no tone mapping), characterized
//!    by the same `characterize` session a real monitor gets.
//! 4. Reproduction: each simulated XYZ through the inverse display model (Eq. 9 or a
//!    richer model) to 8-bit drive values, shown and read with the meter.
//! 5. Validation: display vs box (the paper's question), simulation vs box and display vs
//!    simulation, in CIELAB relative to the box's reference white, with the JND count.

mod box_side;
mod display_side;
mod error;
mod meter;
mod scenario;

pub use box_side::{read_box_and_simulate, SceneReadings};
pub use error::LabError;
pub use scenario::Scenario;

use std::path::{Path, PathBuf};
use std::sync::Arc;

use metamer_drivers::{open_instrument, SharedWorld};
use serde::Serialize;

pub use display_side::{
    characterize, reproduce_and_measure, stimulus_of, white_luminance_for, Reproduced,
};

use crate::color::Xyz;
use crate::display::characterize::finish::Summary;
use crate::display::gamut::GamutMapping;
use crate::display::ModelKind;
use crate::output::OutputPolicy;
use crate::render::{Scene, SceneError, SpotOptions, SpotProgress};
use crate::rig::{Preset, Screen, VirtualDisplay, VirtualPanel};
use crate::validation::{compare, write_delta_e_chart_shaded, Comparison};

/// What a lab run is made of.
#[derive(Clone, Debug, Serialize)]
pub struct LabOptions {
    /// The box scene file; None: the built-in box of `scenario`.
    pub scene: Option<PathBuf>,
    /// The named box the lab measures when no scene file is given.
    pub scenario: Option<Scenario>,
    /// The simulated monitor.
    #[serde(serialize_with = "preset_name")]
    pub display: Preset,
    pub model: ModelKind,
    #[serde(serialize_with = "display_string")]
    pub gamut: GamutMapping,
    /// The simulation's target: 95 % half-width of every patch's ΔE*ab.
    pub target_de: f64,
    /// Meter readings averaged per ColorChecker patch, in the box and on the display (the
    /// display characterization reads each of its patches once, as `characterize` does).
    pub repeats: usize,
    pub seed: u64,
    /// The simulated meter's time scale (1 = the CS-100A's real ≈100 ms per reading).
    pub time_scale: f64,
}

fn preset_name<S: serde::Serializer>(p: &Preset, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_str(p.name())
}

fn display_string<S: serde::Serializer, T: std::fmt::Display>(
    v: &T,
    s: S,
) -> Result<S::Ok, S::Error> {
    s.collect_str(v)
}

/// Where the lab run is, for a progress display.
#[derive(Clone, Copy, Debug)]
pub enum LabProgress<'a> {
    /// A stage begins.
    Stage(&'a str),
    /// The renderer's progress on the current stage.
    Render(SpotProgress),
    /// Readings done of a measuring stage.
    Readings { done: usize, total: usize },
}

/// One patch through the whole chain.
#[derive(Clone, Debug, Serialize)]
pub struct LabPatch {
    pub patch: usize,
    /// The meter's reading in the box, cd/m².
    pub box_xyz: [f64; 3],
    /// The simulation's spot reading and its 95 % ΔE*ab half-width.
    pub simulation_xyz: [f64; 3],
    pub simulation_de_ci95: f64,
    pub display: Reproduced,
}

/// Everything a lab run found.
#[derive(Clone, Debug, Serialize)]
pub struct LabResult {
    pub options: LabOptions,
    /// CIELAB's reference white: the perfect diffuser in place of patch 19, rendered.
    pub white_xyz: [f64; 3],
    /// The simulated monitor's full-white luminance chosen so the rendering fits.
    pub display_white_cd_m2: f64,
    pub render_seconds: f64,
    pub seconds: f64,
    pub display_characterization: Summary,
    pub out_of_gamut: usize,
    pub patches: Vec<LabPatch>,
    pub display_vs_box: Comparison,
    pub simulation_vs_box: Comparison,
    pub display_vs_simulation: Comparison,
}

/// The files a lab run leaves in its directory.
pub const LAB_FILE: &str = "lab.json";
/// The display characterization's own directory inside the lab's.
pub const DISPLAY_DIR: &str = "display";

/// The comparison files and `lab.json` a finished run leaves in `dir`.
pub fn result_files(dir: &Path) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = [
        "display_vs_box",
        "simulation_vs_box",
        "display_vs_simulation",
    ]
    .iter()
    .flat_map(|stem| [format!("{stem}.csv"), format!("{stem}.svg")])
    .map(|f| dir.join(f))
    .collect();
    files.push(dir.join(LAB_FILE));
    files
}

/// The finished run in `dir` made with `opts`, if there is one: its `lab.json`. Resuming
/// it has nothing left to do, so nothing is rendered or measured again. A finished run
/// made with other options is an error naming the first that differs.
pub fn finished_run(dir: &Path, opts: &LabOptions) -> Result<Option<PathBuf>, LabError> {
    let file = dir.join(LAB_FILE);
    let text = match std::fs::read_to_string(&file) {
        Ok(t) => t,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(e) => {
            return Err(LabError::BadResult {
                file,
                message: e.to_string(),
            })
        }
    };
    let bad = |message: String| LabError::BadResult {
        file: file.clone(),
        message,
    };
    let logged: serde_json::Value = serde_json::from_str(&text).map_err(|e| bad(e.to_string()))?;
    let logged = logged
        .get("options")
        .and_then(|o| o.as_object())
        .ok_or_else(|| bad("no options".into()))?;
    let now = serde_json::to_value(opts).expect("lab options serialize");
    let now = now.as_object().expect("lab options are an object");
    let shown = |v: Option<&serde_json::Value>| match v {
        Some(serde_json::Value::String(s)) => s.clone(),
        Some(v) => v.to_string(),
        None => "(not set)".into(),
    };
    for name in now.keys().chain(logged.keys()) {
        let (a, b) = (logged.get(name), now.get(name));
        // Numbers compare by value: 0.5 and 0.50 are the same target.
        let same = match (a.and_then(|v| v.as_f64()), b.and_then(|v| v.as_f64())) {
            (Some(x), Some(y)) => x == y,
            _ => a == b,
        };
        if !same {
            return Err(LabError::OptionDiffers {
                dir: dir.to_path_buf(),
                option: name.clone(),
                logged: shown(a),
                now: shown(b),
            });
        }
    }
    Ok(Some(file))
}

/// Runs the whole chain into `dir`. With `resume`, an interrupted display characterization
/// in `dir` is continued; without it, a directory holding an earlier run is refused.
pub fn run_lab(
    dir: &Path,
    opts: &LabOptions,
    resume: bool,
    progress: &dyn Fn(LabProgress),
) -> Result<LabResult, LabError> {
    let start = std::time::Instant::now();
    if !resume && (dir.join(LAB_FILE).exists() || dir.join(DISPLAY_DIR).exists()) {
        return Err(LabError::Exists {
            dir: dir.to_path_buf(),
        });
    }
    let scene = match &opts.scene {
        Some(path) => Scene::load(path)?,
        None => {
            let scenario = opts.scenario.unwrap_or(Scenario::DisplayWhite);
            Scene::builtin(scenario.builtin_name()).map_err(|source| SceneError::Invalid {
                file: format!("(built-in {} box)", scenario.name()).into(),
                source,
            })?
        }
    };
    let spot = SpotOptions {
        target_de: opts.target_de,
        seed: opts.seed,
        ..SpotOptions::default()
    };
    let meter_spec = |seed: u64| format!("sim:cs100a?time_scale={}&seed={seed}", opts.time_scale);

    // 1–2: the box and the simulation.
    let box_light = Arc::new(SharedWorld::new([0.0; 3]));
    let mut box_meter = open_instrument(&meter_spec(opts.seed), Some(box_light.clone()))?;
    let stage = std::cell::Cell::new("");
    let scene_readings = read_box_and_simulate(
        &scene,
        &spot,
        box_meter.as_mut(),
        &box_light,
        opts.repeats,
        &|name, p| {
            if stage.get() != name {
                stage.set(name);
                progress(LabProgress::Stage(name));
            }
            if let Some(p) = p {
                progress(LabProgress::Render(p));
            }
        },
    )?;
    let render_seconds = scene_readings.box_truth.seconds + scene_readings.simulation.seconds;
    let white = Xyz::from_array(scene_readings.box_truth.white);
    let simulated: Vec<[f64; 3]> = scene_readings
        .simulation
        .patches
        .iter()
        .map(|p| p.xyz)
        .collect();

    // 3: the display, bright enough for the rendering, characterized.
    let panel = VirtualPanel::preset(opts.display);
    let display_white_cd_m2 = white_luminance_for(&panel, &simulated);
    let mut display = VirtualDisplay::new(panel.with_white_luminance(display_white_cd_m2));
    let display_spec = meter_spec(opts.seed.wrapping_add(1));
    let mut display_meter = open_instrument(&display_spec, Some(stimulus_of(&display)?))?;
    progress(LabProgress::Stage("characterizing the display"));
    let (profile, summary) = characterize(
        &dir.join(DISPLAY_DIR),
        &mut display,
        display_meter.as_mut(),
        &display_spec,
        opts.model,
        resume,
        &|done, total| progress(LabProgress::Readings { done, total }),
    )?;

    // 4: the simulation shown and read.
    progress(LabProgress::Stage("showing the simulation on the display"));
    let reproduced = reproduce_and_measure(
        &mut display as &mut dyn Screen,
        display_meter.as_mut(),
        &profile,
        opts.gamut,
        white,
        &simulated,
        opts.repeats,
    )?;

    // 5: validation.
    let xyz = |v: &[[f64; 3]]| v.iter().map(|&c| Xyz::from_array(c)).collect::<Vec<_>>();
    let box_xyz = xyz(&scene_readings.box_xyz);
    let sim_xyz = xyz(&simulated);
    let shown: Vec<[f64; 3]> = reproduced.iter().map(|r| r.measured_xyz).collect();
    let shown_xyz = xyz(&shown);
    let display_vs_box = compare("box", &box_xyz, "display", &shown_xyz, white)?;
    let simulation_vs_box = compare("box", &box_xyz, "simulation", &sim_xyz, white)?;
    let display_vs_simulation = compare("simulation", &sim_xyz, "display", &shown_xyz, white)?;
    let patches = reproduced
        .into_iter()
        .enumerate()
        .map(|(i, display)| LabPatch {
            patch: i + 1,
            box_xyz: scene_readings.box_xyz[i],
            simulation_xyz: simulated[i],
            simulation_de_ci95: scene_readings.simulation.patches[i].de_ci95,
            display,
        })
        .collect::<Vec<_>>();
    Ok(LabResult {
        options: opts.clone(),
        white_xyz: white.to_array(),
        display_white_cd_m2,
        render_seconds,
        seconds: start.elapsed().as_secs_f64(),
        display_characterization: summary,
        out_of_gamut: patches.iter().filter(|p| p.display.out_of_gamut).count(),
        patches,
        display_vs_box,
        simulation_vs_box,
        display_vs_simulation,
    })
}

impl LabResult {
    /// The three comparisons with their file stems.
    pub fn comparisons(&self) -> [(&'static str, &Comparison); 3] {
        [
            ("display_vs_box", &self.display_vs_box),
            ("simulation_vs_box", &self.simulation_vs_box),
            ("display_vs_simulation", &self.display_vs_simulation),
        ]
    }

    /// Writes `lab.json` and each comparison as CSV and SVG chart into `dir`.
    /// Every file is checked under the output policy `out` before the first is written.
    pub fn write(&self, dir: &Path, out: &OutputPolicy) -> Result<Vec<PathBuf>, LabError> {
        out.dir(dir)?;
        for f in result_files(dir) {
            out.check(&f)?;
        }
        let mut written = Vec::new();
        for (stem, c) in self.comparisons() {
            let csv = dir.join(format!("{stem}.csv"));
            out.write(&csv, c.to_csv().as_bytes())?;
            let svg = dir.join(format!("{stem}.svg"));
            // Simulation vs box involves no display: nothing to shade there.
            let shaded: Vec<usize> = if stem == "simulation_vs_box" {
                Vec::new()
            } else {
                self.patches
                    .iter()
                    .filter(|p| p.display.out_of_gamut)
                    .map(|p| p.patch)
                    .collect()
            };
            write_delta_e_chart_shaded(c, &shaded, "outside the display's gamut", &svg, out)?;
            written.extend([csv, svg]);
        }
        let json = dir.join(LAB_FILE);
        let text = serde_json::to_string_pretty(self).expect("lab results serialize");
        // Last: lab.json is what marks the run finished.
        out.write(&json, text.as_bytes())?;
        written.push(json);
        Ok(written)
    }
}
