//! The first bounce at a point, independent of the mesh: the direct light, reflected once,
//! integrated over the faces by adaptive quadrature.
//!
//! The element solution carries the direct light as one mean per element. A point gathers
//! those means with exact point-to-element factors, which is accurate where the elements
//! are small against their distance from it; near a wall, where the direct irradiance falls
//! from its peak to nothing at the emitter's plane within one element, it is not, and as the
//! levels' meshes are not nested that error moves erratically from level to level (a
//! ceiling probe 0.5 m from a wall of a room lit by one panel needed level 11 before the
//! levels agreed). The direct irradiance is known in closed form at every point, so its
//! first reflection is integrated here to a relative tolerance instead, once per point for
//! all levels; the mesh then carries only the light that has bounced at least twice, which
//! is smooth. The quadrature's own error estimate joins the point's bound.

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use super::super::geometry::{Rect, Vec3, VecOps};
use super::super::scene::Scene;
use super::direct::irradiance_factor;
use super::lights::Lights;
use super::mesh::{elements, Face};
use super::polygon::gauss_legendre;

/// Relative tolerance of the quadrature, against the whole first bounce at the point.
pub const REL_TOLERANCE: f64 = 1e-9;

/// Most cells refined per point: bounds the work at a point on an edge, where the kernel is
/// singular and the tolerance may not be met (its error estimate then says so).
pub const MAX_REFINEMENTS: usize = 3_000;

/// Gauss–Legendre nodes per side of a cell.
const NODES: usize = 4;

/// The first bounce at one point.
#[derive(Clone, Debug, PartialEq)]
pub struct FirstBounce {
    /// Per light component, per face: ∫ (g(y)/π)·K(x, y) dy over the face's visible part, g
    /// the component's irradiance factor and K the point-to-point configuration kernel.
    pub per_face: Vec<Vec<f64>>,
    /// Per light component: the estimated absolute error of Σ_faces ρ_max(face)·per_face.
    pub error: Vec<f64>,
}

/// The visible pieces of every face that reflects (decals cut out), as in the mesh's
/// first level with no refinement.
pub fn pieces(scene: &Scene, faces: &[Face], decals: &[Vec<usize>]) -> Vec<(usize, Rect)> {
    elements(scene, faces, decals, f64::MAX, 1, usize::MAX)
        .unwrap_or_default()
        .into_iter()
        .map(|e| (e.face, e.rect))
        .collect()
}

/// A cell of the quadrature: its face, the rule's value on it and on its four quarters (with
/// their rectangles), per light component.
struct Cell {
    face: usize,
    coarse: Vec<f64>,
    quarters: [(Rect, Vec<f64>); 4],
    /// Σ_c ρ_max·|Σ quarters − coarse|.
    err: f64,
}

impl PartialEq for Cell {
    fn eq(&self, other: &Self) -> bool {
        self.err.total_cmp(&other.err) == Ordering::Equal
    }
}
impl Eq for Cell {}
impl PartialOrd for Cell {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Cell {
    fn cmp(&self, other: &Self) -> Ordering {
        self.err.total_cmp(&other.err)
    }
}

fn quarters(r: &Rect) -> [Rect; 4] {
    let (du, dv) = (r.edge_u.times(0.5), r.edge_v.times(0.5));
    [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)]
        .map(|(a, b)| Rect::new(r.corner.plus(du.times(a)).plus(dv.times(b)), du, dv))
}

