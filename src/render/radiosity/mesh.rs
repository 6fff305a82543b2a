//! The faces of a scene, the convexity check that lets the solver skip visibility, and the
//! piecewise-constant mesh with its form factors.
//!
//! A convex enclosure needs no visibility tests: every face lies on or in front of every
//! other face's plane, so the segment between two front-facing points crosses nothing.
//! The one departure real scenes make is a *decal*: a thin rectangle lying just in front
//! of a larger parallel face (the chart on the wall, the patches on the chart). A decal
//! hides the part of the face beneath it, which is cut out of the mesh; the slit between
//! the two is ignored, an error of the order of the slit's width over the decal's size.

use rayon::prelude::*;

use super::super::deadline::Deadline;
use super::super::geometry::{Rect, Vec3, VecOps};
use super::super::scene::Scene;

use super::form::form_factor;
use super::polygon::{corners, gauss_legendre, point_to_rect};

/// A decal may stand off its face by at most this fraction of its shorter edge.
pub const DECAL_MAX_OFFSET: f64 = 0.05;

/// What a face is in the scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FaceKind {
    Surface(usize),
    Emitter(usize),
}

/// A reflecting rectangle of the scene: a surface or an emitter's own surface.
#[derive(Clone, Debug)]
pub struct Face<'a> {
    pub kind: FaceKind,
    pub name: String,
    pub rect: Rect,
    pub reflectance: &'a Vec<f64>,
}

/// The faces of a scene, surfaces first, then emitters.
pub fn faces(scene: &Scene) -> Vec<Face<'_>> {
    let mut out: Vec<Face> = scene
        .surfaces
        .iter()
        .enumerate()
        .map(|(i, s)| Face {
            kind: FaceKind::Surface(i),
            name: s.name.clone(),
            rect: s.rect,
            reflectance: &s.reflectance,
        })
        .collect();
    for (i, e) in scene.emitters.iter().enumerate() {
        out.push(Face {
            kind: FaceKind::Emitter(i),
            name: format!("emitter {i}"),
            rect: e.rect,
            reflectance: &e.reflectance,
        });
    }
    out
}

/// Why a scene cannot be solved without visibility tests.
#[derive(Clone, Debug, thiserror::Error, PartialEq)]
#[error(
    "the scene is not a convex enclosure: '{behind}' reaches {depth_mm:.2} mm behind the \
     front of '{face}', so the one can hide part of the other and visibility would be needed"
)]
pub struct NotConvex {
    pub face: String,
    pub behind: String,
    pub depth_mm: f64,
}

/// (a, b) of a point in a rectangle's edge coordinates.
fn local(r: &Rect, p: Vec3) -> (f64, f64) {
    let d = p.minus(r.corner);
    (
        d.dot(r.edge_u) / r.edge_u.dot(r.edge_u),
        d.dot(r.edge_v) / r.edge_v.dot(r.edge_v),
    )
}

/// Is `d` a decal on `f`: parallel, facing the same way, a little in front, inside it.
fn is_decal(d: &Rect, f: &Rect) -> bool {
    const EPS: f64 = 1e-9;
    if d.normal.dot(f.normal) < 1.0 - 1e-9 {
        return false;
    }
    let offset = d.corner.minus(f.corner).dot(f.normal);
    let short = d.edge_u.length().min(d.edge_v.length());
    if !(offset > 0.0 && offset <= DECAL_MAX_OFFSET * short) {
        return false;
    }
    corners(d).iter().all(|&c| {
        let (a, b) = local(f, c);
        (-EPS..=1.0 + EPS).contains(&a) && (-EPS..=1.0 + EPS).contains(&b)
    })
}

