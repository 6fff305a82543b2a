//! The validation box simulated for `measure-box`: a "truth" box that differs from the
//! nominal data on purpose, and an operator whose hands set what the simulated instruments
//! see for each step, so a whole box measurement runs with `sim:i1pro` and `sim:cs100a`
//! and nobody at the rig.
//!
//! The box's light is a [`Scenario`]: by default the `ips-lcd` virtual display's white, as
//! the paper's box was lit by an LCD showing white, or CIE LED-RGB1.
//!
//! How the truth differs from the nominal box (all seeded):
//! - each tile's spectrum is the light at 100 cd/m² times a gain that falls off towards the
//!   panel's edges (6 % at the corners), tilts across it (+4 % towards the back, −3 %
//!   towards the top) and varies 1 % (1σ) from tile to tile, times a spectral tilt
//!   1 + k·(λ − 560 nm)/220 nm with k from −0.09 to +0.09 across the panel: a
//!   colour-temperature gradient. Every patch sees the whole panel, so the gradient
//!   averages out at the patches: under the display's white, dropping it moves no patch's
//!   linear drives on the `ips-lcd` by more than 2·10⁻⁴ of full drive (seeds 1–3), and it
//!   is kept. What does put two patches on the edge of that display's gamut is physics,
//!   not the tilt: a surface filters each primary's spectrum, and a filtered primary need
//!   not lie inside the primaries' triangle — the yellow patch (16) lies just past its
//!   red–green edge (linear blue drive −0.001 to −0.005 of full, seeds 1–3), the cyan (18)
//!   just inside it but beyond what the panel's crosstalk leaves reachable;
//! - the light's distribution is asymmetric: cos^0.9 γ towards the back (C = 0°), cos^1.4
//!   downwards (C = 90°), cos^0.6 towards the front (C = 180°), cos^1.1 upwards (C = 270°);
//! - the wall paper and the 24 ColorChecker patches are the `data/` reflectances times
//!   1 + a smooth seeded perturbation (three sines over 380–780 nm, 2 % amplitude each, 1σ),
//!   clamped to [0, 1].
//!
//! What the instruments see: on a tile, its spectral radiance; on a material, its
//! reflectance under the instrument's lamp; at a fall-off angle, the fall-off tile's
//! radiance times f(C, γ); aimed at a patch from the viewpoint, the patch's light as the
//! radiosity solver renders the truth box with its asymmetric C-γ table (the same table the
//! fall-off readings see).

use std::collections::HashMap;
use std::sync::{Arc, OnceLock};

use metamer_drivers::{CalibrationCondition, SharedWorld, View};

use super::compare::{render_scene, CompareError};
use super::plan::{BoxPlan, BoxStage, Target};
use super::scene::{scene_json, BoxContents};
use crate::color::{colorchecker, luminance, paper_white, ColorCheckerSet, Outside, Spectrum, Xyz};
use crate::light::{CGammaError, CGammaTable};
use crate::render::scene::DistributionFile;
use crate::rig::Scenario;
use crate::session::{Answer, Operator, OperatorError};
use metamer_drivers::noise::SplitMix64;

