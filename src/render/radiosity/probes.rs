//! Illuminance at points (lux): the direct term in closed form, the indirect from the
//! radiosity solution, refined and extrapolated like the meter readings; and per element,
//! for checks of the whole field (flux balance).

use super::super::geometry::Vec3;
use super::bound::richardson;
use super::direct::irradiance_factor;
use super::lights::Lights;
use super::polygon::point_to_rect;
use super::{solve_level, Prepared, RadiosityError, RadiosityOptions, Solved};
use crate::color::K_M;
use crate::render::deadline::Deadline;
use crate::render::scene::Scene;

/// A probe: a point and the unit normal of the surface it measures on.
#[derive(Clone, Copy, Debug)]
pub struct Probe {
    pub position: Vec3,
    pub normal: Vec3,
}

/// Illuminance at a probe (lux).
#[derive(Clone, Copy, Debug, serde::Serialize)]
pub struct Illuminance {
    pub direct_lux: f64,
    pub indirect_lux: f64,
    pub total_lux: f64,
    /// Error bound of the indirect part (radiosity: the extrapolations' disagreement;
    /// path tracing: the 95 % half-width of the total).
    pub bound_lux: f64,
}

/// K_m Σ_λ S(λ)·ȳ(λ)·w(λ) for one light component: lux from a per-wavelength factor.
fn photometric(scene: &Scene, lights: &Lights, c: usize, w: impl Fn(usize) -> f64) -> f64 {
    K_M * lights.comps[c]
        .spectrum
        .iter()
        .zip(&scene.cmf[1])
        .enumerate()
        .map(|(i, (s, y))| s * y * w(i))
        .sum::<f64>()
}

/// Direct illuminance at `x` facing `n` (lux), exact.
pub fn direct_lux(scene: &Scene, lights: &Lights, x: Vec3, n: Vec3) -> f64 {
    (0..lights.len())
        .map(|c| {
            let comp = &lights.comps[c];
            let g = irradiance_factor(&scene.emitters[comp.emitter], &comp.weights, x, n);
            photometric(scene, lights, c, |_| g)
        })
        .sum()
}

/// Indirect illuminance at `x` facing `n` (lux) from a solved level.
pub fn indirect_lux(scene: &Scene, lights: &Lights, solved: &Solved, x: Vec3, n: Vec3) -> f64 {
    let nb = solved.bands.len();
    let f: Vec<f64> = solved
        .mesh
        .elements
        .iter()
        .map(|el| point_to_rect(x, n, &el.rect))
        .collect();
    (0..lights.len())
        .map(|e| {
            let mut q = vec![0.0; nb];
            for (j, fj) in f.iter().enumerate() {
                if *fj != 0.0 {
                    for (qb, lb) in q.iter_mut().zip(&solved.l[e][j * nb..(j + 1) * nb]) {
                        *qb += fj * lb;
                    }
                }
            }
            let q = solved.bands.interpolate(&q);
            photometric(scene, lights, e, |i| std::f64::consts::PI * q[i])
        })
        .sum()
}

/// Per element of a solved level: (area m², mean direct lux, mean indirect lux), the
/// direct averaged as the solver's source term is, the indirect from the same system.
pub fn element_lux(scene: &Scene, solved: &Solved) -> Vec<(f64, f64, f64)> {
    let n = solved.mesh.elements.len();
    let nb = solved.bands.len();
    let lights = Lights::new(scene);
    let src =
        super::solve::sources(scene, &lights, &solved.mesh, Deadline::never()).unwrap_or_default();
    (0..n)
        .map(|i| {
            let mut direct = 0.0;
            let mut indirect = 0.0;
            for (e, src_e) in src.iter().enumerate() {
                let mut q = vec![0.0; nb];
                for j in 0..n {
                    let f = solved.mesh.form[i * n + j];
                    if f != 0.0 {
                        for (qb, lb) in q.iter_mut().zip(&solved.l[e][j * nb..(j + 1) * nb]) {
                            *qb += f * lb;
                        }
                    }
                }
                let q = solved.bands.interpolate(&q);
                direct += photometric(scene, &lights, e, |_| std::f64::consts::PI * src_e[i]);
                indirect += photometric(scene, &lights, e, |k| std::f64::consts::PI * q[k]);
            }
            (solved.mesh.elements[i].rect.area_m2, direct, indirect)
        })
        .collect()
}

/// Illuminance at every probe: levels 1, 2, 3 (then finer while any bound exceeds
/// `rel_tolerance` of its total, up to `opts.max_level`), the indirect part extrapolated.
pub fn probe_illuminance(
    scene: &Scene,
    probes: &[Probe],
    opts: &RadiosityOptions,
    rel_tolerance: f64,
) -> Result<Vec<Illuminance>, RadiosityError> {
    let p = Prepared::for_probes(scene)?;
    let deadline = Deadline::after(opts.max_seconds);
    let refl: Vec<&[f64]> = p.faces.iter().map(|f| f.reflectance.as_slice()).collect();
    let direct: Vec<f64> = probes
        .iter()
        .map(|q| direct_lux(scene, &p.lights, q.position, q.normal))
        .collect();
    let mut levels: Vec<Vec<f64>> = Vec::new();
    let base = p.base(opts);
    loop {
        let level = levels.len() + 1;
        let solved = solve_level(&p, &refl, opts, level, None, deadline)?;
        levels.push(
            probes
                .iter()
                .map(|q| indirect_lux(scene, &p.lights, &solved, q.position, q.normal))
                .collect(),
        );
        if levels.len() < 3 {
            continue;
        }
        let m = levels.len();
        let h = |k: usize| base / k as f64;
        let out: Vec<Illuminance> = (0..probes.len())
            .map(|i| {
                let fine = richardson(
                    levels[m - 2][i],
                    h(m - 1),
                    levels[m - 1][i],
                    h(m),
                    opts.order,
                );
                let coarse = richardson(
                    levels[m - 3][i],
                    h(m - 2),
                    levels[m - 2][i],
                    h(m - 1),
                    opts.order,
                );
                Illuminance {
                    direct_lux: direct[i],
                    indirect_lux: fine,
                    total_lux: direct[i] + fine,
                    bound_lux: (fine - coarse).abs(),
                }
            })
            .collect();
        let done = out
            .iter()
            .all(|r| r.bound_lux <= rel_tolerance * r.total_lux.abs());
        if done || level >= opts.max_level.max(3) {
            return Ok(out);
        }
    }
}
