//! The measured scene rendered (radiosity: deterministic, with its own error bound) and
//! compared, patch by patch in CIELAB, with the box's spot readings: how well the
//! measurement describes the box. The reference white is the render's (a perfect diffuser
//! in place of patch 19, as `render spots` takes it), the same for both sides, so a
//! luminance error counts as well as a colour error.

use serde::{Deserialize, Serialize};
use serde_json::Value;

use super::scene::{build, BuildError};
use crate::color::{Xyz, COLORCHECKER_NAMES};
use crate::render::radiosity::{render_spots_radiosity, RadiosityError, RadiosityOptions};
use crate::render::spot::RenderedReading;
use crate::validation::{compare, Comparison, ValidationError};

/// The render's accuracy target, ΔE*ab: far below the meter's noise (≈ 0.1 ΔE*ab).
pub const RENDER_TARGET_DE: f64 = 0.02;

/// The box's spot readings against the render of a scene.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct RenderComparison {
    /// box = the spot readings (reference), render = the scene rendered (test).
    pub comparison: Comparison,
    /// The render's ΔE*ab error bound per compared patch.
    pub render_bound: Vec<f64>,
    pub render_seconds: f64,
}

/// The render or comparison failed.
#[derive(Debug, thiserror::Error)]
pub enum CompareError {
    #[error(transparent)]
    Build(#[from] BuildError),
    #[error("rendering the measured scene: {0}")]
    Render(#[from] RadiosityError),
    #[error("comparing the render with the spot readings: {0}")]
    Validation(#[from] ValidationError),
    #[error("the render has no patch {0}")]
    NoPatch(usize),
}

/// The 24 readings of a scene file by the radiosity solver, its reference white and the
/// seconds it took.
pub fn render_scene(scene: &Value) -> Result<(Vec<RenderedReading>, Xyz, f64), CompareError> {
    let scene = build(scene)?;
    let opts = RadiosityOptions {
        target_de: RENDER_TARGET_DE,
        ..RadiosityOptions::default()
    };
    let r = render_spots_radiosity(&scene, &opts, &|_| {})?;
    Ok((r.patches, r.white, r.seconds))
}

/// Compares `box_xyz` (patch, XYZ) with `rendered` in CIELAB relative to `white`.
pub fn compare_readings(
    box_xyz: &[(usize, Xyz)],
    rendered: &[RenderedReading],
    white: Xyz,
    test: &str,
) -> Result<(Comparison, Vec<f64>), CompareError> {
    let mut reference = Vec::new();
    let mut test_xyz = Vec::new();
    let mut bound = Vec::new();
    for &(patch, xyz) in box_xyz {
        let r = rendered
            .iter()
            .find(|r| r.patch == patch)
            .ok_or(CompareError::NoPatch(patch))?;
        reference.push(xyz);
        test_xyz.push(r.xyz);
        bound.push(r.uncertainty.de_ab());
    }
    let mut c = compare("box", &reference, test, &test_xyz, white)?;
    // compare() numbers patches by position; a plan may read only some of them.
    for (p, &(patch, _)) in c.patches.iter_mut().zip(box_xyz) {
        p.patch = patch;
        p.name = COLORCHECKER_NAMES[patch - 1].to_string();
    }
    Ok((c, bound))
}

/// Renders `scene` and compares it with the box's spot readings.
pub fn compare_render(
    scene: &Value,
    box_xyz: &[(usize, Xyz)],
) -> Result<RenderComparison, CompareError> {
    let (rendered, white, seconds) = render_scene(scene)?;
    let (comparison, render_bound) = compare_readings(box_xyz, &rendered, white, "measured scene")?;
    Ok(RenderComparison {
        comparison,
        render_bound,
        render_seconds: seconds,
    })
}