/// For each face, the faces that are decals on it; or why the scene is not convex. A decal
/// stands off its face's plane by a little, so whatever touches that plane may reach
/// behind the decal's by as much.
pub fn check_convex(faces: &[Face]) -> Result<Vec<Vec<usize>>, NotConvex> {
    let scale = faces
        .iter()
        .map(|f| f.rect.edge_u.length().max(f.rect.edge_v.length()))
        .fold(0.0, f64::max);
    let tol = 1e-9 * scale;
    let mut decals = vec![Vec::new(); faces.len()];
    let mut standoff = vec![0.0f64; faces.len()];
    for (i, fi) in faces.iter().enumerate() {
        for (j, fj) in faces.iter().enumerate() {
            if i != j && is_decal(&fj.rect, &fi.rect) {
                decals[i].push(j);
                let offset = fj.rect.corner.minus(fi.rect.corner).dot(fi.rect.normal);
                standoff[j] = standoff[j].max(offset);
            }
        }
    }
    for (i, fi) in faces.iter().enumerate() {
        for (j, fj) in faces.iter().enumerate() {
            if i == j {
                continue;
            }
            let depth = corners(&fj.rect)
                .iter()
                .map(|c| c.minus(fi.rect.corner).dot(fi.rect.normal))
                .fold(f64::INFINITY, f64::min);
            if depth < -(standoff[i] + tol) {
                return Err(NotConvex {
                    face: fi.name.clone(),
                    behind: fj.name.clone(),
                    depth_mm: -depth * 1e3,
                });
            }
        }
    }
    Ok(decals)
}

/// Intervals narrower than this fraction of the base size are never subdivided.
pub const SMALL_INTERVAL: f64 = 0.25;

/// One piecewise-constant element.
#[derive(Clone, Debug)]
pub struct Element {
    pub face: usize,
    pub rect: Rect,
    /// The longer edge.
    pub size: f64,
}

/// The mesh of one refinement level: every face cut at its decals' and tiles' edges, each
/// piece divided into ⌈length/base⌉·level equal parts per side.
pub struct Mesh {
    pub elements: Vec<Element>,
    /// Row-major N×N: F[i·N + k] = mean over element i of F(x → element k).
    pub form: Vec<f64>,
}

fn splits(len: f64, cuts: &mut Vec<f64>, base: f64, level: usize) -> Vec<f64> {
    cuts.push(0.0);
    cuts.push(1.0);
    cuts.retain(|c| (0.0..=1.0).contains(c));
    cuts.sort_by(f64::total_cmp);
    cuts.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
    let mut out = vec![0.0];
    for w in cuts.windows(2) {
        let width = (w[1] - w[0]) * len;
        // Strips cut by decals (the gaps between patches, the patches themselves) are
        // already finer than the mesh needs to be; refining them only adds elements.
        let pieces = if width < base * SMALL_INTERVAL {
            1
        } else {
            ((width / base - 1e-9).ceil().max(1.0) as usize) * level
        };
        for p in 1..=pieces {
            out.push(w[0] + (w[1] - w[0]) * p as f64 / pieces as f64);
        }
    }
    out
}

/// Most elements of a mesh: the form factors are N² numbers (5,000 → 200 MB).
pub const MAX_ELEMENTS: usize = 5_000;

/// The elements of level `level` (1, 2, 3, …) on base size `base` (m), or None when there
/// would be more than `max`. Faces that reflect nothing carry no radiosity and are left out
/// (they still absorb: no light reaches them in the system, and none leaves them).
pub fn elements(
    scene: &Scene,
    faces: &[Face],
    decals: &[Vec<usize>],
    base: f64,
    level: usize,
    max: usize,
) -> Option<Vec<Element>> {
    let mut out = Vec::new();
    for (fi, f) in faces.iter().enumerate() {
        if f.reflectance.iter().all(|r| *r == 0.0) {
            continue;
        }
        let mut ca = Vec::new();
        let mut cb = Vec::new();
        let ranges: Vec<((f64, f64), (f64, f64))> = decals[fi]
            .iter()
            .map(|&d| {
                let pts: Vec<(f64, f64)> = corners(&faces[d].rect)
                    .iter()
                    .map(|&c| local(&f.rect, c))
                    .collect();
                let amin = pts.iter().map(|p| p.0).fold(f64::INFINITY, f64::min);
                let amax = pts.iter().map(|p| p.0).fold(f64::NEG_INFINITY, f64::max);
                let bmin = pts.iter().map(|p| p.1).fold(f64::INFINITY, f64::min);
                let bmax = pts.iter().map(|p| p.1).fold(f64::NEG_INFINITY, f64::max);
                ((amin, amax), (bmin, bmax))
            })
            .collect();
        for ((a0, a1), (b0, b1)) in &ranges {
            ca.extend([*a0, *a1]);
            cb.extend([*b0, *b1]);
        }
        if let FaceKind::Emitter(e) = f.kind {
            let e = &scene.emitters[e];
            ca.extend((1..e.cols).map(|k| k as f64 / e.cols as f64));
            cb.extend((1..e.rows).map(|k| k as f64 / e.rows as f64));
        }
        let sa = splits(f.rect.edge_u.length(), &mut ca, base, level);
        let sb = splits(f.rect.edge_v.length(), &mut cb, base, level);
        if (sa.len() - 1).saturating_mul(sb.len() - 1) > max.saturating_mul(4) {
            return None;
        }
        for wb in sb.windows(2) {
            for wa in sa.windows(2) {
                let (am, bm) = ((wa[0] + wa[1]) / 2.0, (wb[0] + wb[1]) / 2.0);
                let hidden = ranges.iter().any(|((a0, a1), (b0, b1))| {
                    (*a0..=*a1).contains(&am) && (*b0..=*b1).contains(&bm)
                });
                if hidden {
                    continue;
                }
                let eu = f.rect.edge_u.times(wa[1] - wa[0]);
                let ev = f.rect.edge_v.times(wb[1] - wb[0]);
                if out.len() == max {
                    return None;
                }
                out.push(Element {
                    face: fi,
                    rect: Rect::new(f.rect.point(wa[0], wb[0]), eu, ev),
                    size: eu.length().max(ev.length()),
                });
            }
        }
    }
    Some(out)
}

