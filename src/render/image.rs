//! Image mode: the paper's idealised film (Eq. 2–3). A pixel is the mean radiance over its
//! footprint on the image plane (box filter, no cos⁴ fall-off), projected to absolute XYZ.

use rayon::prelude::*;

use super::geometry::VecOps;
use super::image_io::XyzImage;
use super::integrator::{Strategy, Tracer};
use super::scene::Scene;
use super::spectral::Rng;

/// What to render.
#[derive(Clone, Copy, Debug)]
pub struct ImageOptions {
    /// Output size; the scene camera's field of view is kept for any size.
    pub width: usize,
    pub height: usize,
    pub spp: u64,
    pub seed: u64,
    pub strategy: Strategy,
    /// Only pixels x0..x1, y0..y1 (others stay zero), for tests and crops.
    pub window: Option<[usize; 4]>,
}

/// Why an image cannot be rendered.
#[derive(Debug, thiserror::Error)]
pub enum ImageError {
    #[error("the scene has no camera")]
    NoCamera,
}

/// Renders the image; `progress(rows_done)` is called as rows finish.
pub fn render_image(
    scene: &Scene,
    opts: &ImageOptions,
    progress: &(dyn Fn(usize) + Sync),
) -> Result<XyzImage, ImageError> {
    let cam = scene.camera.ok_or(ImageError::NoCamera)?;
    let tracer = Tracer::new(scene, opts.strategy);
    let (w, h) = (opts.width.max(1), opts.height.max(1));
    let half_h = (cam.vfov_deg.to_radians() / 2.0).tan();
    let half_w = half_h * w as f64 / h as f64;
    let [x0, y0, x1, y1] = opts.window.unwrap_or([0, 0, w, h]);
    let rows: Vec<Vec<[f32; 3]>> = (0..h)
        .into_par_iter()
        .map(|py| {
            let mut row = vec![[0.0f32; 3]; w];
            if py < y0 || py >= y1 {
                return row;
            }
            for (px, out) in row.iter_mut().enumerate().take(x1.min(w)).skip(x0) {
                let mut acc = [0.0f64; 3];
                for s in 0..opts.spp {
                    let mut rng = Rng::new(opts.seed, (py * w + px) as u64, s);
                    let sx = (-1.0 + 2.0 * (px as f64 + rng.next_f64()) / w as f64) * half_w;
                    let sy = (1.0 - 2.0 * (py as f64 + rng.next_f64()) / h as f64) * half_h;
                    let d = cam
                        .forward
                        .plus(cam.right.times(sx))
                        .plus(cam.up.times(sy))
                        .normalized();
                    let x = tracer.xyz_sample(cam.position, d, &mut rng);
                    for k in 0..3 {
                        acc[k] += x[k];
                    }
                }
                let n = opts.spp.max(1) as f64;
                *out = [
                    (acc[0] / n) as f32,
                    (acc[1] / n) as f32,
                    (acc[2] / n) as f32,
                ];
            }
            progress(1);
            row
        })
        .collect();
    Ok(XyzImage {
        width: w,
        height: h,
        pixels: rows.into_iter().flatten().collect(),
    })
}
