//! Illuminance at points (lux): the direct term in closed form, the indirect from the
//! radiosity solution, refined and extrapolated like the meter readings; and per element,
//! for checks of the whole field (flux balance).

use super::super::geometry::Vec3;
use super::bound::{extrapolated_with_bound, MIN_ORDER};
use super::direct::irradiance_factor;
use super::first_bounce::{first_bounce, pieces, FirstBounce};
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

/// Each element's point-to-rectangle factor seen from `x` facing `n`: the weights of a
/// gather from a solved level.
fn element_factors(solved: &Solved, x: Vec3, n: Vec3) -> Vec<f64> {
    solved
        .mesh
        .elements
        .iter()
        .map(|el| point_to_rect(x, n, &el.rect))
        .collect()
}

/// Indirect illuminance at `x` facing `n` (lux) from a solved level.
pub fn indirect_lux(scene: &Scene, lights: &Lights, solved: &Solved, x: Vec3, n: Vec3) -> f64 {
    let nb = solved.bands.len();
    let f = element_factors(solved, x, n);
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

/// Indirect illuminance at `x` facing `n` (lux) from a solved level whose reflectances
/// per face (1 nm) are `refl`, with the first bounce at that point integrated apart
/// ([`first_bounce`]): the mesh gathers only ℓ − ρ·g/π, the light that has bounced at least
/// twice.
pub fn indirect_lux_with(
    scene: &Scene,
    lights: &Lights,
    solved: &Solved,
    refl: &[&[f64]],
    first: &FirstBounce,
    x: Vec3,
    n: Vec3,
) -> f64 {
    let nb = solved.bands.len();
    let f = element_factors(solved, x, n);
    (0..lights.len())
        .map(|e| {
            let mut q = vec![0.0; nb];
            for (j, fj) in f.iter().enumerate() {
                if *fj == 0.0 {
                    continue;
                }
                let rho = refl[solved.mesh.elements[j].face];
                let s = solved.src[e][j];
                for (b, (qb, lb)) in q
                    .iter_mut()
                    .zip(&solved.l[e][j * nb..(j + 1) * nb])
                    .enumerate()
                {
                    *qb += fj * (lb - rho[solved.bands.bins[b]] * s);
                }
            }
            for (face, v) in first.per_face[e].iter().enumerate() {
                if *v != 0.0 {
                    for (qb, &bin) in q.iter_mut().zip(&solved.bands.bins) {
                        *qb += refl[face][bin] * v;
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

/// One refinement level of a probe run.
#[derive(Clone, Debug, serde::Serialize)]
pub struct ProbeLevel {
    pub level: usize,
    /// Element size (m).
    pub h_m: f64,
    pub elements: usize,
    pub seconds: f64,
    /// The largest bound over the probes after this level, relative to its total (from
    /// level 3 on).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub worst_relative_bound: Option<f64>,
}

/// Illuminance at every probe, with the levels it came from and whether every bound met
/// the tolerance.
#[derive(Clone, Debug, serde::Serialize)]
pub struct ProbeRun {
    pub probes: Vec<Illuminance>,
    pub levels: Vec<ProbeLevel>,
    /// Every probe's bound is within the tolerance of its total.
    pub converged: bool,
    /// Why refinement ended without convergence: the finest level, the element limit or the
    /// time limit; the result is then the last level that finished.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stopped: Option<String>,
}

/// What a probe run reports while it works.
#[derive(Clone, Copy, Debug)]
pub enum ProbeProgress<'a> {
    /// A level was meshed and solved; its probes are being evaluated.
    Solved { level: usize, elements: usize },
    /// Probes evaluated so far on the current level (or, path tracing, samples so far).
    Evaluated { done: usize, of: usize },
    /// The estimates after a level (from the third on), as they would be reported if the
    /// refinement stopped there.
    Estimated {
        level: usize,
        probes: &'a [Illuminance],
    },
}

/// Probes are evaluated in chunks of this many, between which the deadline is checked.
const CHUNK: usize = 4096;

/// The point-independent parts of a probe run: the scene, each probe's direct light, first
/// bounce and its error in lux.
struct Fixed<'p, 'a> {
    p: &'p Prepared<'a>,
    refl: Vec<&'a [f64]>,
    direct: Vec<f64>,
    first: Vec<FirstBounce>,
    /// What the first bounce's quadrature may be off by at each probe (lux).
    first_err: Vec<f64>,
}

/// Indirect lux at every probe from one solved level, or None when the deadline passed.
fn evaluate(
    fixed: &Fixed,
    solved: &Solved,
    probes: &[Probe],
    deadline: Deadline,
    progress: &(dyn Fn(ProbeProgress) + Sync),
) -> Option<Vec<f64>> {
    use rayon::prelude::*;
    let (scene, lights) = (fixed.p.scene, &fixed.p.lights);
    let mut out = Vec::with_capacity(probes.len());
    for (k, chunk) in probes.chunks(CHUNK).enumerate() {
        if deadline.passed() {
            return None;
        }
        out.par_extend(chunk.par_iter().enumerate().map(|(i, q)| {
            let first = &fixed.first[k * CHUNK + i];
            indirect_lux_with(
                scene,
                lights,
                solved,
                &fixed.refl,
                first,
                q.position,
                q.normal,
            )
        }));
        progress(ProbeProgress::Evaluated {
            done: out.len(),
            of: probes.len(),
        });
    }
    Some(out)
}

/// The direct light and the first bounce at every probe, or the time limit's error.
fn fixed_parts<'p, 'a>(
    p: &'p Prepared<'a>,
    probes: &[Probe],
    opts: &RadiosityOptions,
    deadline: Deadline,
) -> Result<Fixed<'p, 'a>, RadiosityError> {
    use rayon::prelude::*;
    let scene = p.scene;
    let pieces = pieces(scene, &p.faces, &p.decals);
    let mut direct = Vec::with_capacity(probes.len());
    let mut first = Vec::with_capacity(probes.len());
    for chunk in probes.chunks(CHUNK) {
        if deadline.passed() {
            return Err(RadiosityError::TimeLimit {
                seconds: opts.max_seconds,
                during: "while computing the direct light and its first bounce".into(),
            });
        }
        direct.extend(
            chunk
                .iter()
                .map(|q| direct_lux(scene, &p.lights, q.position, q.normal)),
        );
        first.par_extend(
            chunk
                .par_iter()
                .map(|q| first_bounce(scene, &p.lights, &p.faces, &pieces, q.position, q.normal)),
        );
    }
    let first_err = first
        .iter()
        .map(|f| {
            (0..p.lights.len())
                .map(|c| photometric(scene, &p.lights, c, |_| std::f64::consts::PI * f.error[c]))
                .sum()
        })
        .collect();
    Ok(Fixed {
        p,
        refl: p.faces.iter().map(|f| f.reflectance.as_slice()).collect(),
        direct,
        first,
        first_err,
    })
}

/// The estimates after the last level: each probe extrapolated from the last levels (up to
/// four), whether all converged, and how many are within the tolerance but converge more
/// slowly than trusted.
fn estimates(
    fixed: &Fixed,
    raw: &[Vec<f64>],
    levels_alg: &[f64],
    hs_all: &[f64],
    opts: &RadiosityOptions,
    rel_tolerance: f64,
) -> (Vec<Illuminance>, bool, usize) {
    let m = raw.len();
    let first = m.saturating_sub(4);
    let hs = &hs_all[first..m];
    // What the stopped iteration may leave, in lux, at the finest level.
    let algebraic = levels_alg.iter().skip(first).fold(0.0f64, |a, &b| a.max(b));
    // Probes whose estimate is not converged although within the tolerance: their last
    // levels converge more slowly than the slowest order trusted.
    let mut slow = 0;
    let mut done = true;
    let out = (0..fixed.direct.len())
        .map(|i| {
            let direct = fixed.direct[i];
            let v: Vec<f64> = raw[first..].iter().map(|r| r[i]).collect();
            let abs_err = algebraic * (v[v.len() - 1].abs() + direct.abs());
            let e = extrapolated_with_bound(&v, hs, opts.order, abs_err);
            let total = direct + e.value;
            let tol = rel_tolerance * total.abs();
            let bound = e.bound + fixed.first_err[i];
            if !(e.converged(tol) && bound <= tol) {
                done = false;
                slow += usize::from(bound <= tol);
            }
            Illuminance {
                direct_lux: direct,
                indirect_lux: e.value,
                total_lux: total,
                bound_lux: bound,
            }
        })
        .collect();
    (out, done, slow)
}

/// Illuminance at every probe: levels 1, 2, 3 (then finer while any bound exceeds
/// `rel_tolerance` of its total, up to `opts.max_level`), the indirect part extrapolated.
/// A finer level that runs out of time or elements ends the refinement with the last
/// finished result, marked not converged; the first three levels are needed for any.
pub fn probe_illuminance(
    scene: &Scene,
    probes: &[Probe],
    opts: &RadiosityOptions,
    rel_tolerance: f64,
    progress: &(dyn Fn(ProbeProgress) + Sync),
) -> Result<ProbeRun, RadiosityError> {
    let p = Prepared::for_probes(scene)?;
    let deadline = Deadline::after(opts.max_seconds);
    let fixed = fixed_parts(&p, probes, opts, deadline)?;
    let mut raw: Vec<Vec<f64>> = Vec::new();
    let mut levels_alg: Vec<f64> = Vec::new();
    let mut levels: Vec<ProbeLevel> = Vec::new();
    let mut best: Option<Vec<Illuminance>> = None;
    let base = p.base(opts);
    let finest = opts.max_level.max(3);
    let hs: Vec<f64> = (1..=finest).map(|k| base / k as f64).collect();
    loop {
        let level = raw.len() + 1;
        let start = std::time::Instant::now();
        let stop = |why: String, best: Option<Vec<Illuminance>>, levels: Vec<ProbeLevel>| match best
        {
            Some(probes) => Ok(ProbeRun {
                probes,
                levels,
                converged: false,
                stopped: Some(why),
            }),
            None => Err(RadiosityError::TimeLimit {
                seconds: opts.max_seconds,
                during: format!("on mesh level {level}"),
            }),
        };
        let solved = match solve_level(&p, &fixed.refl, opts, level, None, deadline) {
            Ok(s) => s,
            Err(RadiosityError::TimeLimit { .. }) => {
                let why = format!(
                    "the time limit of {} s ran out while solving level {level}",
                    opts.max_seconds
                );
                return stop(why, best, levels);
            }
            Err(RadiosityError::TooDetailed { max, .. }) if best.is_some() => {
                let why = format!("level {level} would need more than {max} elements");
                return stop(why, best, levels);
            }
            Err(e) => return Err(e),
        };
        progress(ProbeProgress::Solved {
            level,
            elements: solved.mesh.elements.len(),
        });
        let Some(values) = evaluate(&fixed, &solved, probes, deadline, progress) else {
            let why = format!(
                "the time limit of {} s ran out while evaluating the probes on level {level}",
                opts.max_seconds
            );
            return stop(why, best, levels);
        };
        raw.push(values);
        levels_alg.push(solved.algebraic);
        levels.push(ProbeLevel {
            level,
            h_m: hs[level - 1],
            elements: solved.mesh.elements.len(),
            seconds: start.elapsed().as_secs_f64(),
            worst_relative_bound: None,
        });
        if raw.len() < 3 {
            continue;
        }
        let (out, done, slow) = estimates(&fixed, &raw, &levels_alg, &hs, opts, rel_tolerance);
        progress(ProbeProgress::Estimated {
            level,
            probes: &out,
        });
        let worst = out
            .iter()
            .map(|r| r.bound_lux / r.total_lux.abs())
            .fold(0.0, f64::max);
        if let Some(l) = levels.last_mut() {
            l.worst_relative_bound = Some(worst);
        }
        if done || level >= finest {
            return Ok(ProbeRun {
                probes: out,
                levels,
                converged: done,
                stopped: (!done).then(|| finest_reason(level, slow)),
            });
        }
        best = Some(out);
    }
}

/// Why a run that reached the finest level did not converge.
fn finest_reason(level: usize, slow: usize) -> String {
    if slow > 0 {
        format!(
            "level {level} is the finest the solver tries, and at {slow} probe(s) the last \
             levels still converge more slowly than order {MIN_ORDER} (a point nearer an \
             edge than the elements are small): their bound is a rough figure"
        )
    } else {
        format!("level {level} is the finest the solver tries")
    }
}
