//! The validation box as a scene file for the renderers, from a geometry, the materials and
//! the light: the contract of `docs/validation-box.md` with every dimension taken from the
//! plan's [`Geometry`]. The simulated box and the measured scene are both built here, so
//! they differ only in what was measured.
//!
//! The light is one emitter over the opening whose tiles carry their own absolute spectral
//! radiance (W·sr⁻¹·m⁻²·nm⁻¹ along the normal, gain 1): tile (0, 0) at the top front
//! corner, `edge_u` along the columns towards the back (C = 0°), `edge_v` along the rows
//! downwards (C = 90°), so the normal points into the box and the fall-off planes are the
//! distribution's C planes.

use serde_json::{json, Value};

use super::plan::Geometry;
use crate::color::{Outside, Spectrum};
use crate::render::scene::{DistributionFile, SceneFile};
use crate::render::Scene;

/// The chart's frame (mm): 204 wide (along z) × 291 high, 1 mm off the wall.
const FRAME_W_M: f64 = 0.204;
const FRAME_H_M: f64 = 0.291;
const FRAME_OFF_M: f64 = 0.001;
/// Patches: 40 mm squares on a 46 mm pitch, 1.5 mm off the wall.
const PATCH_M: f64 = 0.040;
const PITCH_M: f64 = 0.046;
const PATCH_OFF_M: f64 = 0.0015;
/// The frame's flat reflectance (docs/validation-box.md); not measured.
pub const FRAME_REFLECTANCE: f64 = 0.03;

/// What fills the box.
#[derive(Clone, Debug)]
pub struct BoxContents {
    /// The wall paper's reflectance.
    pub wall: Spectrum,
    /// Reflectances of ColorChecker patches 1–24, in order.
    pub patches: Vec<Spectrum>,
    /// Each tile's spectral radiance along the normal, row-major (row 0 at the top).
    pub tiles: Vec<Spectrum>,
    pub distribution: DistributionFile,
    /// Where the contents come from (any JSON object), carried into the file.
    pub provenance: Option<Value>,
}

fn inline(s: &Spectrum) -> Value {
    json!({
        "nm": s.wavelengths_nm(),
        "values": s.values(),
        "outside": match s.outside() { Outside::Zero => "zero", Outside::HoldEnds => "hold_ends" },
    })
}

fn surface(name: &str, corner: [f64; 3], u: [f64; 3], v: [f64; 3], refl: Value) -> Value {
    json!({"name": name, "corner": corner, "edge_u": u, "edge_v": v, "reflectance": refl})
}

/// The chart's centre on the right wall.
pub fn chart_centre(g: &Geometry) -> [f64; 3] {
    [g.size_m - FRAME_OFF_M, g.size_m / 2.0, g.size_m / 2.0]
}

/// The measured scene's camera image, width and height in pixels: the paper's 1014².
pub const CAMERA_PIXELS: [usize; 2] = [1014, 1014];

/// The scene file of the box.
pub fn scene_json(name: &str, description: &str, g: &Geometry, c: &BoxContents) -> Value {
    let mut surfaces = walls(g, &inline(&c.wall));
    surfaces.extend(chart(g, &c.patches));
    let centre = chart_centre(g);
    let mut file = json!({
        "name": name,
        "description": description,
        "surfaces": surfaces,
        "emitters": [emitter(g, c)],
        "camera": {
            "position": g.viewpoint_m,
            "look_at": centre,
            "up": [0.0, 1.0, 0.0],
            "vfov_deg": 15.71,
            "width": CAMERA_PIXELS[0],
            "height": CAMERA_PIXELS[1],
        },
        "meter": {"acceptance_deg": g.acceptance_deg},
    });
    if let Some(p) = &c.provenance {
        file["provenance"] = p.clone();
    }
    file
}

