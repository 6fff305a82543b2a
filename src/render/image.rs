//! Image mode: the paper's idealised film (Eq. 2–3). A pixel is the mean radiance over its
//! footprint on the image plane (box filter, no cos⁴ fall-off), projected to absolute XYZ.

use rayon::prelude::*;

use super::geometry::{Vec3, VecOps};
use super::integrator::{Strategy, Tracer};
use super::scene::{Camera, Scene};
use super::spectral::Rng;
use super::spot::Aim;
use crate::image::XyzImage;

/// The camera's image plane at a given size: the scene camera's field of view is kept
/// for any size (the vertical one; the horizontal follows the aspect ratio).
#[derive(Clone, Copy, Debug)]
pub struct Frame {
    pub forward: Vec3,
    pub right: Vec3,
    pub up: Vec3,
    pub width: usize,
    pub height: usize,
    /// tan of half the vertical and horizontal fields of view.
    pub half_h: f64,
    pub half_w: f64,
}

impl Frame {
    pub fn of(cam: &Camera, width: usize, height: usize) -> Frame {
        let (w, h) = (width.max(1), height.max(1));
        let half_h = (cam.vfov_deg.to_radians() / 2.0).tan();
        Frame {
            forward: cam.forward,
            right: cam.right,
            up: cam.up,
            width: w,
            height: h,
            half_h,
            half_w: half_h * w as f64 / h as f64,
        }
    }

    /// Continuous pixel coordinates (x to the right, y down, pixel centres at k + ½) of
    /// the direction `d` from the camera, or None behind it.
    pub fn project(&self, d: Vec3) -> Option<(f64, f64)> {
        let z = d.dot(self.forward);
        if z <= 0.0 {
            return None;
        }
        let (sx, sy) = (d.dot(self.right) / z, d.dot(self.up) / z);
        Some((
            (sx / self.half_w + 1.0) * self.width as f64 / 2.0,
            (1.0 - sy / self.half_h) * self.height as f64 / 2.0,
        ))
    }
}

/// The unit direction through continuous pixel coordinates (fx, fy) of `frame`.
pub fn pixel_direction(frame: &Frame, fx: f64, fy: f64) -> Vec3 {
    let sx = (-1.0 + 2.0 * fx / frame.width as f64) * frame.half_w;
    let sy = (1.0 - 2.0 * fy / frame.height as f64) * frame.half_h;
    frame
        .forward
        .plus(frame.right.times(sx))
        .plus(frame.up.times(sy))
        .normalized()
}

/// What a spot meter at the camera sees in an image: the mean of the pixels whose centre
/// lies inside the meter's cone, each weighted by its solid angle (∝ cos³ of its angle to
/// the optical axis, for a flat image plane), with the number of pixels. None when no
/// pixel centre lies inside (an image too coarse for the spot).
pub fn spot_mean(image: &XyzImage, frame: &Frame, aim: &Aim) -> Option<([f64; 3], usize)> {
    let cos_max = (aim.acceptance_deg.to_radians() / 2.0).cos();
    let (cx, cy) = frame.project(aim.axis)?;
    // The cone's radius in pixels near its centre, with a margin for the plane's stretch.
    let half = (aim.acceptance_deg.to_radians() / 2.0).tan() / frame.half_h;
    let r = (half * frame.height as f64 / 2.0 * 1.5).ceil() as i64 + 1;
    let (mut acc, mut wsum, mut n) = ([0.0f64; 3], 0.0, 0usize);
    for py in (cy as i64 - r).max(0)..(cy as i64 + r + 1).min(image.height as i64) {
        for px in (cx as i64 - r).max(0)..(cx as i64 + r + 1).min(image.width as i64) {
            let d = pixel_direction(frame, px as f64 + 0.5, py as f64 + 0.5);
            if d.dot(aim.axis) < cos_max {
                continue;
            }
            let w = d.dot(frame.forward).powi(3);
            let v = image.at(px as usize, py as usize);
            for k in 0..3 {
                acc[k] += w * f64::from(v[k]);
            }
            wsum += w;
            n += 1;
        }
    }
    (n > 0).then(|| (acc.map(|a| a / wsum), n))
}

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
pub enum ImageRenderError {
    #[error("the scene has no camera")]
    NoCamera,
}

/// Renders the image; `progress(rows_done)` is called as rows finish.
pub fn render_image(
    scene: &Scene,
    opts: &ImageOptions,
    progress: &(dyn Fn(usize) + Sync),
) -> Result<XyzImage, ImageRenderError> {
    let cam = scene.camera.ok_or(ImageRenderError::NoCamera)?;
    let tracer = Tracer::new(scene, opts.strategy);
    let frame = Frame::of(&cam, opts.width, opts.height);
    let (w, h) = (frame.width, frame.height);
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
                    let fx = px as f64 + rng.next_f64();
                    let fy = py as f64 + rng.next_f64();
                    let d = pixel_direction(&frame, fx, fy);
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
