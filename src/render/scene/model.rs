//! The validated, render-ready scene and the limits a scene file must keep.

use std::sync::Arc;

use super::super::geometry::{Rect, Vec3};
use crate::light::CGammaTable;

/// Largest scene file read.
pub const MAX_SCENE_BYTES: u64 = 256 << 20;
/// Most surfaces in a scene (each carries a 401-bin reflectance).
pub const MAX_SURFACES: usize = 20_000;
/// Most emitters in a scene.
pub const MAX_EMITTERS: usize = 100;
/// Most rows, and most columns, of one emitter's tile grid.
pub const MAX_TILES_PER_SIDE: usize = 1_000;
/// Most tiles in the whole scene.
pub const MAX_TILES: usize = 1_000_000;
/// Most distinct (non-proportional) tile spectra in the whole scene.
pub const MAX_TILE_SPECTRA: usize = 1_024;
/// Largest tile luminance along the normal: far above any lamp (the sun's disc is about
/// 1.6·10⁹ cd/m²), low enough that no sum of the renderers can overflow.
pub const MAX_LUMINANCE_CD_M2: f64 = 1e15;
/// Largest reflectance accepted (with a warning above 1).
pub const MAX_REFLECTANCE: f64 = 1.05;

/// A reflecting rectangle ready to render.
#[derive(Clone, Debug)]
pub struct Surface {
    pub name: String,
    pub rect: Rect,
    pub reflectance: Vec<f64>,
    pub patch: Option<usize>,
}

/// Directional factor f(ω) of the emitter radiance, 1 along the normal.
#[derive(Clone, Debug, PartialEq)]
pub enum Distribution {
    Lambertian,
    CosPower(f64),
    /// f(C, γ) in the emitter's frame.
    Table(Arc<CGammaTable>),
}

impl Distribution {
    /// f for a unit direction given in the emitter's frame: x along `edge_u`, y along
    /// `edge_v`, z along the emitting normal. Behind the emitter f is 0.
    #[inline]
    pub fn factor(&self, local: [f64; 3]) -> f64 {
        match self {
            Distribution::Lambertian => (local[2] > 0.0) as u8 as f64,
            Distribution::CosPower(m) => {
                if local[2] > 0.0 {
                    local[2].powf(*m)
                } else {
                    0.0
                }
            }
            Distribution::Table(t) => t.factor(local),
        }
    }
}

/// A tiled emitter ready to render. Tile t radiates gains[t]·spectra[tile_spectrum[t]](λ)
/// times the directional factor.
#[derive(Clone, Debug)]
pub struct Emitter {
    pub rect: Rect,
    pub rows: usize,
    pub cols: usize,
    /// gains[row * cols + col]
    pub gains: Vec<f64>,
    /// Which of `spectra` each tile radiates.
    pub tile_spectrum: Vec<u32>,
    /// Spectral radiance along the normal, W·sr⁻¹·m⁻²·nm⁻¹ on the 1 nm grid: one entry
    /// for a relative emitter (s·S), one per group of proportional tile spectra otherwise.
    pub spectra: Vec<Vec<f64>>,
    /// The scale s of a relative emitter (683·Σ s·S·ȳ = luminance); 1 for absolute tiles.
    pub scale: f64,
    pub distribution: Distribution,
    pub reflectance: Vec<f64>,
    /// Unit vectors along edge_u and edge_v: the frame of the distribution.
    pub axis_u: Vec3,
    pub axis_v: Vec3,
}

impl Emitter {
    pub fn tile_at(&self, a: f64, b: f64) -> usize {
        let col = ((a * self.cols as f64) as usize).min(self.cols - 1);
        let row = ((b * self.rows as f64) as usize).min(self.rows - 1);
        row * self.cols + col
    }

    /// The spectrum tile `t` radiates (before its gain).
    #[inline]
    pub fn tile_spectrum(&self, t: usize) -> &[f64] {
        &self.spectra[self.tile_spectrum[t] as usize]
    }

    /// The directional factor towards the unit direction `out` leaving the emitter.
    #[inline]
    pub fn directional(&self, out: Vec3) -> f64 {
        if self.distribution == Distribution::Lambertian {
            return (out.dot(self.rect.normal) > 0.0) as u8 as f64;
        }
        self.distribution.factor([
            out.dot(self.axis_u),
            out.dot(self.axis_v),
            out.dot(self.rect.normal),
        ])
    }

    /// Σ over tiles of gain × area × luminance along the normal (cd·m²/m² · m² = cd):
    /// the luminous intensity along the normal.
    pub fn intensity_cd(&self, ybar: &[f64]) -> f64 {
        let lum: Vec<f64> = self
            .spectra
            .iter()
            .map(|s| crate::color::K_M * s.iter().zip(ybar).map(|(a, b)| a * b).sum::<f64>())
            .collect();
        let area = self.rect.area_m2 / self.gains.len() as f64;
        self.gains
            .iter()
            .zip(&self.tile_spectrum)
            .map(|(g, k)| g * lum[*k as usize] * area)
            .sum()
    }
}

/// Pinhole camera.
#[derive(Clone, Copy, Debug)]
pub struct Camera {
    pub position: Vec3,
    pub forward: Vec3,
    pub right: Vec3,
    pub up: Vec3,
    pub vfov_deg: f64,
    pub width: usize,
    pub height: usize,
}

/// A validated scene.
#[derive(Clone, Debug)]
pub struct Scene {
    pub name: String,
    pub surfaces: Vec<Surface>,
    pub emitters: Vec<Emitter>,
    /// None when the file has no camera (a room for illuminance probes).
    pub camera: Option<Camera>,
    /// None when the file has no meter.
    pub meter_acceptance_deg: Option<f64>,
    /// x̄, ȳ, z̄ on the grid (CIE 1931 2°).
    pub cmf: [Vec<f64>; 3],
    /// The file's provenance object, untouched.
    pub provenance: Option<serde_json::Map<String, serde_json::Value>>,
    /// What was accepted but deserves a look (reflectances slightly above 1).
    pub warnings: Vec<String>,
}