/// The box's five walls in the wall paper `wall`: the left one around the light opening,
/// in up to four pieces.
fn walls(g: &Geometry, wall: &Value) -> Vec<Value> {
    let s = g.size_m;
    let [y0, y1, z0, z1] = g.light_m;
    let mut surfaces = vec![
        surface(
            "floor",
            [0.0, 0.0, 0.0],
            [0.0, 0.0, s],
            [s, 0.0, 0.0],
            wall.clone(),
        ),
        surface(
            "ceiling",
            [0.0, s, 0.0],
            [s, 0.0, 0.0],
            [0.0, 0.0, s],
            wall.clone(),
        ),
        surface(
            "back wall",
            [0.0, 0.0, s],
            [0.0, s, 0.0],
            [s, 0.0, 0.0],
            wall.clone(),
        ),
        surface(
            "right wall",
            [s, 0.0, 0.0],
            [0.0, 0.0, s],
            [0.0, s, 0.0],
            wall.clone(),
        ),
    ];
    let left = [
        (
            "left wall below the light",
            [0.0, 0.0, 0.0],
            [0.0, y0, 0.0],
            [0.0, 0.0, s],
        ),
        (
            "left wall above the light",
            [0.0, y1, 0.0],
            [0.0, s - y1, 0.0],
            [0.0, 0.0, s],
        ),
        (
            "left wall in front of the light",
            [0.0, y0, 0.0],
            [0.0, y1 - y0, 0.0],
            [0.0, 0.0, z0],
        ),
        (
            "left wall behind the light",
            [0.0, y0, z1],
            [0.0, y1 - y0, 0.0],
            [0.0, 0.0, s - z1],
        ),
    ];
    for (n, corner, u, v) in left {
        let area = (u[1] * v[2]).abs();
        if area > 1e-12 {
            surfaces.push(surface(n, corner, u, v, wall.clone()));
        }
    }
    surfaces
}

/// The ColorChecker on the right wall: its frame, then the patches of `patches` (1–24 in
/// order) in four rows of six.
fn chart(g: &Geometry, patches: &[Spectrum]) -> Vec<Value> {
    let s = g.size_m;
    let centre = chart_centre(g);
    let mut surfaces = vec![surface(
        "chart frame",
        [
            centre[0],
            centre[1] - FRAME_H_M / 2.0,
            centre[2] - FRAME_W_M / 2.0,
        ],
        [0.0, 0.0, FRAME_W_M],
        [0.0, FRAME_H_M, 0.0],
        json!(FRAME_REFLECTANCE),
    )];
    for (i, refl) in patches.iter().enumerate() {
        let (r, col) = ((i / 6) as f64, (i % 6) as f64);
        let z = centre[2] + (r - 1.5) * PITCH_M;
        let y = centre[1] + (2.5 - col) * PITCH_M;
        let mut p = surface(
            &format!("patch {}", i + 1),
            [s - PATCH_OFF_M, y - PATCH_M / 2.0, z - PATCH_M / 2.0],
            [0.0, 0.0, PATCH_M],
            [0.0, PATCH_M, 0.0],
            inline(refl),
        );
        p["patch"] = json!(i + 1);
        surfaces.push(p);
    }
    surfaces
}

/// The light: one emitter over the opening, its tiles' spectra and its distribution.
fn emitter(g: &Geometry, c: &BoxContents) -> Value {
    let [y0, y1, z0, z1] = g.light_m;
    let tiles: Vec<Value> = c
        .tiles
        .iter()
        .enumerate()
        .map(|(i, spectrum)| {
            json!({"row": i / g.cols, "col": i % g.cols, "gain": 1.0, "spectrum": inline(spectrum)})
        })
        .collect();
    json!({
        "corner": [0.0, y1, z0],
        "edge_u": [0.0, 0.0, z1 - z0],
        "edge_v": [0.0, y0 - y1, 0.0],
        "rows": g.rows,
        "cols": g.cols,
        "tiles": tiles,
        "distribution": c.distribution,
    })
}

/// A scene file that does not make a scene: a fault of this module, said with the JSON
/// path the renderer names.
#[derive(Debug, thiserror::Error)]
#[error("the box's scene is not a valid scene: {0}")]
pub struct BuildError(pub String);

/// The render-ready scene of a scene file.
pub fn build(value: &Value) -> Result<Scene, BuildError> {
    let file: SceneFile =
        serde_json::from_value(value.clone()).map_err(|e| BuildError(e.to_string()))?;
    Scene::build(&file, std::path::Path::new("."))
        .map_err(|e| BuildError(format!("{}: {}", e.path, e.message)))
}

/// The centre of ColorChecker patch `patch` (1–24) on the chart, as [`chart`] places it.
pub fn patch_centre(g: &Geometry, patch: usize) -> [f64; 3] {
    let i = patch.saturating_sub(1);
    let (r, col) = ((i / 6) as f64, (i % 6) as f64);
    let centre = chart_centre(g);
    [
        g.size_m - PATCH_OFF_M,
        centre[1] + (2.5 - col) * PITCH_M,
        centre[2] + (r - 1.5) * PITCH_M,
    ]
}

/// The centre of tile (row, col) of the light, as [`emitter`] lays the tiles out.
pub fn tile_centre(g: &Geometry, row: usize, col: usize) -> [f64; 3] {
    let [y0, y1, z0, z1] = g.light_m;
    [
        0.0,
        y1 - (row as f64 + 0.5) * (y1 - y0) / g.rows as f64,
        z0 + (col as f64 + 0.5) * (z1 - z0) / g.cols as f64,
    ]
}
