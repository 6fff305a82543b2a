//! Illuminance at probe points, by either method: `render probes` in one call.
//!
//! The radiosity solver (convex rooms of Lambertian rectangles) refines its mesh until every
//! bound is within the tolerance; the path tracer traces cosine-weighted directions from each
//! point, E_v = π·mean(luminance), the direct part being the same directions stopped at their
//! first hit. Both hold a wall-clock limit inside their loops and report what they finished,
//! marked not converged, rather than nothing.

use rayon::prelude::*;

use super::deadline::Deadline;
use super::geometry::VecOps;
use super::integrator::{Strategy, Tracer};
use super::method::Method;
use super::radiosity::probes::{
    probe_illuminance, Illuminance, Probe, ProbeLevel, ProbeProgress, ProbeRun,
};
use super::radiosity::{RadiosityError, RadiosityOptions};
use super::scene::Scene;
use super::spectral::Rng;

/// What a probe run is asked for.
#[derive(Clone, Copy, Debug)]
pub struct ProbeOptions {
    pub method: Method,
    /// Radiosity: refine until every bound is within this fraction of its total.
    pub rel_tolerance: f64,
    /// Path tracing: paths per probe (the run may end sooner at the time limit).
    pub samples: u64,
    pub seed: u64,
    /// Wall-clock limit (s); what finished by then is reported, marked not converged.
    pub max_seconds: f64,
}

impl Default for ProbeOptions {
    fn default() -> Self {
        ProbeOptions {
            method: Method::Auto,
            rel_tolerance: 1e-3,
            samples: 65_536,
            seed: 1,
            max_seconds: 600.0,
        }
    }
}

/// Why probes could not be computed.
#[derive(Debug, thiserror::Error)]
pub enum ProbeError {
    #[error("{what} must be {need}, got {got}")]
    BadOption {
        what: &'static str,
        need: &'static str,
        got: f64,
    },
    #[error(transparent)]
    Radiosity(#[from] RadiosityError),
    #[error(
        "no result within the time limit of {seconds} s: the path tracer finished its first \
         {samples} paths for {done} of {of} probes (give more time, or fewer points)"
    )]
    TimeLimit {
        seconds: f64,
        samples: u64,
        done: usize,
        of: usize,
    },
    #[error("probe {probe}: the illuminance is not a finite number")]
    NonFinite { probe: usize },
}

/// The illuminance at every probe and how it was reached.
#[derive(Clone, Debug, serde::Serialize)]
pub struct ProbeResult {
    /// "radiosity" or "path".
    pub method: &'static str,
    /// Why `auto` fell back to the path tracer.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub method_reason: Option<String>,
    pub seconds: f64,
    pub probes: Vec<Illuminance>,
    /// Radiosity: every bound within the tolerance; path: every probe got its paths.
    pub converged: bool,
    /// Why the work ended before that.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub stopped: Option<String>,
    /// Radiosity: the mesh levels solved.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub levels: Vec<ProbeLevel>,
    /// Path tracing: the fewest paths any probe got.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub samples: Option<u64>,
}

/// Illuminance at every probe by the method `opts` asks for (`auto` resolved here, its
/// reason kept in the result).
pub fn illuminance(
    scene: &Scene,
    probes: &[Probe],
    opts: &ProbeOptions,
    progress: &(dyn Fn(ProbeProgress) + Sync),
) -> Result<ProbeResult, ProbeError> {
    if !(opts.rel_tolerance > 0.0 && opts.rel_tolerance.is_finite()) {
        return Err(ProbeError::BadOption {
            what: "the relative tolerance",
            need: "> 0",
            got: opts.rel_tolerance,
        });
    }
    if opts.max_seconds.is_nan() || opts.max_seconds <= 0.0 {
        return Err(ProbeError::BadOption {
            what: "the time limit",
            need: "> 0 s",
            got: opts.max_seconds,
        });
    }
    if opts.samples < 2 {
        return Err(ProbeError::BadOption {
            what: "the number of paths per probe",
            need: "≥ 2",
            got: opts.samples as f64,
        });
    }
    let start = std::time::Instant::now();
    let resolved = opts.method.resolve(scene)?;
    let method_reason = resolved.fallback().map(str::to_string);
    let mut result = if resolved.is_radiosity() {
        let ropts = RadiosityOptions {
            max_seconds: opts.max_seconds,
            ..RadiosityOptions::default()
        };
        let ProbeRun {
            probes,
            levels,
            converged,
            stopped,
        } = probe_illuminance(scene, probes, &ropts, opts.rel_tolerance, progress)?;
        ProbeResult {
            method: "radiosity",
            method_reason,
            seconds: 0.0,
            probes,
            converged,
            stopped,
            levels,
            samples: None,
        }
    } else {
        let deadline = Deadline::after(opts.max_seconds);
        let (probes, samples, stopped) =
            path_probes(scene, probes, opts.samples, opts.seed, deadline, progress).map_err(
                |(samples, done, of)| ProbeError::TimeLimit {
                    seconds: opts.max_seconds,
                    samples,
                    done,
                    of,
                },
            )?;
        ProbeResult {
            method: "path",
            method_reason,
            seconds: 0.0,
            converged: stopped.is_none(),
            stopped,
            probes,
            levels: Vec::new(),
            samples: Some(samples),
        }
    };
    if let Some(i) = result.probes.iter().position(|e| {
        ![e.direct_lux, e.indirect_lux, e.total_lux, e.bound_lux]
            .iter()
            .all(|x| x.is_finite())
    }) {
        return Err(ProbeError::NonFinite { probe: i + 1 });
    }
    result.seconds = start.elapsed().as_secs_f64();
    Ok(result)
}

