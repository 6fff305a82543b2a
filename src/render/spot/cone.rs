//! The meter's cone read from an image of the scene's camera instead of traced: which
//! pixels it covers and by how much, and the weighted mean of their XYZ with the
//! uncertainty of that mean. The image is taken with the mapping of `render image`
//! ([`Frame`], [`pixel_direction`]): rows top to bottom, not mirrored, the camera's
//! vertical field of view at any size.
//!
//! A pixel's weight is the solid angle of its part inside the cone: its footprint on the
//! image plane (at unit distance) is cut into [`SUBPIXELS`]² cells, each inside or not by
//! its centre's direction, and each inside cell weighs its area times cos³ of its angle to
//! the optical axis (the solid angle a small patch of a flat image plane subtends). So the
//! weights sum to the cone's solid angle, 2π(1 − cos α), and the mean is uniform in solid
//! angle over the cone, as the traced meter's samples are; pixels on the rim count by
//! the part of them inside.
//!
//! The uncertainty is the standard error of that weighted mean from the pixels' spread:
//! the weighted covariance of the pixels about the mean (with the reliability-weights
//! correction 1 − Σŵ², ŵ the normalised weights) times Σŵ², which is 1 / the effective
//! number of pixels. This assumes the pixels' errors are independent and alike, which
//! holds for a path tracer's pixels (each its own samples). A denoised or filtered image's
//! pixels are correlated and the error is understated; a real gradient of radiance across
//! the cone counts as noise and overstates it (a radiosity image has no noise at all and
//! gets only that).

use std::path::PathBuf;

use super::Aim;
use crate::color::Xyz;
use crate::image::XyzImage;
use crate::render::image::{pixel_direction, Frame};

/// Cells per pixel side for the inside test: an error of the rim's area of well under a
/// pixel's, against a cone tens of pixels across at the camera's size.
pub const SUBPIXELS: usize = 8;

/// A pixel the cone covers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ConePixel {
    pub x: usize,
    pub y: usize,
    /// The solid angle (sr) of its part inside the cone.
    pub weight: f64,
}

/// Why a cone cannot be read from an image.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ConeError {
    #[error("part of the cone is behind the camera")]
    Behind,
    #[error(
        "the cone reaches outside the image (pixels {x0}..{x1} × {y0}..{y1} of {width}×{height})"
    )]
    OutsideImage {
        x0: i64,
        x1: i64,
        y0: i64,
        y1: i64,
        width: usize,
        height: usize,
    },
    #[error("pixel ({x}, {y}) (from the top left) is {value:?}, not a finite XYZ ≥ 0")]
    BadPixel { x: usize, y: usize, value: [f32; 3] },
}

/// The fewest effective pixels a cone must cover: below that its spread says little of
/// the noise, and the rim's partial pixels dominate.
pub const MIN_EFFECTIVE_PIXELS: f64 = 16.0;

/// Why an image cannot be read back as the meter's readings.
#[derive(Debug, thiserror::Error)]
pub enum ReadBackError {
    #[error(
        "{}: the image is {width}×{height} pixels, the scene camera's {camera_width}×\
         {camera_height}: another aspect ratio is another horizontal field of view, so the \
         pixels do not look where the camera does (render it at {camera_width}×\
         {camera_height} or a size of the same aspect ratio)",
        file.display()
    )]
    Aspect {
        file: PathBuf,
        width: usize,
        height: usize,
        camera_width: usize,
        camera_height: usize,
    },
    #[error(
        "{}: the scene has no meter (its acceptance angle), so there is no cone to read",
        scene
    )]
    NoMeter { scene: String },
    #[error("{}: patch {patch}'s 1° cone: {error}", file.display())]
    Cone {
        file: PathBuf,
        patch: usize,
        error: ConeError,
    },
    #[error(
        "{}: patch {patch}'s cone covers {pixels} pixels, worth {effective:.1} equally \
         weighted ones; at least {MIN_EFFECTIVE_PIXELS} are needed to estimate the noise: \
         render the image larger",
        file.display()
    )]
    TooCoarse {
        file: PathBuf,
        patch: usize,
        pixels: usize,
        effective: f64,
    },
    #[error(
        "{}: every pixel in patch {patch}'s cone is zero: the image is black there (a light \
         missing, or values in a unit far below cd/m²)",
        file.display()
    )]
    Dark { file: PathBuf, patch: usize },
    #[error(
        "{}: patch 19 (the chart's white) reads Y = {patch:.4} against the white diffuser's \
         {white:.4} cd/m², {ratio:.3} times it: outside 0.1–10, so the image is not in cd/m² \
         of this scene (W/(sr·m²) would be 683 times too small) or not of this scene",
        file.display()
    )]
    Units {
        file: PathBuf,
        patch: f64,
        white: f64,
        ratio: f64,
    },
}

