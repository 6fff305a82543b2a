//! The validation box, simulated: with no real box at hand, the box is its scene. A spot
//! render refined well below the meter's repeatability stands for the light at each
//! ColorChecker patch, and aiming the box at a patch puts that light in front of the
//! simulated meter, which then reads it, with its noise, as the paper's meter read the real
//! patches.

use std::sync::Arc;

use metamer_drivers::SharedWorld;

use crate::render::spot::SpotError;
use crate::render::{render_spots_with_progress, Scene, SpotOptions, SpotProgress, SpotResult};

/// The box could not be simulated or aimed.
#[derive(Debug, thiserror::Error)]
pub enum SimBoxError {
    #[error("rendering the box: {0}")]
    Render(#[from] SpotError),
    #[error("the box has no ColorChecker patch {patch}; its patches are {first}–{last}")]
    NoSuchPatch {
        patch: usize,
        first: usize,
        last: usize,
    },
    #[error("the box's render has no patches")]
    Empty,
}

/// A rendered box and the light a simulated meter aimed into it sees.
pub struct SimBox {
    truth: SpotResult,
    light: Arc<SharedWorld>,
}

impl SimBox {
    /// Renders the light at every patch of `scene` with `opts` (its `target_de` sets how far
    /// below the meter's noise the render lies) and drives `light`, which the simulated
    /// meter looks at; it shows black until [`SimBox::aim`].
    pub fn render(
        scene: &Scene,
        opts: &SpotOptions,
        light: Arc<SharedWorld>,
        progress: &dyn Fn(SpotProgress),
    ) -> Result<SimBox, SimBoxError> {
        let truth = render_spots_with_progress(scene, opts, progress)?;
        SimBox::from_render(truth, light)
    }

    /// A box from an existing render.
    pub fn from_render(truth: SpotResult, light: Arc<SharedWorld>) -> Result<SimBox, SimBoxError> {
        if truth.patches.is_empty() {
            return Err(SimBoxError::Empty);
        }
        light.set([0.0; 3]);
        Ok(SimBox { truth, light })
    }

    /// Aims the meter at ColorChecker patch `patch` (numbered as in the scene, 1–24): the
    /// meter sees that patch's light until the next aim.
    pub fn aim(&self, patch: usize) -> Result<(), SimBoxError> {
        let reading = self
            .truth
            .patches
            .iter()
            .find(|p| p.patch == patch)
            .ok_or_else(|| SimBoxError::NoSuchPatch {
                patch,
                first: self.patches().next().unwrap_or(0),
                last: self.patches().last().unwrap_or(0),
            })?;
        self.light.set(reading.xyz);
        Ok(())
    }

    /// The patch numbers, in the render's order.
    pub fn patches(&self) -> impl Iterator<Item = usize> + '_ {
        self.truth.patches.iter().map(|p| p.patch)
    }

    /// The render standing for the box's light (before the meter).
    pub fn truth(&self) -> &SpotResult {
        &self.truth
    }

    /// The light the box drives; give it to the simulated meter.
    pub fn light(&self) -> &Arc<SharedWorld> {
        &self.light
    }
}

#[cfg(test)]
mod tests {
    use metamer_drivers::{open_instrument, Request};

    use super::*;
    use crate::render::spot::PatchReading;

    fn reading(patch: usize, xyz: [f64; 3]) -> PatchReading {
        PatchReading {
            patch,
            xyz,
            xyz_stderr: [0.0; 3],
            lab: [0.0; 3],
            de_ci95: 0.0,
            samples: 1,
        }
    }

    /// A noiseless meter aimed at each patch reads that patch's light, to the CS-100A's
    /// printed precision (4 significant digits of Y, 4 decimals of x and y).
    #[test]
    fn the_meter_reads_the_patch_aimed_at() {
        let lights = [(3, [20.0, 21.0, 22.0]), (7, [41.2, 35.0, 5.5])];
        let truth = SpotResult {
            white: [95.0, 100.0, 108.0],
            seconds: 0.0,
            patches: lights.iter().map(|&(p, xyz)| reading(p, xyz)).collect(),
            converged: true,
        };
        let light = Arc::new(SharedWorld::new([1.0; 3]));
        let sim_box = SimBox::from_render(truth, light.clone()).unwrap();
        let mut meter = open_instrument("sim:cs100a?time_scale=0&noise=off", Some(light)).unwrap();
        for (patch, want) in lights {
            sim_box.aim(patch).unwrap();
            let got = meter.measure(&Request::default()).unwrap().xyz;
            assert!(
                (got[1] - want[1]).abs() / want[1] < 1e-3,
                "{got:?} vs {want:?}"
            );
            let x = |v: [f64; 3]| v[0] / (v[0] + v[1] + v[2]);
            assert!((x(got) - x(want)).abs() < 1e-4, "{got:?} vs {want:?}");
        }
        let e = sim_box.aim(19).unwrap_err().to_string();
        assert_eq!(
            e,
            "the box has no ColorChecker patch 19; its patches are 3–7"
        );
        assert_eq!(sim_box.patches().collect::<Vec<_>>(), [3, 7]);
    }
}
