//! The box side of the simulated lab: the 24 ColorChecker readings "in the real box" and
//! the simulation of the same readings.
//!
//! The box is the simulated one of the rig, read by the simulated CS-100A. The simulation is
//! an independent render (another seed) at the user's target accuracy, as `metamer render
//! spots` gives it. The two therefore differ by meter noise and Monte Carlo error only,
//! which is what a perfect model of the box would leave.

use std::sync::Arc;

use metamer_drivers::{Instrument, SharedWorld};

use crate::render::{render_spots_with_progress, Scene, SpotOptions, SpotProgress, SpotResult};
use crate::rig::sim_box::SimBox;

use super::error::LabError;
use super::meter::mean_reading;

/// The box's readings and the simulation's.
#[derive(Clone, Debug)]
pub struct SceneReadings {
    /// The meter's mean reading of each patch in the box, cd/m².
    pub box_xyz: Vec<[f64; 3]>,
    /// The render standing in for the box's light (before the meter).
    pub box_truth: SpotResult,
    /// The simulation: the renderer's 24 spot readings.
    pub simulation: SpotResult,
}

/// Renders the box truth and the simulation and reads the box with `meter`, which sees
/// `stimulus`. `progress` gets a line of text as each stage starts.
pub fn read_box_and_simulate(
    scene: &Scene,
    opts: &SpotOptions,
    meter: &mut dyn Instrument,
    stimulus: &Arc<SharedWorld>,
    repeats: usize,
    progress: &dyn Fn(&'static str, Option<SpotProgress>),
) -> Result<SceneReadings, LabError> {
    progress("rendering the box (truth)", None);
    let truth_opts = SpotOptions {
        // Another stream than the simulation's, so the two errors are independent.
        seed: opts
            .seed
            .wrapping_mul(0x9E37_79B9_7F4A_7C15)
            .wrapping_add(17),
        ..*opts
    };
    let sim_box = SimBox::render(scene, &truth_opts, stimulus.clone(), &|p| {
        progress("rendering the box (truth)", Some(p))
    })?;
    progress("simulating the 24 spot readings", None);
    let simulation = render_spots_with_progress(scene, opts, &|p| {
        progress("simulating the 24 spot readings", Some(p))
    })?;
    progress("reading the box with the meter", None);
    let patches: Vec<usize> = sim_box.patches().collect();
    let box_xyz = patches
        .into_iter()
        .enumerate()
        .map(|(i, patch)| {
            sim_box.aim(patch)?;
            // Patch i's noise whatever was read before (see Instrument::seek_noise).
            meter.seek_noise(i as u64);
            mean_reading(meter, repeats)
        })
        .collect::<Result<_, LabError>>()?;
    Ok(SceneReadings {
        box_xyz,
        box_truth: sim_box.truth().clone(),
        simulation,
    })
}
