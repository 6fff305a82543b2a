//! The scene file (JSON) and its validated, render-ready form.
//!
//! The file states the validation box of `docs/validation-box.md` (or a room like it):
//! rectangles with a Lambertian spectral reflectance, tiled emitters, a pinhole camera and
//! the spot meter. Spectra are a constant, a CSV file (path relative to the scene file,
//! optional 1-based value column) or inline samples. Every error names the JSON path of
//! the bad field.
//!
//! **Emitters.** The radiance of tile t of an emitter towards ω is
//! L_t(λ, ω) = g_t·S_t(λ)·f(ω), f = 1 along the normal. The tile spectra come in one of two
//! forms, per emitter:
//! - *relative* (the nominal box): one `spectrum` S(λ) for every tile, in any unit, and
//!   `luminance_cd_m2`; then S_t = s·S with s chosen so that 683·Σ s·S·ȳ =
//!   `luminance_cd_m2` — the luminance along the normal of a tile of gain 1;
//! - *absolute* (a measured box): every tile has its own `spectrum`, an absolute spectral
//!   radiance along the normal in W·sr⁻¹·m⁻²·nm⁻¹, and the emitter has neither `spectrum`
//!   nor `luminance_cd_m2` (the luminance follows from the spectra). The tile's `gain`
//!   (default 1) still multiplies it.
//!
//! f is `lambertian` (1), `cos_power` (cosᵐθ) or `c_gamma`: a measured table f(C, γ)
//! ([`crate::light::CGammaTable`]) with γ from the emitting normal and C about it, from
//! the emitter's `edge_u` (C = 0°) towards its `edge_v` (C = 90°).
//!
//! **Reflectances** must lie in [0, 1]; measured values up to 1.05 are accepted as
//! measurement noise with a warning in [`Scene::warnings`]. `provenance` is any JSON object,
//! carried through untouched.
//!
//! **Limits** (checked before anything is allocated for them): a file of at most
//! [`MAX_SCENE_BYTES`], [`MAX_SURFACES`] surfaces, [`MAX_EMITTERS`] emitters, at most
//! [`MAX_TILES_PER_SIDE`] rows and columns per emitter and [`MAX_TILES`] tiles in all,
//! [`MAX_TILE_SPECTRA`] distinct tile spectra (tiles whose spectra are proportional share
//! one), and a tile luminance of at most [`MAX_LUMINANCE_CD_M2`]. A scene that emits no
//! light is refused: every reading of it would be 0/0.

mod build;
pub mod builtin;
pub mod file;
mod hidden;
mod loader;
mod model;
pub mod reader;

use std::path::{Path, PathBuf};

pub use file::{
    CameraFile, DistributionFile, EmitterFile, MeterFile, SceneFile, SpectrumRef, SurfaceFile,
    TileFile, WriteError,
};
pub use model::{
    Camera, Distribution, Emitter, Scene, Surface, MAX_EMITTERS, MAX_LUMINANCE_CD_M2,
    MAX_REFLECTANCE, MAX_SCENE_BYTES, MAX_SURFACES, MAX_TILES, MAX_TILES_PER_SIDE,
    MAX_TILE_SPECTRA,
};
pub use reader::PathError;

/// Why a scene could not be loaded.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    #[error("cannot read scene {file}: {source}")]
    Io {
        file: PathBuf,
        source: std::io::Error,
    },
    #[error("{file}: {size} bytes is more than a scene may have ({max} bytes)")]
    TooLarge { file: PathBuf, size: u64, max: u64 },
    #[error("{file}: {source}")]
    Invalid { file: PathBuf, source: PathError },
}

impl Scene {
    /// Reads and validates a scene file.
    pub fn load(path: &Path) -> Result<Scene, SceneError> {
        Scene::load_with_inputs(path).map(|(scene, _)| scene)
    }

    /// [`Scene::load`], with every file the scene read: the scene file first, then the
    /// files it names, resolved against its directory.
    pub fn load_with_inputs(path: &Path) -> Result<(Scene, Vec<PathBuf>), SceneError> {
        let io = |source| SceneError::Io {
            file: path.to_path_buf(),
            source,
        };
        let size = std::fs::metadata(path).map_err(io)?.len();
        if size > MAX_SCENE_BYTES {
            return Err(SceneError::TooLarge {
                file: path.to_path_buf(),
                size,
                max: MAX_SCENE_BYTES,
            });
        }
        let text = metamer_color::text::read_text(path).map_err(io)?;
        let invalid = |source| SceneError::Invalid {
            file: path.to_path_buf(),
            source,
        };
        let file = SceneFile::from_json(&text).map_err(invalid)?;
        let dir = match path.parent() {
            Some(d) if !d.as_os_str().is_empty() => d,
            _ => Path::new("."),
        };
        let scene = Scene::build(&file, dir).map_err(invalid)?;
        let inputs = std::iter::once(path.to_path_buf())
            .chain(file.named_files().into_iter().map(|f| dir.join(f)))
            .collect();
        Ok((scene, inputs))
    }

    /// Validates a parsed scene; files are resolved against `dir`.
    pub fn build(file: &SceneFile, dir: &Path) -> Result<Scene, PathError> {
        build::scene(file, loader::SpectrumFiles::Dir(dir))
    }

    /// A box built into the program by name (`validation-box`, lit by the `ips-lcd`
    /// display's white; `validation-box-led-rgb1`), so the defaults work from any directory.
    pub fn builtin(name: &str) -> Result<Scene, PathError> {
        build::builtin_scene(builtin::scene_text(name))
    }

    /// The built-in box a scene argument names: one of [`builtin::NAMES`] when no file of
    /// that name exists (a file always wins, so a scene saved under such a name still loads).
    pub fn builtin_named(path: &Path) -> Option<&'static str> {
        let name = path.to_str()?;
        let known = builtin::NAMES.iter().find(|n| **n == name)?;
        (!path.exists()).then_some(*known)
    }

    /// The surface index of ColorChecker patch `k` (1–24).
    pub fn patch_surface(&self, k: usize) -> Option<usize> {
        self.surfaces.iter().position(|s| s.patch == Some(k))
    }

    /// Every emitter's luminous intensity along its normal summed (cd): zero means the
    /// scene is dark.
    pub fn intensity_cd(&self) -> f64 {
        self.emitters
            .iter()
            .map(|e| e.intensity_cd(&self.cmf[1]))
            .sum()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_built_in_name_names_its_box() {
        assert_eq!(
            Scene::builtin_named(Path::new("validation-box-led-rgb1")),
            Some("validation-box-led-rgb1")
        );
        assert_eq!(Scene::builtin_named(Path::new("no-such-box")), None);
        // The LED box is lit by the LED table, the default box by the display's white: two
        // scenes, not one under two names.
        let led = Scene::builtin("validation-box-led-rgb1").unwrap();
        let default = Scene::builtin(builtin::NAMES[0]).unwrap();
        assert_ne!(led.emitters[0].spectra, default.emitters[0].spectra);
    }
}