/// The truth box could not be made.
#[derive(Debug, thiserror::Error)]
pub enum SimulatedBoxError {
    #[error("the simulated box's distribution: {0}")]
    Table(#[from] CGammaError),
    #[error("rendering the simulated box: {0}")]
    Render(#[from] CompareError),
    #[error("the simulated box: {0}")]
    Spectrum(String),
}

/// The exponents of the truth's four half-planes, C = 0°, 90°, 180°, 270°.
pub const TRUTH_EXPONENTS: [f64; 4] = [0.9, 1.4, 0.6, 1.1];

/// A tile's luminance before its gain, cd/m², whatever the light.
pub const TILE_CD_M2: f64 = 100.0;

/// The box as it really is (in the simulation).
#[derive(Clone, Debug)]
pub struct SimulatedBox {
    /// Spectral radiance of each tile along the normal, row-major.
    pub tiles: Vec<Spectrum>,
    pub table: CGammaTable,
    pub wall: Spectrum,
    /// Patches 1–24.
    pub patches: Vec<Spectrum>,
    /// The light at each patch seen from the viewpoint, cd/m², patches 1–24: rendered when
    /// first needed ([`SimulatedBox::spots`]), since only the spots stage needs it.
    spots: OnceLock<Vec<Xyz>>,
    plan: BoxPlan,
    falloff_tile: usize,
}

const GRID: (f64, f64, f64) = (380.0, 780.0, 5.0);

fn grid_nm() -> Vec<f64> {
    let n = ((GRID.1 - GRID.0) / GRID.2).round() as usize + 1;
    (0..n).map(|i| GRID.0 + GRID.2 * i as f64).collect()
}

fn on_grid(f: impl Fn(f64) -> f64, outside: Outside) -> Result<Spectrum, SimulatedBoxError> {
    let nm = grid_nm();
    let v = nm.iter().map(|&l| f(l)).collect();
    Spectrum::new(nm, v)
        .map(|s| s.with_outside(outside))
        .map_err(|e| SimulatedBoxError::Spectrum(e.to_string()))
}

/// `base` times a smooth seeded perturbation, clamped to [0, 1].
fn perturbed(base: &Spectrum, rng: &mut SplitMix64) -> Result<Spectrum, SimulatedBoxError> {
    let terms: Vec<(f64, f64)> = (1..=3)
        .map(|_| (0.02 * rng.normal(), std::f64::consts::TAU * rng.uniform()))
        .collect();
    on_grid(
        |l| {
            let x = (l - 380.0) / 400.0 * std::f64::consts::PI;
            let p: f64 = terms
                .iter()
                .enumerate()
                .map(|(k, (a, phi))| a * ((k + 1) as f64 * x + phi).sin())
                .sum();
            (base.value_at(l) * (1.0 + p)).clamp(0.0, 1.0)
        },
        Outside::HoldEnds,
    )
}

impl SimulatedBox {
    /// The truth box of `plan`'s geometry lit by `light`, perturbed by `seed` (the same
    /// seed perturbs every light alike).
    pub fn new(
        plan: &BoxPlan,
        seed: u64,
        light: Scenario,
    ) -> Result<SimulatedBox, SimulatedBoxError> {
        let g = &plan.geometry;
        let mut rng = SplitMix64::new(seed ^ 0x6d62_6f78);
        let source = light.spectrum();
        let source = source.scaled(TILE_CD_M2 / luminance(&source));
        let half = |n: usize| ((n as f64 - 1.0) / 2.0).max(1.0);
        let mut tiles = Vec::new();
        for row in 0..g.rows {
            for col in 0..g.cols {
                let u = (col as f64 - (g.cols as f64 - 1.0) / 2.0) / half(g.cols);
                let v = (row as f64 - (g.rows as f64 - 1.0) / 2.0) / half(g.rows);
                let gain = (1.0 - 0.03 * (u * u + v * v))
                    * (1.0 + 0.04 * u + 0.03 * v)
                    * (1.0 + 0.01 * rng.normal());
                let k = 0.06 * u + 0.03 * v;
                tiles.push(on_grid(
                    |l| source.value_at(l) * gain * (1.0 + k * (l - 560.0) / 220.0),
                    Outside::Zero,
                )?);
            }
        }
        let gammas: Vec<f64> = (0..=18).map(|i| 5.0 * f64::from(i)).collect();
        let values = TRUTH_EXPONENTS
            .iter()
            .map(|m| {
                gammas
                    .iter()
                    .map(|g| g.to_radians().cos().max(0.0).powf(*m))
                    .collect()
            })
            .collect();
        let table = CGammaTable::new(vec![0.0, 90.0, 180.0, 270.0], gammas, values)?;
        let wall = perturbed(&paper_white(), &mut rng)?;
        let patches = colorchecker(ColorCheckerSet::BabelColorAverage)
            .iter()
            .map(|p| perturbed(p, &mut rng))
            .collect::<Result<Vec<_>, _>>()?;
        let [fr, fc] = plan.falloff_tile();
        let falloff_tile = fr * g.cols + fc;
        Ok(SimulatedBox {
            tiles,
            table,
            wall,
            patches,
            spots: OnceLock::new(),
            falloff_tile,
            plan: plan.clone(),
        })
    }

    /// The light at each patch 1–24 seen from the viewpoint, cd/m² (rendered on the first
    /// call).
    pub fn spots(&self) -> Result<&[Xyz], SimulatedBoxError> {
        if let Some(s) = self.spots.get() {
            return Ok(s);
        }
        let (rendered, _, _) = render_scene(&self.scene_json())?;
        Ok(self
            .spots
            .get_or_init(|| rendered.iter().map(|r| r.xyz).collect()))
    }

    /// The truth as a scene file.
    pub fn scene_json(&self) -> serde_json::Value {
        let plan = &self.plan;
        scene_json(
            "simulated validation box (truth)",
            "The simulated box's truth: drifting tile spectra, perturbed materials.",
            &plan.geometry,
            &BoxContents {
                wall: self.wall.clone(),
                patches: self.patches.clone(),
                tiles: self.tiles.clone(),
                distribution: DistributionFile::CGamma {
                    table: self.table.clone(),
                },
                provenance: None,
            },
        )
    }

    /// What an instrument placed on or aimed at `target` sees.
    pub fn view(&self, target: &Target) -> Result<View, SimulatedBoxError> {
        let plan = &self.plan;
        let drv = |e: metamer_drivers::DriverError| SimulatedBoxError::Spectrum(e.to_string());
        let cols = plan.geometry.cols;
        Ok(match target {
            Target::Tile { row, col } => {
                View::radiance(self.tiles[row * cols + col].clone()).map_err(drv)?
            }
            Target::Falloff { plane, angle_deg } => {
                let (c, g) = plane.c_gamma(*angle_deg);
                let f = self.table.at(c, g);
                View::radiance(self.tiles[self.falloff_tile].scaled(f)).map_err(drv)?
            }
            Target::Wall => View::surface(self.wall.clone()).map_err(drv)?,
            Target::Patch { patch } => {
                View::surface(self.patches.get(patch - 1).cloned().ok_or_else(|| {
                    SimulatedBoxError::Spectrum(format!("no ColorChecker patch {patch}"))
                })?)
                .map_err(drv)?
            }
            Target::Spot { patch } => {
                View::xyz(*self.spots()?.get(patch - 1).ok_or_else(|| {
                    SimulatedBoxError::Spectrum(format!("no ColorChecker patch {patch}"))
                })?)
            }
        })
    }
}

/// The simulated rig's operator: each step's prompt puts the instrument where the step
/// says (the world then shows that target), a calibration prompt puts it on its white tile
/// or caps it. Every prompt is kept.
pub struct BoxOperator {
    truth: SimulatedBox,
    world: Arc<SharedWorld>,
    targets: HashMap<String, Target>,
    pub prompts: Vec<String>,
}

impl BoxOperator {
    /// The operator of the truth box's plan, moving what `world` shows.
    pub fn new(truth: SimulatedBox, world: Arc<SharedWorld>) -> BoxOperator {
        let mut targets = HashMap::new();
        // Every target of the plan, not only its steps': an adaptive plan's later rounds
        // read targets its first pass does not.
        for stage in BoxStage::ALL {
            for target in truth.plan.targets(stage) {
                targets.entry(truth.plan.prompt(&target)).or_insert(target);
            }
        }
        BoxOperator {
            truth,
            world,
            targets,
            prompts: Vec::new(),
        }
    }

    pub fn truth(&self) -> &SimulatedBox {
        &self.truth
    }
}

impl Operator for BoxOperator {
    fn ask(&mut self, prompt: &str) -> Result<Answer, OperatorError> {
        self.prompts.push(prompt.to_string());
        if let Some(target) = self.targets.get(prompt) {
            let view = self
                .truth
                .view(target)
                .map_err(|e| OperatorError(std::io::Error::other(e.to_string())))?;
            self.world.set(view);
        } else if prompt.ends_with(&CalibrationCondition::OnWhiteTile.prompt()) {
            self.world.set(View::WhiteTile);
        } else if prompt.ends_with(&CalibrationCondition::SensorCapped.prompt()) {
            self.world.set(View::Capped);
        } else if !prompt.ends_with(&CalibrationCondition::OnTarget.prompt()) {
            return Err(OperatorError(std::io::Error::other(format!(
                "the simulated box does not know how to '{prompt}'"
            ))));
        }
        Ok(Answer::Confirmed)
    }
}
