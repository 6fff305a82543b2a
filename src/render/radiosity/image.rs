//! The camera image from the radiosity solution: what the spot readings see, for every
//! pixel.
//!
//! Every surface is Lambertian, so the radiance a camera ray sees is the reflected
//! radiance at its first hit, ρ(λ)·(E_direct(x, λ) + E_indirect(x, λ))/π, plus the
//! emitter's own radiance where the ray meets a tile. Both irradiances are smooth over a
//! face (the box is convex: no shadows), so they are evaluated exactly as the meter's
//! gather does — the direct term in closed form, the indirect by exact point-to-element
//! factors from the solved mesh — on a grid of nodes over each visible face, and each
//! pixel interpolates its face's grid bilinearly. Like the spot readings, the indirect
//! term is extrapolated (Richardson) from the last two mesh levels, so an image's patch
//! regions read what the 24 spot readings read.

use rayon::prelude::*;

use super::super::geometry::{Vec3, VecOps};
use super::super::image::{pixel_direction, Frame};
use super::super::spectral::N_BINS;
use super::bound::richardson;
use super::direct::irradiance_factor;
use super::gather::hit;
use super::lights::Lights;
use super::mesh::{Face, FaceKind};
use super::polygon::point_to_rect;
use super::{solve_level, LastLevels, Prepared, RadiosityError, RadiosityOptions, Solved};
use crate::color::K_M;
use crate::image::XyzImage;
use crate::render::deadline::Deadline;
use crate::render::scene::Scene;
use crate::render::spot::SpotError;

/// What to render.
#[derive(Clone, Copy, Debug)]
pub struct RadiosityImageOptions {
    pub width: usize,
    pub height: usize,
    /// The finest mesh level (the spot readings' last); with 2 or more the indirect term is
    /// extrapolated from this level and the one before, as the readings are.
    pub level: usize,
    /// Sub-pixel samples per side (a k×k grid of ray positions per pixel, box filter).
    pub subpixels: usize,
    /// Largest spacing of the interpolation nodes on a face (m); faces shorter than eight
    /// spacings get eight intervals.
    pub node_spacing_m: f64,
}

impl Default for RadiosityImageOptions {
    fn default() -> Self {
        RadiosityImageOptions {
            width: 1014,
            height: 1014,
            level: 3,
            subpixels: 1,
            node_spacing_m: 0.01,
        }
    }
}

/// What a camera ray sees first.
#[derive(Clone, Copy)]
enum Seen {
    Nothing,
    Face { face: usize, a: f64, b: f64 },
}

/// XYZ (cd/m²) per unit of a spectral factor for one face: K_m Σ ρ·S·x̄ etc.
fn project(scene: &Scene, refl: &[f64], spectrum: &[f64]) -> [f64; 3] {
    std::array::from_fn(|k| {
        K_M * (0..N_BINS)
            .map(|i| refl[i] * spectrum[i] * scene.cmf[k][i])
            .sum::<f64>()
    })
}

/// One face's reflected radiance as XYZ on a node grid, row-major `na × nb`.
struct Grid {
    na: usize,
    nb: usize,
    xyz: Vec<[f64; 3]>,
}

impl Grid {
    fn at(&self, a: f64, b: f64) -> [f64; 3] {
        let fa = (a.clamp(0.0, 1.0) * (self.na - 1) as f64).min((self.na - 1) as f64 - 1e-9);
        let fb = (b.clamp(0.0, 1.0) * (self.nb - 1) as f64).min((self.nb - 1) as f64 - 1e-9);
        let (ia, ib) = (fa.floor() as usize, fb.floor() as usize);
        let (ta, tb) = (fa - ia as f64, fb - ib as f64);
        let v = |i: usize, j: usize| self.xyz[j * self.na + i];
        let (v00, v10, v01, v11) = (v(ia, ib), v(ia + 1, ib), v(ia, ib + 1), v(ia + 1, ib + 1));
        std::array::from_fn(|k| {
            (1.0 - tb) * ((1.0 - ta) * v00[k] + ta * v10[k])
                + tb * ((1.0 - ta) * v01[k] + ta * v11[k])
        })
    }
}

