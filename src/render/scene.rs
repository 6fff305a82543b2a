//! The scene file (serde JSON) and its validated, render-ready form.
//!
//! The file states the validation box of `docs/validation-box.md` (or a room like it): rectangles with a
//! Lambertian spectral reflectance, one tiled emitter whose radiance is
//! L(λ, ω) = s·S(λ)·g[row][col]·f(ω) with s chosen so the untiled source has the stated
//! luminance (683·Σ s·S·ȳ = luminance_cd_m2), a pinhole camera and the spot meter.
//! Spectra are a constant, a CSV file (path relative to the scene file, optional 1-based
//! value column) or inline samples. Every error names the JSON path of the bad field.

use std::path::{Path, PathBuf};

use serde::Deserialize;

use super::geometry::{Rect, Vec3, VecOps};
use super::spectral::{bins, cmf_bins, constant_bins};
use crate::color::{luminance, ObserverKind, Outside, SpectralTable, Spectrum};

/// Why a scene could not be loaded.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    #[error("cannot read scene {file}: {source}")]
    Io {
        file: PathBuf,
        source: std::io::Error,
    },
    #[error("{file}: not a valid scene: {source}")]
    Json {
        file: PathBuf,
        source: serde_json::Error,
    },
    #[error("{file}: {path}: {message}")]
    Invalid {
        file: PathBuf,
        path: String,
        message: String,
    },
}