/// The pixels of an image of `frame`'s size inside `aim`'s cone, each with its weight.
pub fn cone_pixels(frame: &Frame, aim: &Aim) -> Result<Vec<ConePixel>, ConeError> {
    let cos_max = (aim.acceptance_deg.to_radians() / 2.0).cos();
    // The rim's image bounds the cone's: a closed curve around the axis's image.
    let mut bounds = [
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    ];
    const RIM: usize = 256;
    for i in 0..RIM {
        let d = super::cone_direction(aim.axis, cos_max, 1.0, i as f64 / RIM as f64);
        let (x, y) = frame.project(d).ok_or(ConeError::Behind)?;
        bounds = [
            bounds[0].min(x),
            bounds[1].max(x),
            bounds[2].min(y),
            bounds[3].max(y),
        ];
    }
    // A pixel of margin: the rim between the points sampled bulges less than that.
    let (x0, x1) = (bounds[0].floor() as i64 - 1, bounds[1].ceil() as i64 + 1);
    let (y0, y1) = (bounds[2].floor() as i64 - 1, bounds[3].ceil() as i64 + 1);
    let (w, h) = (frame.width as i64, frame.height as i64);
    if x0 < 0 || y0 < 0 || x1 > w || y1 > h {
        return Err(ConeError::OutsideImage {
            x0,
            x1,
            y0,
            y1,
            width: frame.width,
            height: frame.height,
        });
    }
    let cell_area = (2.0 * frame.half_w / frame.width as f64)
        * (2.0 * frame.half_h / frame.height as f64)
        / (SUBPIXELS * SUBPIXELS) as f64;
    let mut out = Vec::new();
    for py in y0..y1 {
        for px in x0..x1 {
            let mut weight = 0.0;
            for j in 0..SUBPIXELS {
                for i in 0..SUBPIXELS {
                    let fx = px as f64 + (i as f64 + 0.5) / SUBPIXELS as f64;
                    let fy = py as f64 + (j as f64 + 0.5) / SUBPIXELS as f64;
                    let d = pixel_direction(frame, fx, fy);
                    if d.dot(aim.axis) >= cos_max {
                        weight += d.dot(frame.forward).powi(3) * cell_area;
                    }
                }
            }
            if weight > 0.0 {
                out.push(ConePixel {
                    x: px as usize,
                    y: py as usize,
                    weight,
                });
            }
        }
    }
    Ok(out)
}

/// The weighted mean of an image over a cone and how sure it is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ConeMean {
    /// The mean XYZ (the image's unit).
    pub xyz: Xyz,
    /// The covariance of the mean, from the pixels' spread (see the module comment).
    pub cov_mean: [[f64; 3]; 3],
    /// Pixels with a part inside the cone.
    pub pixels: usize,
    /// (Σw)² / Σw²: how many equally weighted pixels the mean is worth.
    pub effective: f64,
    /// Σw, the cone's solid angle as the pixels cover it (sr).
    pub solid_angle: f64,
}

impl ConeMean {
    /// The standard error of each of X, Y, Z.
    pub fn stderr(&self) -> [f64; 3] {
        [0, 1, 2].map(|k| self.cov_mean[k][k].max(0.0).sqrt())
    }
}

