//! The camera's XYZ image (absolute cd/m², float): `metamer render image` in one call
//! ([`run`]), and [`render`], the one renderer of it by either solver that the command and
//! the experiment's simulation stage share.
//!
//! The two differ on purpose in where the radiosity image's light comes from
//! ([`RadiosityLight`]) and how many rays a pixel gets ([`Film::subpixels`]): the command
//! solves afresh at its `--level` with ⌊√spp⌋² rays per pixel; the stage shows the very
//! solution its spot readings came from, one ray per pixel. Their pixels differ.
//!
//! ```no_run
//! use metamer::render::job::image::{run, ImageRequest};
//!
//! let request = ImageRequest {
//!     width: Some(64),
//!     height: Some(64),
//!     ..ImageRequest::new(16, "box.exr".into())
//! };
//! let report = run(&request, &|_| {})?;
//! println!("{}×{} in {:.1} s", report.width, report.height, report.seconds);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use std::path::PathBuf;
use std::time::Instant;

pub use super::ImageReport;
use super::{load_scene, RenderError, RenderEvent};
use crate::image::{write_srgb_preview, write_xyz_image, XyzImage};
use crate::output::{OutputError, OutputPolicy};
use crate::render::image::{render_image, ImageOptions};
use crate::render::integrator::Strategy;
use crate::render::method::{Method, Solver};
use crate::render::radiosity::image::{
    check_level, render_image_from, render_image_radiosity, RadiosityImageOptions,
};
use crate::render::radiosity::{RadiosityOptions, Solved};
use crate::render::scene::Scene;
use crate::render::spot::{reference_white, SpotOptions};

/// Where the radiosity image's light comes from.
#[derive(Clone, Copy)]
pub enum RadiosityLight<'a> {
    /// Solve the levels `level − 1` and `level` afresh with the default options.
    Solve { level: usize },
    /// The solutions a spot run left (see [`super::spots::Readings::Radiosity`]).
    Solved {
        levels: &'a [(Solved, f64)],
        options: &'a RadiosityOptions,
    },
}

/// The image to render from a loaded scene.
#[derive(Clone, Copy)]
pub struct Film<'a> {
    pub width: usize,
    pub height: usize,
    /// Path tracer: samples per pixel.
    pub spp: u64,
    /// Path tracer: the seed.
    pub seed: u64,
    pub light: RadiosityLight<'a>,
    /// Radiosity: a k×k grid of rays per pixel (it has no noise to average; more rays
    /// only smooth the edges).
    pub subpixels: usize,
}

/// Renders `film` of `scene` by `method`; the path tracer reports rows done as
/// [`RenderEvent::Rows`].
pub fn render(
    scene: &Scene,
    method: Solver,
    film: &Film,
    events: &(dyn Fn(RenderEvent) + Sync),
) -> Result<XyzImage, RenderError> {
    let radiosity_image = RadiosityImageOptions {
        width: film.width,
        height: film.height,
        subpixels: film.subpixels,
        ..RadiosityImageOptions::default()
    };
    Ok(match (method, film.light) {
        (Solver::Radiosity, RadiosityLight::Solve { level }) => {
            let io = RadiosityImageOptions {
                level,
                ..radiosity_image
            };
            render_image_radiosity(scene, &RadiosityOptions::default(), &io)?
        }
        (Solver::Radiosity, RadiosityLight::Solved { levels, options }) => {
            render_image_from(scene, levels, options, &radiosity_image)?
        }
        (Solver::PathTracer, _) => {
            let opts = ImageOptions {
                width: film.width,
                height: film.height,
                spp: film.spp,
                seed: film.seed,
                strategy: Strategy::default(),
                window: None,
            };
            render_image(scene, &opts, &|n| events(RenderEvent::Rows(n)))?
        }
    })
}

/// What `metamer render image` is asked for.
#[derive(Clone, Debug)]
pub struct ImageRequest {
    /// The scene file; None is the built-in validation box.
    pub scene: Option<PathBuf>,
    /// Samples per pixel (radiosity: a ⌊√spp⌋ × ⌊√spp⌋ grid of rays).
    pub spp: u64,
    pub method: Method,
    /// Radiosity: the finest mesh level.
    pub level: usize,
    /// Output size (default: the scene camera's); the field of view is kept.
    pub width: Option<usize>,
    pub height: Option<usize>,
    /// `.exr` or `.pfm`, by extension.
    pub output: PathBuf,
    /// sRGB PNG preview, exposed so the perfect white diffuser is at 1.
    pub preview: Option<PathBuf>,
    pub seed: u64,
    /// Replace the image and preview if they exist.
    pub force: bool,
}