/// A spectrum in the scene file.
#[derive(Clone, Debug, Deserialize)]
#[serde(untagged)]
pub enum SpectrumRef {
    /// The same value at every wavelength.
    Constant(f64),
    /// A column of a spectral CSV file.
    File {
        file: String,
        /// 1-based value column (default 1).
        #[serde(default)]
        column: Option<usize>,
        #[serde(default)]
        outside: Option<Outside>,
    },
    /// Samples given in the file.
    Inline {
        nm: Vec<f64>,
        values: Vec<f64>,
        #[serde(default)]
        outside: Option<Outside>,
    },
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SurfaceFile {
    pub name: String,
    pub corner: [f64; 3],
    pub edge_u: [f64; 3],
    pub edge_v: [f64; 3],
    pub reflectance: SpectrumRef,
    /// ColorChecker patch number (1–24) if this surface is a patch.
    #[serde(default)]
    pub patch: Option<usize>,
}

#[derive(Clone, Debug, Default, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum DistributionFile {
    #[default]
    Lambertian,
    /// f(θ) = cosᵐθ relative to a Lambertian emitter (f = 1 on the normal).
    CosPower { exponent: f64 },
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TileFile {
    pub row: usize,
    pub col: usize,
    pub gain: f64,
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EmitterFile {
    /// Corner of tile (0, 0); `edge_u` runs along the columns, `edge_v` along the rows.
    pub corner: [f64; 3],
    pub edge_u: [f64; 3],
    pub edge_v: [f64; 3],
    /// Tile grid (default 1 × 1: an untiled panel).
    #[serde(default = "one")]
    pub rows: usize,
    #[serde(default = "one")]
    pub cols: usize,
    /// Tile gains; omitted, every tile has gain 1.
    #[serde(default)]
    pub tiles: Vec<TileFile>,
    /// Relative spectral radiance (default: equal energy, as for a photometric-only light).
    #[serde(default = "equal_energy")]
    pub spectrum: SpectrumRef,
    pub luminance_cd_m2: f64,
    /// Directional factor (default Lambertian).
    #[serde(default)]
    pub distribution: DistributionFile,
    /// Reflectance of the emitting surface (default 0: the light absorbs what reaches it).
    #[serde(default)]
    pub reflectance: Option<SpectrumRef>,
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CameraFile {
    pub position: [f64; 3],
    pub look_at: [f64; 3],
    pub up: [f64; 3],
    pub vfov_deg: f64,
    pub width: usize,
    pub height: usize,
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MeterFile {
    pub acceptance_deg: f64,
}

/// The scene file as written.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    pub name: String,
    #[serde(default)]
    pub description: Option<String>,
    pub surfaces: Vec<SurfaceFile>,
    pub emitters: Vec<EmitterFile>,
    /// A room lit for illuminance probes needs neither camera nor meter.
    #[serde(default)]
    pub camera: Option<CameraFile>,
    #[serde(default)]
    pub meter: Option<MeterFile>,
}

fn one() -> usize {
    1
}

fn equal_energy() -> SpectrumRef {
    SpectrumRef::Constant(1.0)
}

/// A reflecting rectangle ready to render.
#[derive(Clone, Debug)]
pub struct Surface {
    pub name: String,
    pub rect: Rect,
    pub reflectance: Vec<f64>,
    pub patch: Option<usize>,
}

/// Directional factor f(ω) of the emitter radiance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Distribution {
    Lambertian,
    CosPower(f64),
}

impl Distribution {
    /// f for a direction with cosine `cos_theta` to the emitter normal.
    #[inline]
    pub fn factor(self, cos_theta: f64) -> f64 {
        match self {
            Distribution::Lambertian => 1.0,
            Distribution::CosPower(m) => cos_theta.max(0.0).powf(m),
        }
    }
}

/// A tiled emitter ready to render.
#[derive(Clone, Debug)]
pub struct Emitter {
    pub rect: Rect,
    pub rows: usize,
    pub cols: usize,
    /// gains[row * cols + col]
    pub gains: Vec<f64>,
    /// s·S(λ) in W·sr⁻¹·m⁻²·nm⁻¹ on the grid.
    pub radiance: Vec<f64>,
    /// The scale s (paper: 683·Σ s·S·ȳ = luminance).
    pub scale: f64,
    pub distribution: Distribution,
    pub reflectance: Vec<f64>,
}

impl Emitter {
    pub fn tile_at(&self, a: f64, b: f64) -> usize {
        let col = ((a * self.cols as f64) as usize).min(self.cols - 1);
        let row = ((b * self.rows as f64) as usize).min(self.rows - 1);
        row * self.cols + col
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
}

impl Scene {
    /// Reads and validates a scene file.
    pub fn load(path: &Path) -> Result<Scene, SceneError> {
        let text = std::fs::read_to_string(path).map_err(|source| SceneError::Io {
            file: path.to_path_buf(),
            source,
        })?;
        let file: SceneFile = serde_json::from_str(&text).map_err(|source| SceneError::Json {
            file: path.to_path_buf(),
            source,
        })?;
        let dir = path.parent().unwrap_or(Path::new("."));
        Scene::build(&file, dir).map_err(|(p, message)| SceneError::Invalid {
            file: path.to_path_buf(),
            path: p,
            message,
        })
    }

    /// Validates a parsed scene; files are resolved against `dir`.
    pub fn build(file: &SceneFile, dir: &Path) -> Result<Scene, (String, String)> {
        let mut surfaces = Vec::new();
        for (i, s) in file.surfaces.iter().enumerate() {
            let p = format!("surfaces[{i}]");
            let rect = rect(&p, s.corner, s.edge_u, s.edge_v)?;
            let reflectance = spectrum(&format!("{p}.reflectance"), &s.reflectance, dir)?;
            check_reflectance(&format!("{p}.reflectance"), &reflectance)?;
            if let Some(k) = s.patch {
                if !(1..=24).contains(&k) {
                    return Err((format!("{p}.patch"), format!("must be 1–24, got {k}")));
                }
            }
            surfaces.push(Surface {
                name: s.name.clone(),
                rect,
                reflectance,
                patch: s.patch,
            });
        }
        if file.emitters.is_empty() {
            return Err(("emitters".into(), "at least one emitter is needed".into()));
        }
        let mut emitters = Vec::new();
        for (i, e) in file.emitters.iter().enumerate() {
            emitters.push(emitter(&format!("emitters[{i}]"), e, dir)?);
        }
        let camera = match &file.camera {
            Some(c) => Some(camera(c)?),
            None => None,
        };
        let meter_acceptance_deg = match &file.meter {
            Some(m) => {
                let a = m.acceptance_deg;
                if !(a > 0.0 && a < 90.0) {
                    return Err(("meter.acceptance_deg".into(), "must be in (0, 90)".into()));
                }
                Some(a)
            }
            None => None,
        };
        Ok(Scene {
            name: file.name.clone(),
            surfaces,
            emitters,
            camera,
            meter_acceptance_deg,
            cmf: cmf_bins(ObserverKind::Cie1931),
        })
    }

    /// The surface index of ColorChecker patch `k` (1–24).
    pub fn patch_surface(&self, k: usize) -> Option<usize> {
        self.surfaces.iter().position(|s| s.patch == Some(k))
    }
}

fn camera(c: &CameraFile) -> Result<Camera, (String, String)> {
    let position = Vec3::from_array(c.position);
    let forward = Vec3::from_array(c.look_at).minus(position);
    if forward.length() == 0.0 || !forward.length().is_finite() {
        return Err(("camera.look_at".into(), "must differ from position".into()));
    }
    let forward = forward.normalized();
    let right = forward.cross(Vec3::from_array(c.up));
    if right.length() < 1e-9 {
        return Err((
            "camera.up".into(),
            "must not be parallel to the view".into(),
        ));
    }
    let right = right.normalized();
    let up = right.cross(forward);
    if !(c.vfov_deg > 0.0 && c.vfov_deg < 179.0) {
        return Err(("camera.vfov_deg".into(), "must be in (0, 179)".into()));
    }
    if c.width == 0 || c.height == 0 {
        return Err(("camera.width".into(), "image size must be ≥ 1".into()));
    }
    Ok(Camera {
        position,
        forward,
        right,
        up,
        vfov_deg: c.vfov_deg,
        width: c.width,
        height: c.height,
    })
}

fn finite3(path: &str, v: [f64; 3]) -> Result<Vec3, (String, String)> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(Vec3::from_array(v))
    } else {
        Err((path.into(), "must be finite numbers".into()))
    }
}

fn rect(p: &str, c: [f64; 3], u: [f64; 3], v: [f64; 3]) -> Result<Rect, (String, String)> {
    let c = finite3(&format!("{p}.corner"), c)?;
    let u = finite3(&format!("{p}.edge_u"), u)?;
    let v = finite3(&format!("{p}.edge_v"), v)?;
    if u.length() == 0.0 || v.length() == 0.0 {
        return Err((format!("{p}.edge_u"), "edges must be non-zero".into()));
    }
    if u.dot(v).abs() > 1e-9 * u.length() * v.length() {
        return Err((format!("{p}.edge_v"), "must be orthogonal to edge_u".into()));
    }
    Ok(Rect::new(c, u, v))
}

fn check_reflectance(p: &str, r: &[f64]) -> Result<(), (String, String)> {
    match r.iter().find(|x| !(0.0..=1.0).contains(*x)) {
        Some(x) => Err((
            p.into(),
            format!("reflectance must be in [0, 1], found {x}"),
        )),
        None => Ok(()),
    }
}

fn spectrum(p: &str, s: &SpectrumRef, dir: &Path) -> Result<Vec<f64>, (String, String)> {
    let sp = match s {
        SpectrumRef::Constant(v) => {
            if !v.is_finite() {
                return Err((p.into(), "must be finite".into()));
            }
            let v = *v;
            return Ok(constant_bins(v));
        }
        SpectrumRef::File {
            file,
            column,
            outside,
        } => {
            let path = dir.join(file);
            let table =
                SpectralTable::read(&path).map_err(|e| (format!("{p}.file"), e.to_string()))?;
            let col = column.unwrap_or(1);
            if col == 0 || col > table.columns.len() {
                return Err((
                    format!("{p}.column"),
                    format!("must be 1–{}, got {col}", table.columns.len()),
                ));
            }
            table
                .spectrum(col - 1)
                .with_outside(outside.unwrap_or(Outside::Zero))
        }
        SpectrumRef::Inline {
            nm,
            values,
            outside,
        } => Spectrum::new(nm.clone(), values.clone())
            .map_err(|e| (p.into(), e.to_string()))?
            .with_outside(outside.unwrap_or(Outside::Zero)),
    };
    Ok(bins(&sp))
}

fn emitter(p: &str, e: &EmitterFile, dir: &Path) -> Result<Emitter, (String, String)> {
    let rect = rect(p, e.corner, e.edge_u, e.edge_v)?;
    if e.rows == 0 {
        return Err((format!("{p}.rows"), "must be ≥ 1".into()));
    }
    if e.cols == 0 {
        return Err((format!("{p}.cols"), "must be ≥ 1".into()));
    }
    // No tiles listed: an untiled panel, every tile at gain 1.
    let fill = if e.tiles.is_empty() { 1.0 } else { f64::NAN };
    let mut gains = vec![fill; e.rows * e.cols];
    for (i, t) in e.tiles.iter().enumerate() {
        let tp = format!("{p}.tiles[{i}]");
        if t.row >= e.rows {
            return Err((format!("{tp}.row"), format!("must be < rows = {}", e.rows)));
        }
        if t.col >= e.cols {
            return Err((format!("{tp}.col"), format!("must be < cols = {}", e.cols)));
        }
        if !(t.gain >= 0.0 && t.gain.is_finite()) {
            return Err((format!("{tp}.gain"), "must be ≥ 0".into()));
        }
        let g = &mut gains[t.row * e.cols + t.col];
        if !g.is_nan() && !e.tiles.is_empty() {
            return Err((tp, format!("tile ({}, {}) given twice", t.row, t.col)));
        }
        *g = t.gain;
    }
    if let Some(i) = gains.iter().position(|g| g.is_nan()) {
        return Err((
            format!("{p}.tiles"),
            format!("tile ({}, {}) is missing", i / e.cols, i % e.cols),
        ));
    }
    let sp = format!("{p}.spectrum");
    let relative = spectrum(&sp, &e.spectrum, dir)?;
    if relative.iter().any(|v| *v < 0.0) {
        return Err((sp, "must be ≥ 0".into()));
    }
    // s from the colour core's Eq. 8 summation on the same grid.
    let rel = Spectrum::from_grid(380.0, 1.0, relative.clone())
        .map_err(|e| (sp.clone(), e.to_string()))?;
    let lum = luminance(&rel);
    if lum <= 0.0 {
        return Err((sp, "has no luminance (zero under ȳ)".into()));
    }
    if !(e.luminance_cd_m2 >= 0.0 && e.luminance_cd_m2.is_finite()) {
        return Err((format!("{p}.luminance_cd_m2"), "must be ≥ 0".into()));
    }
    let scale = e.luminance_cd_m2 / lum;
    let distribution = match e.distribution {
        DistributionFile::Lambertian => Distribution::Lambertian,
        DistributionFile::CosPower { exponent } => {
            if !(exponent >= 0.0 && exponent.is_finite()) {
                return Err((format!("{p}.distribution.exponent"), "must be ≥ 0".into()));
            }
            Distribution::CosPower(exponent)
        }
    };
    let reflectance = match &e.reflectance {
        Some(r) => {
            let rp = format!("{p}.reflectance");
            let r = spectrum(&rp, r, dir)?;
            check_reflectance(&rp, &r)?;
            r
        }
        None => constant_bins(0.0),
    };
    Ok(Emitter {
        rect,
        rows: e.rows,
        cols: e.cols,
        gains,
        radiance: relative.iter().map(|v| v * scale).collect(),
        scale,
        distribution,
        reflectance,
    })
}