/// The first bounce at `x` facing `n`: every piece's integral, refined where the rule and
/// its quarters disagree most, until their disagreement is within [`REL_TOLERANCE`] of the
/// whole or [`MAX_REFINEMENTS`] cells were refined.
pub fn first_bounce(
    scene: &Scene,
    lights: &Lights,
    faces: &[Face],
    pieces: &[(usize, Rect)],
    x: Vec3,
    n: Vec3,
) -> FirstBounce {
    let nc = lights.len();
    let rho_max: Vec<f64> = faces
        .iter()
        .map(|f| f.reflectance.iter().fold(0.0f64, |a, r| a.max(r.abs())))
        .collect();
    let rule = gauss_legendre(NODES);
    // ∫ over a rectangle of (g_c/π)·K per component, by the tensor rule.
    let integrate = |r: &Rect| -> Vec<f64> {
        let mut s = vec![0.0; nc];
        for &(a, wa) in &rule {
            for &(b, wb) in &rule {
                let y = r.point(a, b);
                let d = y.minus(x);
                let r2 = d.dot(d);
                let cos_x = d.dot(n);
                let cos_y = -d.dot(r.normal);
                if cos_x <= 0.0 || cos_y <= 0.0 || r2 <= 0.0 {
                    continue;
                }
                let k = cos_x * cos_y / (std::f64::consts::PI * r2 * r2);
                for (c, comp) in lights.comps.iter().enumerate() {
                    let g = irradiance_factor(
                        &scene.emitters[comp.emitter],
                        &comp.weights,
                        y,
                        r.normal,
                    );
                    s[c] += wa * wb * k * g / std::f64::consts::PI;
                }
            }
        }
        s.iter_mut().for_each(|v| *v *= r.area_m2);
        s
    };
    let cell = |face: usize, rect: Rect, coarse: Vec<f64>| -> Cell {
        let q = quarters(&rect).map(|r| {
            let v = integrate(&r);
            (r, v)
        });
        let err = (0..nc)
            .map(|c| {
                let fine: f64 = q.iter().map(|(_, v)| v[c]).sum();
                rho_max[face] * (fine - coarse[c]).abs()
            })
            .sum();
        Cell {
            face,
            coarse,
            quarters: q,
            err,
        }
    };
    let mut heap = BinaryHeap::new();
    for &(face, rect) in pieces {
        // A point on or behind a piece's plane sees none of it.
        if x.minus(rect.corner).dot(rect.normal) <= 0.0 {
            continue;
        }
        let coarse = integrate(&rect);
        heap.push(cell(face, rect, coarse));
    }
    let (mut total, mut err) = magnitude(&heap, &rho_max);
    let mut refined = 0;
    while refined < MAX_REFINEMENTS && err > REL_TOLERANCE * total {
        let Some(worst) = heap.pop() else { break };
        refined += 1;
        let Cell {
            face,
            quarters: q,
            err: e,
            ..
        } = worst;
        err -= e;
        total -= rho_max[face] * q.iter().flat_map(|(_, v)| v).map(|v| v.abs()).sum::<f64>();
        for (r, v) in q {
            let c = cell(face, r, v);
            err += c.err;
            total += rho_max[face]
                * c.quarters
                    .iter()
                    .flat_map(|(_, v)| v)
                    .map(|v| v.abs())
                    .sum::<f64>();
            heap.push(c);
        }
        // Refresh the running sums now and then against their drift.
        if refined % 512 == 0 {
            (total, err) = magnitude(&heap, &rho_max);
        }
    }
    sums(heap, nc, &rho_max)
}

/// The whole (Σ ρ_max·|value|) and the error estimate of a set of cells.
fn magnitude(heap: &BinaryHeap<Cell>, rho_max: &[f64]) -> (f64, f64) {
    heap.iter().fold((0.0, 0.0), |(m, e), c| {
        let fine: f64 = c
            .quarters
            .iter()
            .flat_map(|(_, v)| v)
            .map(|v| v.abs())
            .sum();
        (m + rho_max[c.face] * fine, e + c.err)
    })
}

/// Every cell's integral and error estimate, summed per component and face.
fn sums(heap: BinaryHeap<Cell>, nc: usize, rho_max: &[f64]) -> FirstBounce {
    let mut per_face = vec![vec![0.0; rho_max.len()]; nc];
    let mut error = vec![0.0; nc];
    for c in heap {
        for (k, pf) in per_face.iter_mut().enumerate() {
            let fine: f64 = c.quarters.iter().map(|(_, v)| v[k]).sum();
            pf[c.face] += fine;
            error[k] += rho_max[c.face] * (fine - c.coarse[k]).abs();
        }
    }
    FirstBounce { per_face, error }
}