/// Gauss–Legendre nodes per side for averaging a factor over a receiving element of size
/// `size` whose source is `dist` away: the midpoint when far, up to 4×4 when adjacent.
/// The rule depends on the ratio only, so a refined mesh meets the same rules.
pub fn receiver_nodes(size: f64, dist: f64) -> usize {
    ((1.0 + 6.0 * size / dist.max(1e-12)).floor() as usize).clamp(1, 6)
}

/// Mean of `f(x)` over a rectangle by an n×n Gauss–Legendre rule.
pub fn average_over(r: &Rect, n: usize, mut f: impl FnMut(Vec3) -> f64) -> f64 {
    if n == 1 {
        return f(r.centre());
    }
    let q = gauss_legendre(n);
    let mut s = 0.0;
    for &(a, wa) in &q {
        for &(b, wb) in &q {
            s += wa * wb * f(r.point(a, b));
        }
    }
    s
}

impl Mesh {
    /// The mesh and its form factors, or None if the deadline passed first. Each pair is
    /// integrated once, over the smaller of the two elements, and the other direction
    /// follows by reciprocity (A_i F_ik = A_k F_ki); rows of pairs are computed in parallel.
    pub fn build(elements: Vec<Element>, deadline: Deadline) -> Option<Mesh> {
        let n = elements.len();
        let area: Vec<f64> = elements.iter().map(|e| e.rect.area_m2).collect();
        let upper: Vec<Vec<f64>> = (0..n)
            .into_par_iter()
            .map(|i| {
                if deadline.passed() {
                    return Vec::new();
                }
                let ei = &elements[i];
                ((i + 1)..n)
                    .map(|k| {
                        let ek = &elements[k];
                        if ei.face == ek.face {
                            return 0.0;
                        }
                        let dist = ek.rect.centre().minus(ei.rect.centre()).length();
                        let nodes = receiver_nodes(ei.size + ek.size, dist);
                        // In closed form where it has one, near or far: any fixed point
                        // rule leaves an error that changes class with the level and
                        // spoils the extrapolation (see `form`).
                        if let Some(f) = form_factor(&ei.rect, &ek.rect, nodes > 1) {
                            return f;
                        }
                        // F from the smaller element, expressed as F_ik.
                        if area[i] <= area[k] {
                            average_over(&ei.rect, nodes, |x| {
                                point_to_rect(x, ei.rect.normal, &ek.rect)
                            })
                        } else {
                            average_over(&ek.rect, nodes, |x| {
                                point_to_rect(x, ek.rect.normal, &ei.rect)
                            }) * area[k]
                                / area[i]
                        }
                    })
                    .collect()
            })
            .collect();
        if deadline.passed() {
            return None;
        }
        let mut form = vec![0.0; n * n];
        for (i, row) in upper.iter().enumerate() {
            for (off, &f) in row.iter().enumerate() {
                let k = i + 1 + off;
                form[i * n + k] = f;
                form[k * n + i] = f * area[i] / area[k];
            }
        }
        Some(Mesh { elements, form })
    }
}