impl ImageRequest {
    /// The command's defaults: the built-in scene by the path tracer, at its camera's size.
    pub fn new(spp: u64, output: PathBuf) -> Self {
        ImageRequest {
            scene: None,
            spp,
            method: Method::PathTracer,
            level: 3,
            width: None,
            height: None,
            output,
            preview: None,
            seed: 1,
            force: false,
        }
    }
}

/// Checks the request and the outputs (before the render: a refused output costs nothing
/// yet), renders, writes the image ([`RenderEvent::ImageWritten`]) and then the preview,
/// which needs the reference white rendered too.
pub fn run(
    request: &ImageRequest,
    events: &(dyn Fn(RenderEvent) + Sync),
) -> Result<ImageReport, RenderError> {
    let r = request;
    if r.spp == 0 {
        return Err(RenderError::Spp);
    }
    let out = output_policy(r)?;
    let name = r
        .scene
        .as_ref()
        .map_or("the built-in scene".into(), |p| p.display().to_string());
    let scene = load_scene(r.scene.as_deref(), events)?;
    let camera = scene.camera.ok_or(RenderError::NoCamera { scene: name })?;
    let width = r.width.unwrap_or(camera.width);
    let height = r.height.unwrap_or(camera.height);
    if width == 0 || height == 0 {
        return Err(RenderError::Size);
    }
    let t = Instant::now();
    if r.method == Method::Radiosity {
        check_level(r.level)?;
    }
    let method = r.method.resolve(&scene)?.method;
    let film = Film {
        width,
        height,
        spp: r.spp,
        seed: r.seed,
        light: RadiosityLight::Solve { level: r.level },
        // The command spends its samples on a square grid of rays per pixel.
        subpixels: (r.spp as f64).sqrt().floor().max(1.0) as usize,
    };
    events(RenderEvent::ImageSize { width, height });
    let img = render(&scene, method, &film, events)?;
    let mut report = ImageReport {
        width,
        height,
        spp: r.spp,
        method,
        seconds: t.elapsed().as_secs_f64(),
        output: r.output.clone(),
        preview: None,
    };
    write_xyz_image(&r.output, &img, &out)?;
    events(RenderEvent::ImageWritten(&report));
    if let Some(p) = &r.preview {
        // Expose for the perfect diffuser under the scene's light, read by the meter.
        let white = reference_white(
            &scene,
            &SpotOptions {
                target_de: 0.5,
                ..SpotOptions::default()
            },
        )?;
        write_srgb_preview(p, &img, white[1], &out)?;
        report.preview = Some(p.clone());
        events(RenderEvent::PreviewWritten(p));
    }
    Ok(report)
}

/// The outputs' policy, both outputs checked; the scene is an input neither may replace.
fn output_policy(r: &ImageRequest) -> Result<OutputPolicy, RenderError> {
    let mut out = OutputPolicy::new(r.force);
    if let Some(s) = &r.scene {
        out.input(s);
    }
    out.check(&r.output)?;
    if let Some(p) = &r.preview {
        let mut besides_image = out.clone();
        besides_image.input(&r.output);
        if let Err(OutputError::IsInput { .. }) = besides_image.check(p) {
            return Err(RenderError::PreviewIsImage {
                preview: p.clone(),
                image: r.output.clone(),
            });
        }
        out.check(p)?;
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_preview_on_the_image_is_a_bad_request_before_anything_renders() {
        let dir = std::env::temp_dir().join(format!("metamer-job-image-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let output = dir.join("x.exr");
        let request = ImageRequest {
            preview: Some(output.clone()),
            scene: Some(dir.join("no such scene.json")),
            ..ImageRequest::new(4, output.clone())
        };
        let e = run(&request, &|_| panic!("no event")).unwrap_err();
        assert!(e.is_bad_request());
        assert_eq!(
            e.to_string(),
            format!(
                "the preview {} is the same file as the image {}",
                output.display(),
                output.display()
            )
        );
        let e = run(&ImageRequest::new(0, output), &|_| panic!("no event")).unwrap_err();
        assert_eq!(e.to_string(), "the samples per pixel must be ≥ 1");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