/// The mean of `image` over `cone` (of [`cone_pixels`] for its size). Refuses a pixel in
/// the cone that is not finite or has a negative component: XYZ of light is never
/// negative, and such a pixel means an image that is not absolute XYZ.
pub fn cone_mean(image: &XyzImage, cone: &[ConePixel]) -> Result<ConeMean, ConeError> {
    let (mut sw, mut sw2) = (0.0, 0.0);
    let mut sx = [0.0; 3];
    for p in cone {
        let v = image.at(p.x, p.y);
        if !v.iter().all(|c| c.is_finite() && *c >= 0.0) {
            return Err(ConeError::BadPixel {
                x: p.x,
                y: p.y,
                value: v,
            });
        }
        sw += p.weight;
        sw2 += p.weight * p.weight;
        for k in 0..3 {
            sx[k] += p.weight * f64::from(v[k]);
        }
    }
    let mean = sx.map(|s| s / sw.max(f64::MIN_POSITIVE));
    // About the mean, not from raw sums: the spread is small against the values.
    let mut s = [[0.0; 3]; 3];
    for p in cone {
        let v = image.at(p.x, p.y);
        let d = [0, 1, 2].map(|k| f64::from(v[k]) - mean[k]);
        for i in 0..3 {
            for j in 0..3 {
                s[i][j] += p.weight * d[i] * d[j];
            }
        }
    }
    let sum_w2 = sw2 / (sw * sw).max(f64::MIN_POSITIVE);
    // The reliability-weights correction; one pixel leaves no spread to estimate from.
    let correction = 1.0 - sum_w2;
    let cov_mean = s.map(|row| {
        row.map(|c| {
            if correction > 0.0 {
                c / sw / correction * sum_w2
            } else {
                f64::INFINITY
            }
        })
    });
    Ok(ConeMean {
        xyz: mean.into(),
        cov_mean,
        pixels: cone.len(),
        effective: 1.0 / sum_w2.max(f64::MIN_POSITIVE),
        solid_angle: sw,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::geometry::{Vec3, VecOps};
    use crate::render::scene::Camera;

    fn frame(size: usize) -> Frame {
        let cam = Camera {
            position: Vec3::ZERO,
            forward: Vec3::Z,
            right: Vec3::X,
            up: Vec3::Y,
            vfov_deg: 15.71,
            width: size,
            height: size,
        };
        Frame::of(&cam, size, size)
    }

    /// An aim off the optical axis, as most patches are.
    fn aim() -> Aim {
        Aim {
            origin: Vec3::ZERO,
            axis: Vec3::new(0.06, -0.04, 1.0).normalized(),
            acceptance_deg: 1.0,
        }
    }

    /// The image whose X at each pixel centre is (1 − cos θ) / (1 − cos α), θ the angle
    /// to the aim and α the cone's half angle; Y is 1, Z is 0.
    fn image(frame: &Frame, aim: &Aim) -> XyzImage {
        let cos_a = (aim.acceptance_deg.to_radians() / 2.0).cos();
        let mut pixels = Vec::new();
        for y in 0..frame.height {
            for x in 0..frame.width {
                let d = pixel_direction(frame, x as f64 + 0.5, y as f64 + 0.5);
                pixels.push([((1.0 - d.dot(aim.axis)) / (1.0 - cos_a)) as f32, 1.0, 0.0]);
            }
        }
        XyzImage {
            width: frame.width,
            height: frame.height,
            pixels,
        }
    }

    #[test]
    fn the_weights_are_the_cones_solid_angle_and_the_mean_is_uniform_in_it() {
        // At the camera's 1014 pixels the 1° cone is about 65 pixels across.
        let (f, a) = (frame(1014), aim());
        let cone = cone_pixels(&f, &a).unwrap();
        let m = cone_mean(&image(&f, &a), &cone).unwrap();
        let alpha = 0.5f64.to_radians();
        let omega = 2.0 * std::f64::consts::PI * (1.0 - alpha.cos());
        // The rim's cells are in or out by their centres: an error of about a cell's
        // width along the rim, (π·65 px)·(1/8 px) / (π·32.5² px²) ≈ 0.4 % at most.
        assert!(
            (m.solid_angle / omega - 1.0).abs() < 1e-3,
            "{} sr against {omega} sr",
            m.solid_angle
        );
        // Uniform in solid angle over the cone, (1 − cos θ) has the mean
        // ∫₀^α (1 − cos θ) sin θ dθ / ∫₀^α sin θ dθ = (1 − cos α) / 2: X's mean is ½.
        // The pixels hold the value at their centres, not their footprint's mean: the
        // function is nearly quadratic in the offset, so the difference is about
        // (pixel / cone radius)² / 12 of it, 1e-4 here.
        assert!((m.xyz[0] - 0.5).abs() < 2e-3, "{:?}", m.xyz);
        assert!((m.xyz[1] - 1.0).abs() < 1e-6 && m.xyz[2] == 0.0);
        // A constant has no spread; X's pixels spread over [0, 1] (variance 1/12 if the
        // values were uniform in solid angle — they are: (1 − cos θ) is, over the cone).
        assert_eq!(m.cov_mean[1][1], 0.0);
        let var_pixels = m.cov_mean[0][0] * m.effective;
        assert!(
            (var_pixels / (1.0 / 12.0) - 1.0).abs() < 0.02,
            "{var_pixels}"
        );
        // The pixels inside: about the disc's area, π·32.5², and the rim's partial ones.
        assert!(
            m.effective > 2900.0 && m.effective < 3500.0,
            "{}",
            m.effective
        );
    }

    #[test]
    fn a_coarse_image_weighs_its_rim_pixels_by_their_part_inside() {
        // Ten times coarser: the cone about 6.5 pixels across, most of its pixels on the
        // rim; the cells still recover the solid angle to about a percent.
        let (f, a) = (frame(101), aim());
        let cone = cone_pixels(&f, &a).unwrap();
        let total: f64 = cone.iter().map(|p| p.weight).sum();
        let omega = 2.0 * std::f64::consts::PI * (1.0 - 0.5f64.to_radians().cos());
        assert!(
            (total / omega - 1.0).abs() < 0.02,
            "{total} sr against {omega}"
        );
        let full = cone.iter().map(|p| p.weight).fold(0.0, f64::max);
        assert!(cone.iter().any(|p| p.weight < full / 2.0));
    }

    #[test]
    fn a_cone_off_the_image_or_a_negative_pixel_in_it_is_refused() {
        let f = frame(64);
        let edge = Aim {
            axis: Vec3::new(0.0, 0.138, 1.0).normalized(),
            ..aim()
        };
        assert!(matches!(
            cone_pixels(&f, &edge),
            Err(ConeError::OutsideImage { .. })
        ));
        let behind = Aim {
            axis: Vec3::NEG_Z,
            ..aim()
        };
        assert_eq!(cone_pixels(&f, &behind), Err(ConeError::Behind));
        let cone = cone_pixels(&f, &aim()).unwrap();
        let mut img = image(&f, &aim());
        let p = cone[cone.len() / 2];
        img.pixels[p.y * 64 + p.x] = [1.0, -0.5, 1.0];
        assert_eq!(
            cone_mean(&img, &cone),
            Err(ConeError::BadPixel {
                x: p.x,
                y: p.y,
                value: [1.0, -0.5, 1.0]
            })
        );
    }
}