/// The indirect XYZ basis of one solved level: per element j, K_m Σ ρ_face·T_j·cmf with
/// T_j(λ) = Σ_c S_c(λ)·ℓ_cj(λ), for the face `fi`.
fn indirect_basis(scene: &Scene, lights: &Lights, solved: &Solved, refl: &[f64]) -> Vec<[f64; 3]> {
    let nb = solved.bands.len();
    solved
        .mesh
        .elements
        .par_iter()
        .enumerate()
        .map(|(j, _)| {
            let mut t = vec![0.0; N_BINS];
            for (c, comp) in lights.comps.iter().enumerate() {
                let l = solved.bands.interpolate(&solved.l[c][j * nb..(j + 1) * nb]);
                for i in 0..N_BINS {
                    t[i] += comp.spectrum[i] * l[i];
                }
            }
            project(scene, refl, &t)
        })
        .collect()
}

/// The irradiance part seen from `x` on face `fi` through the elements of one level.
fn indirect_at(solved: &Solved, basis: &[[f64; 3]], fi: usize, x: Vec3, n: Vec3) -> [f64; 3] {
    let mut out = [0.0; 3];
    for (el, b) in solved.mesh.elements.iter().zip(basis) {
        if el.face == fi {
            continue;
        }
        let f = point_to_rect(x, n, &el.rect);
        for k in 0..3 {
            out[k] += f * b[k];
        }
    }
    out
}

/// The node grid of face `fi`: direct in closed form, indirect from `levels` (one level,
/// or the last two to extrapolate with order `order` and element sizes `h`).
fn face_grid(
    scene: &Scene,
    lights: &Lights,
    face: &Face,
    fi: usize,
    levels: &[(Solved, f64)],
    order: f64,
    spacing: f64,
) -> Grid {
    let r = &face.rect;
    let nodes = |len: f64| ((len / spacing).ceil() as usize).max(8) + 1;
    let (na, nb) = (nodes(r.edge_u.length()), nodes(r.edge_v.length()));
    if face.reflectance.iter().all(|v| *v == 0.0) {
        return Grid {
            na,
            nb,
            xyz: vec![[0.0; 3]; na * nb],
        };
    }
    let direct: Vec<[f64; 3]> = lights
        .comps
        .iter()
        .map(|c| project(scene, face.reflectance, c.spectrum))
        .collect();
    let bases: Vec<Vec<[f64; 3]>> = levels
        .iter()
        .map(|(s, _)| indirect_basis(scene, lights, s, face.reflectance))
        .collect();
    let n = r.normal;
    let xyz = (0..na * nb)
        .into_par_iter()
        .map(|idx| {
            let (i, j) = (idx % na, idx / na);
            let x = r.point(i as f64 / (na - 1) as f64, j as f64 / (nb - 1) as f64);
            let mut v = [0.0; 3];
            for (c, comp) in lights.comps.iter().enumerate() {
                let g = irradiance_factor(&scene.emitters[comp.emitter], &comp.weights, x, n)
                    / std::f64::consts::PI;
                for k in 0..3 {
                    v[k] += g * direct[c][k];
                }
            }
            let ind: Vec<[f64; 3]> = levels
                .iter()
                .zip(&bases)
                .map(|((s, _), b)| indirect_at(s, b, fi, x, n))
                .collect();
            let indirect = match (ind.as_slice(), levels) {
                ([coarse, fine], [(_, hc), (_, hf)]) => {
                    std::array::from_fn(|k| richardson(coarse[k], *hc, fine[k], *hf, order))
                }
                _ => ind[ind.len() - 1],
            };
            std::array::from_fn(|k| v[k] + indirect[k])
        })
        .collect();
    Grid { na, nb, xyz }
}

/// Whether `level` can be an image's finest mesh level; callers that decide on the solver
/// first check it sooner, so a bad level is reported before whether the scene qualifies.
pub fn check_level(level: usize) -> Result<(), RadiosityError> {
    if level == 0 {
        return Err(RadiosityError::BadOption {
            what: "the image's mesh level",
            need: "at least 1",
            got: 0.0,
        });
    }
    Ok(())
}

/// Renders the camera's image from the radiosity solution (see the module doc), solving
/// the levels `opts.level − 1` and `opts.level` first.
pub fn render_image_radiosity(
    scene: &Scene,
    ropts: &RadiosityOptions,
    opts: &RadiosityImageOptions,
) -> Result<XyzImage, RadiosityError> {
    check_level(opts.level)?;
    let deadline = Deadline::after(ropts.max_seconds);
    let p = Prepared::for_probes(scene)?;
    let refl: Vec<&[f64]> = p.faces.iter().map(|f| f.reflectance.as_slice()).collect();
    let first = if opts.level >= 2 { opts.level - 1 } else { 1 };
    let mut levels: LastLevels = Vec::new();
    for level in first..=opts.level {
        let solved = solve_level(&p, &refl, ropts, level, None, deadline)?;
        levels.push((solved, p.base(ropts) / level as f64));
    }
    render_image_from(scene, &levels, ropts, opts)
}