/// Paths per probe in the first round: enough for a first bound, few enough that a million
/// points get one quickly.
const FIRST_ROUND: u64 = 256;

/// Probes per parallel chunk, between which the deadline is checked.
const CHUNK: usize = 1024;

/// Paths per parallel task.
const BATCH: u64 = 1024;

/// Per-probe sums of (Y, Y², Y of the first hit only) and the paths they hold.
#[derive(Clone, Copy, Default)]
struct Sums {
    y: f64,
    y2: f64,
    direct: f64,
    n: u64,
}

/// Path-traced probes in rounds of doubling size over all probes, so that a time limit
/// leaves every probe with about the same paths; Err((paths, probes done, of)) when even the
/// first round did not finish. Each path's random numbers depend only on the seed, the
/// probe and the path's index, so the result does not depend on how the rounds fall.
/// The path-traced probes, the paths per probe, and why the rounds stopped early (if they did).
type PathProbes = (Vec<Illuminance>, u64, Option<String>);

fn path_probes(
    scene: &Scene,
    probes: &[Probe],
    samples: u64,
    seed: u64,
    deadline: Deadline,
    progress: &(dyn Fn(ProbeProgress) + Sync),
) -> Result<PathProbes, (u64, usize, usize)> {
    let total = Tracer::new(scene, Strategy::default());
    let mut first = Tracer::new(scene, Strategy::default());
    first.max_depth = Some(0);
    let mut sums = vec![Sums::default(); probes.len()];
    let mut round = FIRST_ROUND.min(samples);
    let mut stopped = None;
    'rounds: while sums.iter().any(|s| s.n < samples) {
        for (c, chunk) in sums.chunks_mut(CHUNK).enumerate() {
            if deadline.passed() {
                let done = sums.iter().filter(|s| s.n > 0).count();
                if sums.iter().any(|s| s.n == 0) {
                    return Err((FIRST_ROUND.min(samples), done, probes.len()));
                }
                stopped = Some(format!(
                    "the time limit ran out after {} of {samples} paths per probe",
                    sums.iter().map(|s| s.n).min().unwrap_or(0)
                ));
                break 'rounds;
            }
            // Tasks of at most BATCH paths, so that a few probes still use every core;
            // their sums are added in order, so the result does not depend on the threads.
            let tasks: Vec<(usize, u64, u64)> = chunk
                .iter()
                .enumerate()
                .flat_map(|(j, s)| {
                    let end = s.n + round.min(samples - s.n);
                    (s.n..end)
                        .step_by(BATCH as usize)
                        .map(move |i0| (j, i0, (i0 + BATCH).min(end)))
                })
                .collect();
            let parts: Vec<(usize, Sums)> = tasks
                .par_iter()
                .map(|&(j, i0, i1)| {
                    let k = c * CHUNK + j;
                    (j, trace(&total, &first, &probes[k], k, seed, i0..i1))
                })
                .collect();
            for (j, part) in parts {
                let s = &mut chunk[j];
                s.y += part.y;
                s.y2 += part.y2;
                s.direct += part.direct;
                s.n += part.n;
            }
            progress(ProbeProgress::Evaluated {
                done: (c * CHUNK + chunk.len()).min(probes.len()),
                of: probes.len(),
            });
        }
        round = round.saturating_mul(2).min(1 << 16);
    }
    let pi = std::f64::consts::PI;
    let out = sums
        .iter()
        .map(|s| {
            let m = s.n.max(1) as f64;
            let mean = s.y / m;
            let var = (s.y2 / m - mean * mean).max(0.0) / (m - 1.0).max(1.0);
            let direct = pi * s.direct / m;
            Illuminance {
                direct_lux: direct,
                indirect_lux: pi * mean - direct,
                total_lux: pi * mean,
                bound_lux: 1.96 * pi * var.sqrt(),
            }
        })
        .collect();
    let fewest = sums.iter().map(|s| s.n).min().unwrap_or(0);
    Ok((out, fewest, stopped))
}

/// Paths `range` of probe `k`: cosine-weighted directions about its normal.
fn trace(
    total: &Tracer,
    first: &Tracer,
    p: &Probe,
    k: usize,
    seed: u64,
    range: std::ops::Range<u64>,
) -> Sums {
    let n = p.normal.normalized();
    let (u, v) = n.basis();
    let mut s = Sums::default();
    for i in range {
        let mut rng = Rng::new(seed, 5000 + k as u64, i);
        let r = rng.next_f64().sqrt();
        let phi = 2.0 * std::f64::consts::PI * rng.next_f64();
        let z = (1.0 - r * r).max(0.0).sqrt();
        let d = u
            .times(r * phi.cos())
            .plus(v.times(r * phi.sin()))
            .plus(n.times(z))
            .normalized();
        let mut r2 = rng.clone();
        let y_all = total.xyz_sample(p.position, d, &mut rng)[1];
        let y_dir = first.xyz_sample(p.position, d, &mut r2)[1];
        s.y += y_all;
        s.y2 += y_all * y_all;
        s.direct += y_dir;
        s.n += 1;
    }
    s
}

/// Illuminance at every probe from `samples` paths each (95 % half-width as the bound), with
/// no time limit.
pub fn probe_illuminance_path(
    scene: &Scene,
    probes: &[Probe],
    samples: u64,
    seed: u64,
) -> Vec<Illuminance> {
    path_probes(
        scene,
        probes,
        samples.max(2),
        seed,
        Deadline::never(),
        &|_| {},
    )
    .map(|(out, _, _)| out)
    .unwrap_or_default()
}
