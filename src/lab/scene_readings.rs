//! The box side of the simulated lab: the 24 ColorChecker readings "in the real box" and
//! the simulation of the same readings.
//!
//! With no real box at hand, the box is the scene itself: a spot render refined well below
//! the meter's repeatability stands for the light in the box, and the simulated CS-100A
//! reads it, with its noise, as the paper's meter read the real patches. The simulation is
//! an independent render (another seed) at the user's target accuracy, as `metamer render
//! spots` gives it. The two therefore differ by meter noise and Monte Carlo error only,
//! which is what a perfect model of the box would leave.

use std::sync::Arc;

use metamer_drivers::{Instrument, Request, SharedWorld};

use crate::render::{render_spots_with_progress, Scene, SpotOptions, SpotProgress, SpotResult};

use super::LabError;

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
    let box_truth = render_spots_with_progress(scene, &truth_opts, &|p| {
        progress("rendering the box (truth)", Some(p))
    })?;
    progress("simulating the 24 spot readings", None);
    let simulation = render_spots_with_progress(scene, opts, &|p| {
        progress("simulating the 24 spot readings", Some(p))
    })?;
    progress("reading the box with the meter", None);
    let truths: Vec<[f64; 3]> = box_truth.patches.iter().map(|p| p.xyz).collect();
    let box_xyz = measure_each(meter, stimulus, &truths, repeats)?;
    Ok(SceneReadings {
        box_xyz,
        box_truth,
        simulation,
    })
}

/// Puts each light in front of the meter and averages `repeats` readings of it.
pub fn measure_each(
    meter: &mut dyn Instrument,
    stimulus: &SharedWorld,
    lights: &[[f64; 3]],
    repeats: usize,
) -> Result<Vec<[f64; 3]>, LabError> {
    lights
        .iter()
        .map(|&xyz| {
            stimulus.set(xyz);
            mean_reading(meter, repeats)
        })
        .collect()
}

/// The mean XYZ of `repeats` (at least one) readings of whatever the meter sees now.
pub fn mean_reading(meter: &mut dyn Instrument, repeats: usize) -> Result<[f64; 3], LabError> {
    let repeats = repeats.max(1);
    let mut sum = [0.0; 3];
    for _ in 0..repeats {
        let r = meter.measure(&Request::default())?;
        sum.iter_mut().zip(r.xyz).for_each(|(s, v)| *s += v);
    }
    Ok(sum.map(|s| s / repeats as f64))
}

#[cfg(test)]
mod tests {
    use super::*;
    use metamer_drivers::open_instrument;

    /// The noiseless simulated meter returns what it is shown, to the CS-100A's printed
    /// precision (4 significant digits of Y, 4 decimals of x and y).
    #[test]
    fn a_noiseless_meter_reads_back_each_light() {
        let stimulus = Arc::new(SharedWorld::new([0.0; 3]));
        let mut meter =
            open_instrument("sim:cs100a?time_scale=0&noise=off", Some(stimulus.clone())).unwrap();
        let lights = [[20.0, 21.0, 22.0], [41.2, 35.0, 5.5]];
        let got = measure_each(meter.as_mut(), &stimulus, &lights, 3).unwrap();
        for (g, l) in got.iter().zip(&lights) {
            assert!((g[1] - l[1]).abs() / l[1] < 1e-3, "{g:?} vs {l:?}");
            let (gx, lx) = (g[0] / (g[0] + g[1] + g[2]), l[0] / (l[0] + l[1] + l[2]));
            assert!((gx - lx).abs() < 1e-4, "{g:?} vs {l:?}");
        }
    }
}