/// What each of the k×k sample rays per pixel hits, and the emitter radiance it sees
/// directly (XYZ).
fn sample_rays(
    scene: &Scene,
    faces: &[Face],
    origin: Vec3,
    frame: &Frame,
    k: usize,
) -> Vec<(Seen, [f64; 3])> {
    (0..frame.width * frame.height * k * k)
        .into_par_iter()
        .map(|idx| {
            let (pixel, sub) = (idx / (k * k), idx % (k * k));
            let (px, py) = (pixel % frame.width, pixel / frame.width);
            let fx = px as f64 + ((sub % k) as f64 + 0.5) / k as f64;
            let fy = py as f64 + ((sub / k) as f64 + 0.5) / k as f64;
            let d = pixel_direction(frame, fx, fy);
            let Some((fi, _, a, b)) = hit(faces, origin, d) else {
                return (Seen::Nothing, [0.0; 3]);
            };
            let mut emitted = [0.0; 3];
            if let FaceKind::Emitter(e) = faces[fi].kind {
                let em = &scene.emitters[e];
                let tile = em.tile_at(a, b);
                let s = &em.spectra[em.tile_spectrum[tile] as usize];
                let w = em.gains[tile] * em.directional(d.times(-1.0));
                emitted = std::array::from_fn(|k| {
                    w * K_M * (0..N_BINS).map(|i| s[i] * scene.cmf[k][i]).sum::<f64>()
                });
            }
            (Seen::Face { face: fi, a, b }, emitted)
        })
        .collect()
}

/// Renders the camera's image from solved levels (one, or the last two of a spot run:
/// see [`super::render_spots_radiosity_solved`]); `opts.level` is not used.
pub fn render_image_from(
    scene: &Scene,
    levels: &[(Solved, f64)],
    ropts: &RadiosityOptions,
    opts: &RadiosityImageOptions,
) -> Result<XyzImage, RadiosityError> {
    let cam = scene.camera.ok_or(SpotError::NoCamera)?;
    if !(opts.node_spacing_m > 0.0 && opts.node_spacing_m.is_finite()) {
        return Err(RadiosityError::BadOption {
            what: "the image's node spacing",
            need: "> 0 m",
            got: opts.node_spacing_m,
        });
    }
    if levels.is_empty() {
        return Err(RadiosityError::BadOption {
            what: "the number of solved levels",
            need: "1 or 2",
            got: 0.0,
        });
    }
    let deadline = Deadline::after(ropts.max_seconds);
    let p = Prepared::for_probes(scene)?;
    let frame = Frame::of(&cam, opts.width, opts.height);
    let k = opts.subpixels.max(1);
    let faces = &p.faces;
    // Pass 1: what each sample ray hits, and the emitter radiance it sees directly.
    let samples = sample_rays(scene, faces, cam.position, &frame, k);
    // Pass 2: a node grid on every face some ray sees.
    let mut visible = vec![false; faces.len()];
    for (s, _) in &samples {
        if let Seen::Face { face, .. } = s {
            visible[*face] = true;
        }
    }
    let mut grids: Vec<Option<Grid>> = Vec::with_capacity(faces.len());
    for (fi, face) in faces.iter().enumerate() {
        if deadline.passed() {
            return Err(RadiosityError::TimeLimit {
                seconds: ropts.max_seconds,
                during: "while drawing the image".into(),
            });
        }
        grids.push(visible[fi].then(|| {
            face_grid(
                scene,
                &p.lights,
                face,
                fi,
                levels,
                ropts.order,
                opts.node_spacing_m,
            )
        }));
    }
    // Pass 3: each pixel the mean of its samples.
    let n = (k * k) as f64;
    let pixels = samples
        .par_chunks(k * k)
        .map(|px| {
            let mut acc = [0.0; 3];
            for (seen, emitted) in px {
                if let Seen::Face { face, a, b } = seen {
                    let v = grids[*face].as_ref().map_or([0.0; 3], |g| g.at(*a, *b));
                    for c in 0..3 {
                        acc[c] += v[c] + emitted[c];
                    }
                }
            }
            acc.map(|v| (v / n) as f32)
        })
        .collect();
    Ok(XyzImage {
        width: frame.width,
        height: frame.height,
        pixels,
    })
}
