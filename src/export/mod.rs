//! `metamer export`: the validated scene written for another renderer — Mitsuba 3 (XML and
//! `.spd` spectrum files), pbrt-v4 (one `.pbrt` file) or Blender's Cycles (a `bpy` script
//! with every spectrum as an RGB colour, [`rgb`]) — with a README beside it that says
//! how to render it, what the image holds and where the other renderer cannot say what
//! the scene says.
//!
//! The scene is loaded the way `metamer render spots` loads it (a scene file, a built-in
//! box by name, or the default built-in box), so a measured `box/scene.json` and the
//! built-in boxes export alike. What is written:
//!
//! - geometry in metres, every rectangle with its front side along `edge_u × edge_v`;
//! - every surface a Lambertian reflector with its reflectance on the scene's 1 nm grid
//!   (380–780 nm);
//! - every emitter tile an area light of its absolute spectral radiance, `gain · S(λ)`
//!   (W·sr⁻¹·m⁻²·nm⁻¹); a non-Lambertian emitter is written in the Lambertian form of
//!   [`approximation`], which both renderers can express, and the difference it makes to
//!   the 24 patches is measured with metamer's radiosity solver and stated;
//! - the scene's camera (position, view, vertical field of view, size), oriented so the
//!   other renderer's image comes out as `metamer render image` writes it: row 0 at the
//!   top, x along the camera's right (`forward × up`), not mirrored — the display's mirror
//!   is applied later, by the reproduction, to either image alike;
//! - a film that records XYZ in cd/m² (details in each renderer's module).
//!
//! ```
//! use metamer::export::{run, ExportRequest, Renderer};
//!
//! let dir = std::env::temp_dir().join(format!("metamer-export-doc-{}", std::process::id()));
//! let _ = std::fs::remove_dir_all(&dir);
//! let request = ExportRequest::new(None, Renderer::PbrtV4, dir.clone());
//! let report = run(&request)?;
//! assert!(report.files.iter().any(|f| f.ends_with("scene.pbrt")));
//! println!("{}", report.summary);
//! std::fs::remove_dir_all(&dir)?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod approximation;
mod blender;
mod common;
mod error;
mod mitsuba3;
mod pbrt;
mod readme;
pub mod rgb;

use std::path::{Path, PathBuf};

use crate::output::{OutputError, OutputPolicy};
use crate::render::scene::Scene;

pub use approximation::{Approximation, Difference, Measured};
use common::File;
pub use common::Renderer;
pub use error::ExportError;

/// What to export.
#[derive(Clone, Debug)]
pub struct ExportRequest {
    /// A scene file, or the name of a built-in box (used when no such file exists); None is
    /// the default built-in box.
    pub scene: Option<PathBuf>,
    pub to: Renderer,
    /// The output directory: created if missing; refused when it holds anything, unless
    /// `force`. Even forced, no file the scene reads, nor the scene file, is replaced.
    pub output: PathBuf,
    pub force: bool,
    /// Samples per pixel written as the scene's default (both files let a user override it).
    pub spp: u32,
    /// Measure the difference of a non-Lambertian emitter's Lambertian form with the
    /// radiosity solver (two solves, tens of seconds on the measured box).
    pub measure_difference: bool,
}

impl ExportRequest {
    /// The command's defaults: 256 spp, the difference measured.
    pub fn new(scene: Option<PathBuf>, to: Renderer, output: PathBuf) -> Self {
        ExportRequest {
            scene,
            to,
            output,
            force: false,
            spp: 256,
            measure_difference: true,
        }
    }
}

/// What an export wrote.
#[derive(Clone, Debug)]
pub struct ExportReport {
    /// Every file written, the scene file first and the README last.
    pub files: Vec<PathBuf>,
    /// How the emitters were written (exactly, or the Lambertian form and its difference).
    pub approximation: Approximation,
    /// The README's summary of what the export approximates, in a sentence or two.
    pub summary: String,
}

/// The scene as `render spots` would load it, with the name errors use and the files it
/// read (none for a built-in scene).
fn load(scene: Option<&Path>) -> Result<(Scene, String, Vec<PathBuf>), ExportError> {
    let builtin = |name: &str| {
        Scene::builtin(name)
            .map(|s| (s, format!("built-in scene {name}"), Vec::new()))
            .map_err(|source| ExportError::Builtin {
                name: name.to_string(),
                source,
            })
    };
    match scene {
        None => builtin(crate::render::scene::builtin::NAMES[0]),
        Some(p) => match Scene::builtin_named(p) {
            Some(name) => builtin(name),
            None => {
                let (scene, inputs) = Scene::load_with_inputs(p)?;
                Ok((scene, p.display().to_string(), inputs))
            }
        },
    }
}

/// Whether a directory holds anything (a missing one holds nothing).
fn is_non_empty(dir: &Path) -> Result<bool, ExportError> {
    match std::fs::read_dir(dir) {
        Ok(mut entries) => Ok(entries.next().is_some()),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(false),
        Err(e) if e.kind() == std::io::ErrorKind::NotADirectory => {
            Err(ExportError::Output(OutputError::NotADirectory {
                path: dir.to_path_buf(),
            }))
        }
        Err(source) => Err(ExportError::Output(OutputError::Io {
            path: dir.to_path_buf(),
            action: "inspect",
            source,
        })),
    }
}

/// Loads the scene, checks the output directory, chooses each emitter's form (measuring
/// the difference of a Lambertian stand-in), writes the renderer's files and the README.
pub fn run(request: &ExportRequest) -> Result<ExportReport, ExportError> {
    if request.spp == 0 {
        return Err(ExportError::BadSpp);
    }
    let (scene, name, inputs) = load(request.scene.as_deref())?;
    let Some(camera) = scene.camera else {
        return Err(ExportError::NoCamera { scene: name });
    };
    if !request.force && is_non_empty(&request.output)? {
        return Err(ExportError::NotEmpty {
            dir: request.output.clone(),
        });
    }
    let approximation = approximation::choose(&scene, &name, request.measure_difference)?;
    let files = match request.to {
        Renderer::Mitsuba3 => mitsuba3::files(&scene, &camera, &approximation, request.spp),
        Renderer::PbrtV4 => pbrt::files(&scene, &camera, &approximation, request.spp),
        Renderer::Blender => blender::files(&scene, &camera, &approximation, request.spp),
    };
    let mut summary = readme::summary(&approximation);
    if request.to == Renderer::Blender {
        summary.push_str(
            "; Cycles renders in RGB, so every spectrum is entered as the linear Rec.709 \
             colour the README states",
        );
    }
    let readme = File {
        rel: PathBuf::from("README.md"),
        text: readme::text(request.to, &scene, &name, &camera, &approximation, &summary),
    };
    // Even forced, no file the scene reads (nor the scene itself) is replaced: every
    // output is checked against them before the first is written, so a refusal leaves the
    // directory as it was.
    let mut policy = OutputPolicy::new(request.force);
    policy.inputs(inputs.iter().map(PathBuf::as_path));
    let all: Vec<&File> = files.iter().chain(std::iter::once(&readme)).collect();
    for f in &all {
        let path = request.output.join(&f.rel);
        if path.parent().is_some_and(|d| d.is_dir()) {
            policy.check(&path)?;
        }
    }
    policy.dir(&request.output)?;
    let mut written = Vec::new();
    for f in all {
        let path = request.output.join(&f.rel);
        if let Some(parent) = path.parent() {
            policy.dir(parent)?;
        }
        policy.write(&path, f.text.as_bytes())?;
        written.push(path);
    }
    Ok(ExportReport {
        files: written,
        approximation,
        summary,
    })
}
