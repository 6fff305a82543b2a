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

pub use box_side::{read_box_and_simulate, SceneReadings};
pub use error::LabError;

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
use crate::render::{Scene, SceneError, SpotOptions, SpotProgress};
use crate::rig::{Preset, Screen, VirtualDisplay, VirtualPanel};
use crate::validation::{compare, write_delta_e_chart_shaded, Comparison};

/// What a lab run is made of.
#[derive(Clone, Debug, Serialize)]
pub struct LabOptions {
    /// The box scene file; None: the built-in validation box.
    pub scene: Option<PathBuf>,
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
        None => crate::render::scene::builtin::validation_box().map_err(|source| {
            SceneError::Invalid {
                file: "(built-in validation box)".into(),
                source,
            }
        })?,
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
    pub fn write(&self, dir: &Path) -> Result<Vec<PathBuf>, LabError> {
        let io = |file: &Path| {
            let file = file.to_path_buf();
            move |source| LabError::Write { file, source }
        };
        std::fs::create_dir_all(dir).map_err(io(dir))?;
        let mut written = Vec::new();
        for (stem, c) in self.comparisons() {
            let csv = dir.join(format!("{stem}.csv"));
            std::fs::write(&csv, c.to_csv()).map_err(io(&csv))?;
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
            write_delta_e_chart_shaded(c, &shaded, "outside the display's gamut", &svg)?;
            written.extend([csv, svg]);
        }
        let json = dir.join(LAB_FILE);
        let text = serde_json::to_string_pretty(self).expect("lab results serialize");
        std::fs::write(&json, text).map_err(io(&json))?;
        written.push(json);
        Ok(written)
    }
}
