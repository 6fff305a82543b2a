//! What the export's writers share: the renderers, one written file, the emitter's tiles
//! as both renderers write them, and how numbers and wavelengths are printed.

use std::path::PathBuf;

use super::approximation::Approximation;
use crate::render::scene::Scene;

/// The renderers a scene can be exported to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Renderer {
    /// Mitsuba 3, a spectral variant (`scalar_spectral`).
    Mitsuba3,
    /// pbrt-v4 (spectral by construction).
    PbrtV4,
}

impl Renderer {
    /// The name `--to` takes.
    pub fn name(self) -> &'static str {
        match self {
            Renderer::Mitsuba3 => "mitsuba3",
            Renderer::PbrtV4 => "pbrt-v4",
        }
    }
}

/// One file of an export: its path inside the output directory and its text.
pub(crate) struct File {
    pub rel: PathBuf,
    pub text: String,
}

/// A number with every digit it has: Rust's shortest representation that reads back to
/// the same f64.
pub(crate) fn num(x: f64) -> String {
    if x == x.trunc() && x.abs() < 1e15 {
        format!("{x:.1}")
    } else {
        format!("{x:e}")
    }
}

/// The wavelength of bin `i` of the scene's 1 nm grid.
pub(crate) fn grid_nm(i: usize) -> f64 {
    (metamer_color::START_NM as usize + i) as f64
}

/// One emitter tile as both renderers write it: a rectangle radiating `radiance` (absolute,
/// W·sr⁻¹·m⁻²·nm⁻¹ on the 1 nm grid, the written gain included) from its front.
pub(crate) struct Tile<'a> {
    pub emitter: usize,
    pub row: usize,
    pub col: usize,
    pub corner: [f64; 3],
    pub edge_u: [f64; 3],
    pub edge_v: [f64; 3],
    pub radiance: Vec<f64>,
    /// The emitter's own reflectance (what its tiles reflect of the box's light).
    pub reflectance: &'a [f64],
}

/// Every emitter's tiles, emitter by emitter, row by row.
pub(crate) fn tiles<'a>(scene: &'a Scene, approximation: &Approximation) -> Vec<Tile<'a>> {
    let mut out = Vec::new();
    for (i, e) in scene.emitters.iter().enumerate() {
        let (u, v) = (e.rect.edge_u / e.cols as f64, e.rect.edge_v / e.rows as f64);
        for row in 0..e.rows {
            for col in 0..e.cols {
                let t = row * e.cols + col;
                let gain = approximation.gains[i][t];
                out.push(Tile {
                    emitter: i,
                    row,
                    col,
                    corner: (e.rect.corner + u * col as f64 + v * row as f64).to_array(),
                    edge_u: u.to_array(),
                    edge_v: v.to_array(),
                    radiance: e.tile_spectrum(t).iter().map(|s| s * gain).collect(),
                    reflectance: &e.reflectance,
                });
            }
        }
    }
    out
}

/// The luminance (cd/m²) of a spectral radiance on the grid: 683 · Σ L · ȳ · 1 nm, the
/// scene's own definition (paper Eq. 8).
pub(crate) fn luminance(scene: &Scene, radiance: &[f64]) -> f64 {
    metamer_color::K_M
        * radiance
            .iter()
            .zip(&scene.cmf[1])
            .map(|(l, y)| l * y)
            .sum::<f64>()
}
