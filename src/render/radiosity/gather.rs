//! The meter: the mean radiance over the 1° cone, gathered where the cone meets the scene.
//!
//! The spot mode averages radiance uniformly in solid angle over the cone around the aim
//! axis; with u = (1 − cos θ)/(1 − cos α) and the azimuth φ, that measure is uniform on
//! [0, 1]², and the φ-average of a smooth function on the footprint is smooth in u. So a
//! Gauss–Legendre rule in u times the trapezoid rule in φ (exact for the periodic part)
//! integrates it to high order. At every node the ray's hit point gets the direct term in
//! closed form and the indirect term from the radiosity solution by exact point-to-element
//! factors.

use super::super::geometry::{Vec3, VecOps};
use super::super::spectral::N_BINS;
use super::super::spot::{cone_direction, Aim};
use super::direct::irradiance_factor;
use super::lights::Lights;
use super::mesh::{Face, FaceKind, Mesh};
use super::polygon::{gauss_legendre, point_to_rect};
use super::solve::Bands;
use crate::color::{Xyz, K_M};
use crate::render::scene::Scene;

/// Nodes of the cone cubature: (radial Gauss nodes, azimuth steps).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ConeRule {
    pub radial: usize,
    pub azimuthal: usize,
}

/// Directions and weights (summing to 1) of a rule.
pub fn cone_nodes(aim: &Aim, rule: ConeRule) -> Vec<(Vec3, f64)> {
    let cos_max = (aim.acceptance_deg.to_radians() / 2.0).cos();
    let mut out = Vec::new();
    for (u, wu) in gauss_legendre(rule.radial) {
        for k in 0..rule.azimuthal {
            // Offset the azimuths by half a step per ring so rings do not line up.
            let v = (k as f64 + 0.5 * u) / rule.azimuthal as f64;
            out.push((
                cone_direction(aim.axis, cos_max, u, v),
                wu / rule.azimuthal as f64,
            ));
        }
    }
    out
}

/// What one face contributes to a reading, as weighted sums over the cone.
#[derive(Clone, Debug)]
pub struct FaceShare {
    pub face: usize,
    /// Σ w·g_c(x)/π per light component.
    pub direct: Vec<f64>,
    /// Σ w·F(x → element j) for every element.
    pub indirect: Vec<f64>,
}

/// The cone's footprint: per face hit, the weighted direct and indirect factors, and the
/// radiance of any emitter seen directly (per unit of each component's spectrum).
#[derive(Clone, Debug)]
pub struct Footprint {
    pub shares: Vec<FaceShare>,
    pub emission: Vec<f64>,
}

/// Nearest front-facing face along a ray, or None (a back side is black).
pub(super) fn hit(faces: &[Face], o: Vec3, d: Vec3) -> Option<(usize, Vec3, f64, f64)> {
    let mut best: Option<(usize, f64, f64, f64, bool)> = None;
    for (i, f) in faces.iter().enumerate() {
        let t_max = best.map_or(f64::INFINITY, |b| b.1);
        if let Some(h) = f.rect.intersect(o, d, 1e-9, t_max) {
            best = Some((i, h.t, h.a, h.b, h.front));
        }
    }
    match best {
        Some((i, t, a, b, true)) => Some((i, o.plus(d.times(t)), a, b)),
        _ => None,
    }
}

/// The footprint of `aim`: the direct term with `direct_rule`, the indirect with
/// `indirect_rule` (the indirect field varies slowly over a 1° spot and is the costly part).
pub fn footprint(
    scene: &Scene,
    lights: &Lights,
    faces: &[Face],
    mesh: &Mesh,
    aim: &Aim,
    direct_rule: ConeRule,
    indirect_rule: ConeRule,
) -> Footprint {
    let ne = lights.len();
    let mut shares: Vec<FaceShare> = Vec::new();
    let mut emission = vec![0.0; ne];
    let share = |face: usize, shares: &mut Vec<FaceShare>| -> usize {
        match shares.iter().position(|s| s.face == face) {
            Some(k) => k,
            None => {
                shares.push(FaceShare {
                    face,
                    direct: vec![0.0; ne],
                    indirect: vec![0.0; mesh.elements.len()],
                });
                shares.len() - 1
            }
        }
    };
    for (d, w) in cone_nodes(aim, direct_rule) {
        let Some((fi, x, a, b)) = hit(faces, aim.origin, d) else {
            continue;
        };
        let n = faces[fi].rect.normal;
        if let FaceKind::Emitter(e) = faces[fi].kind {
            let em = &scene.emitters[e];
            let tile = em.tile_at(a, b);
            emission[lights.of_tile(scene, e, tile)] +=
                w * em.gains[tile] * em.directional(d.times(-1.0));
        }
        let k = share(fi, &mut shares);
        for (c, comp) in lights.comps.iter().enumerate() {
            let em = &scene.emitters[comp.emitter];
            shares[k].direct[c] +=
                w * irradiance_factor(em, &comp.weights, x, n) / std::f64::consts::PI;
        }
    }
    for (d, w) in cone_nodes(aim, indirect_rule) {
        let Some((fi, x, _, _)) = hit(faces, aim.origin, d) else {
            continue;
        };
        let n = faces[fi].rect.normal;
        let k = share(fi, &mut shares);
        for (j, el) in mesh.elements.iter().enumerate() {
            if el.face != fi {
                shares[k].indirect[j] += w * point_to_rect(x, n, &el.rect);
            }
        }
    }
    Footprint { shares, emission }
}

/// Absolute XYZ (cd/m²) of a footprint given the solution `l[c]` (N × bands per component)
/// and each face's reflectance at 1 nm.
pub fn reading(
    scene: &Scene,
    lights: &Lights,
    fp: &Footprint,
    face_refl: &[&[f64]],
    bands: &Bands,
    l: &[Vec<f64>],
) -> Xyz {
    let nb = bands.len();
    let mut radiance = vec![0.0; N_BINS];
    for (e, comp) in lights.comps.iter().enumerate() {
        for (r, s) in radiance.iter_mut().zip(comp.spectrum) {
            *r += fp.emission[e] * s;
        }
        for sh in &fp.shares {
            let mut q = vec![0.0; nb];
            for (j, f) in sh.indirect.iter().enumerate() {
                if *f != 0.0 {
                    for (qb, lb) in q.iter_mut().zip(&l[e][j * nb..(j + 1) * nb]) {
                        *qb += f * lb;
                    }
                }
            }
            let q = bands.interpolate(&q);
            let rho = face_refl[sh.face];
            for i in 0..N_BINS {
                radiance[i] += rho[i] * comp.spectrum[i] * (sh.direct[e] + q[i]);
            }
        }
    }
    let mut xyz = Xyz::default();
    for (k, c) in scene.cmf.iter().enumerate() {
        xyz[k] = K_M * radiance.iter().zip(c).map(|(r, c)| r * c).sum::<f64>();
    }
    xyz
}
