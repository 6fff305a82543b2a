//! The simulated spot meter: the 1° colorimeter at the camera's optical centre, aimed at
//! each patch centre. A reading is the mean radiance over the acceptance cone, uniform in
//! solid angle, projected on x̄ȳz̄ and scaled by K_m (paper Eq. 8). Samples are drawn in
//! batches until the 95 % confidence half-width of every patch's ΔE*ab falls below the
//! target; the half-width is 1.96 times the RMS of ΔE*ab of the mean, propagated from the
//! covariance of the mean XYZ through the Jacobian of CIELAB (the reference white is
//! treated as exact). A reading of either renderer is a [`RenderedReading`] (`reading`).

pub mod cone;
pub mod reading;

use std::time::Instant;

use rayon::prelude::*;

use super::deadline::Deadline;
use super::geometry::{Vec3, VecOps};
use super::integrator::{Strategy, Tracer};
use super::scene::Scene;
use super::spectral::Rng;
use crate::color::Xyz;
pub use reading::{RenderedReading, Sampling, Uncertainty};

/// Running sums of XYZ samples.
#[derive(Clone, Copy, Debug, Default)]
pub struct XyzStats {
    pub n: u64,
    pub sum: [f64; 3],
    /// Σ xᵢxⱼ
    pub sum_sq: [[f64; 3]; 3],
}

impl XyzStats {
    pub fn push(&mut self, x: [f64; 3]) {
        self.n += 1;
        for i in 0..3 {
            self.sum[i] += x[i];
            for j in 0..3 {
                self.sum_sq[i][j] += x[i] * x[j];
            }
        }
    }
    pub fn merge(&mut self, o: &XyzStats) {
        self.n += o.n;
        for i in 0..3 {
            self.sum[i] += o.sum[i];
            for j in 0..3 {
                self.sum_sq[i][j] += o.sum_sq[i][j];
            }
        }
    }
    pub fn mean(&self) -> Xyz {
        let n = self.n.max(1) as f64;
        Xyz::new(self.sum[0] / n, self.sum[1] / n, self.sum[2] / n)
    }
    /// Covariance of the mean.
    pub fn cov_mean(&self) -> [[f64; 3]; 3] {
        let n = self.n as f64;
        let m = self.mean();
        let mut c = [[0.0; 3]; 3];
        if self.n < 2 {
            return [[f64::INFINITY; 3]; 3];
        }
        for i in 0..3 {
            for j in 0..3 {
                c[i][j] = (self.sum_sq[i][j] / n - m[i] * m[j]) * n / (n - 1.0) / n;
            }
        }
        c
    }
    pub fn stderr(&self) -> [f64; 3] {
        let c = self.cov_mean();
        [c[0][0].sqrt(), c[1][1].sqrt(), c[2][2].sqrt()]
    }
    /// 95 % half-width of ΔE*ab of the mean against `white`.
    pub fn de_ci95(&self, white: Xyz) -> f64 {
        de_ci95_of(self.mean(), self.cov_mean(), white)
    }
}

/// 95 % half-width of ΔE*ab of a mean XYZ `m` whose covariance is `c`, against `white`:
/// 1.96 times the RMS ΔE*ab propagated through CIELAB's Jacobian (by finite differences).
pub fn de_ci95_of(m: Xyz, c: [[f64; 3]; 3], white: Xyz) -> f64 {
    let lab = |x: Xyz| x.to_lab(white).to_array();
    let base = lab(m);
    let mut jac = [[0.0; 3]; 3]; // jac[lab][xyz]
    for k in 0..3 {
        let h = 1e-6 * (m[k].abs() + white[k] * 1e-3);
        let mut p = m;
        p[k] += h;
        let l = lab(p);
        for r in 0..3 {
            jac[r][k] = (l[r] - base[r]) / h;
        }
    }
    let mut var = 0.0;
    for row in jac {
        for i in 0..3 {
            for j in 0..3 {
                var += row[i] * c[i][j] * row[j];
            }
        }
    }
    1.96 * var.max(0.0).sqrt()
}

/// Direction of sample `u, v` uniform in solid angle inside a cone of half-angle whose
/// cosine is `cos_max` around `axis` (unit).
pub fn cone_direction(axis: Vec3, cos_max: f64, u: f64, v: f64) -> Vec3 {
    let cos_t = 1.0 - u * (1.0 - cos_max);
    let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
    let phi = 2.0 * std::f64::consts::PI * v;
    let (s, t) = axis.basis();
    s.times(sin_t * phi.cos())
        .plus(t.times(sin_t * phi.sin()))
        .plus(axis.times(cos_t))
        .normalized()
}

/// A meter pointing: origin, unit axis, full acceptance angle.
#[derive(Clone, Copy, Debug)]
pub struct Aim {
    pub origin: Vec3,
    pub axis: Vec3,
    pub acceptance_deg: f64,
}

/// Samples `count` cone samples starting at sample index `first` for stream `stream`.
/// Deterministic: each sample has its own random stream; chunks are merged in order.
pub fn sample_cone(
    tracer: &Tracer,
    aim: Aim,
    seed: u64,
    stream: u64,
    first: u64,
    count: u64,
) -> XyzStats {
    sample_cone_until(tracer, aim, seed, stream, first, count, Deadline::never())
}

/// [`sample_cone`], stopping early (with fewer samples) once `deadline` has passed.
pub fn sample_cone_until(
    tracer: &Tracer,
    aim: Aim,
    seed: u64,
    stream: u64,
    first: u64,
    count: u64,
    deadline: Deadline,
) -> XyzStats {
    const CHUNK: u64 = 256;
    let cos_max = (aim.acceptance_deg.to_radians() / 2.0).cos();
    let chunks: Vec<u64> = (0..count.div_ceil(CHUNK)).collect();
    let parts: Vec<XyzStats> = chunks
        .par_iter()
        .map(|c| {
            let mut st = XyzStats::default();
            let lo = first + c * CHUNK;
            let hi = (first + (c + 1) * CHUNK).min(first + count);
            for i in lo..hi {
                // A sample costs microseconds in the box but can cost milliseconds in a
                // scene of thousands of surfaces: look at the clock every few.
                if (i - lo) % 8 == 0 && deadline.passed() {
                    break;
                }
                let mut rng = Rng::new(seed, stream, i);
                let d = cone_direction(aim.axis, cos_max, rng.next_f64(), rng.next_f64());
                st.push(tracer.xyz_sample(aim.origin, d, &mut rng));
            }
            st
        })
        .collect();
    let mut total = XyzStats::default();
    for p in &parts {
        total.merge(p);
    }
    total
}

/// Options of a spot run.
#[derive(Clone, Copy, Debug)]
pub struct SpotOptions {
    pub target_de: f64,
    pub white: Option<Xyz>,
    pub max_seconds: f64,
    pub seed: u64,
    pub strategy: Strategy,
    /// Samples per patch in the first batch (doubling afterwards, as needed).
    pub first_batch: u64,
}

impl Default for SpotOptions {
    fn default() -> Self {
        SpotOptions {
            target_de: 0.1,
            white: None,
            max_seconds: 600.0,
            seed: 1,
            strategy: Strategy::default(),
            first_batch: 4096,
        }
    }
}

/// All readings of a spot run.
#[derive(Clone, Debug, serde::Serialize)]
pub struct SpotResult {
    pub white: Xyz,
    pub seconds: f64,
    /// Each with its 95 % half-width ([`Uncertainty::HalfWidth95`], with its sampling).
    pub patches: Vec<RenderedReading>,
    /// Every patch reached the target (false if `max_seconds` ran out first).
    #[serde(skip)]
    pub converged: bool,
}

/// Why a spot run cannot start.
#[derive(Debug, thiserror::Error)]
pub enum SpotError {
    #[error("the scene has no surface marked as ColorChecker patch {0}")]
    MissingPatch(usize),
    #[error("reference white must have Y > 0, got {0:?}")]
    BadWhite([f64; 3]),
    #[error("the scene has no camera: the meter stands at the camera's optical centre")]
    NoCamera,
    #[error("the scene has no meter (its acceptance angle)")]
    NoMeter,
    #[error("the time limit must be > 0 s, got {0}")]
    BadTimeLimit(f64),
    #[error("the ΔE*ab target must be > 0, got {0}")]
    BadTarget(f64),
    #[error(
        "the time limit of {seconds} s ran out before {what} had two samples: no reading \
         and no confidence interval can be given"
    )]
    TimeLimit { seconds: f64, what: String },
    #[error("the reference white is not lit (Y = {0}): the meter sees no light from patch 19")]
    DarkWhite(f64),
    #[error("patch {patch}: the reading is not a finite number ({xyz:?})")]
    NonFinite { patch: usize, xyz: [f64; 3] },
}

/// The meter aim at patch `k` of `scene`.
pub fn patch_aim(scene: &Scene, k: usize) -> Result<Aim, SpotError> {
    let s = scene.patch_surface(k).ok_or(SpotError::MissingPatch(k))?;
    let origin = scene.camera.ok_or(SpotError::NoCamera)?.position;
    Ok(Aim {
        origin,
        axis: scene.surfaces[s].rect.centre().minus(origin).normalized(),
        acceptance_deg: scene.meter_acceptance_deg.ok_or(SpotError::NoMeter)?,
    })
}

/// The scene with a perfect white diffuser in place of patch 19.
pub fn white_scene(scene: &Scene) -> Result<Scene, SpotError> {
    let mut w = scene.clone();
    let s = w.patch_surface(19).ok_or(SpotError::MissingPatch(19))?;
    w.surfaces[s].reflectance.iter_mut().for_each(|r| *r = 1.0);
    Ok(w)
}

/// How far a spot run has come, for a progress display.
#[derive(Clone, Copy, Debug)]
pub struct SpotProgress {
    /// Patches whose half-width is below the target.
    pub converged: usize,
    /// The largest ΔE*ab 95 % half-width among the patches.
    pub worst_de: f64,
    pub seconds: f64,
}

/// The reference white: a perfect white diffuser in place of patch 19, seen by the meter and
/// refined to a third of `opts.target_de`. Its error shifts every patch alike and is not in
/// the patches' half-widths, so it has to be well below theirs.
pub fn reference_white(scene: &Scene, opts: &SpotOptions) -> Result<Xyz, SpotError> {
    reference_white_traced(scene, opts).map(|w| w.xyz)
}

/// A reference white as traced: its XYZ and how close it came to its target before the
/// time limit.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct TracedWhite {
    #[serde(rename = "XYZ")]
    pub xyz: Xyz,
    /// Its own ΔE*ab 95 % half-width (against itself).
    pub de_ci95: f64,
    /// What it was traced to: a third of the readings' target.
    pub target_de: f64,
    pub samples: u64,
    /// The time limit (s) it was traced under.
    pub max_seconds: f64,
}

impl TracedWhite {
    /// Whether the white reached its target; one that did not was cut short by the time
    /// limit.
    pub fn reached(&self) -> bool {
        self.de_ci95 < self.target_de
    }
}

/// [`reference_white`] with how far it got.
pub fn reference_white_traced(scene: &Scene, opts: &SpotOptions) -> Result<TracedWhite, SpotError> {
    check_options(opts)?;
    reference_white_until(scene, opts, Deadline::after(opts.max_seconds))
}

fn check_options(opts: &SpotOptions) -> Result<(), SpotError> {
    if opts.max_seconds.is_nan() || opts.max_seconds <= 0.0 {
        return Err(SpotError::BadTimeLimit(opts.max_seconds));
    }
    if opts.target_de.is_nan() || opts.target_de <= 0.0 {
        return Err(SpotError::BadTarget(opts.target_de));
    }
    Ok(())
}

fn reference_white_until(
    scene: &Scene,
    opts: &SpotOptions,
    deadline: Deadline,
) -> Result<TracedWhite, SpotError> {
    let ws = white_scene(scene)?;
    let wt = Tracer::new(&ws, opts.strategy);
    let aim = patch_aim(&ws, 19)?;
    let mut st = XyzStats::default();
    let mut batch = opts.first_batch;
    loop {
        st.merge(&sample_cone_until(
            &wt, aim, opts.seed, 1000, st.n, batch, deadline,
        ));
        if st.n < 2 {
            return Err(SpotError::TimeLimit {
                seconds: opts.max_seconds,
                what: "the reference white".into(),
            });
        }
        let white = st.mean();
        if !(white[1] > 0.0 && white.is_finite()) {
            return Err(SpotError::DarkWhite(white[1]));
        }
        if deadline.passed() || st.de_ci95(white) < opts.target_de / 3.0 {
            break;
        }
        batch = st.n;
    }
    let white = st.mean();
    if !(white[1] > 0.0 && white.is_finite()) {
        return Err(SpotError::DarkWhite(white[1]));
    }
    Ok(TracedWhite {
        xyz: white,
        de_ci95: st.de_ci95(white),
        target_de: opts.target_de / 3.0,
        samples: st.n,
        max_seconds: opts.max_seconds,
    })
}

/// The 24 readings, refined until every ΔE*ab 95 % half-width is below the target.
pub fn render_spots(scene: &Scene, opts: &SpotOptions) -> Result<SpotResult, SpotError> {
    render_spots_with_progress(scene, opts, &|_| {})
}

/// [`render_spots`], reporting after every round of batches.
pub fn render_spots_with_progress(
    scene: &Scene,
    opts: &SpotOptions,
    progress: &dyn Fn(SpotProgress),
) -> Result<SpotResult, SpotError> {
    let start = Instant::now();
    check_options(opts)?;
    let deadline = Deadline::after(opts.max_seconds);
    let aims: Vec<Aim> = (1..=24)
        .map(|k| patch_aim(scene, k))
        .collect::<Result<_, _>>()?;
    let tracer = Tracer::new(scene, opts.strategy);
    let white = match opts.white {
        Some(w) => {
            if !(w[1] > 0.0 && w.is_finite()) {
                return Err(SpotError::BadWhite(w.to_array()));
            }
            w
        }
        None => reference_white_until(scene, opts, deadline)?.xyz,
    };
    let mut stats = vec![XyzStats::default(); 24];
    let mut batch = [opts.first_batch; 24];
    let mut converged;
    loop {
        converged = true;
        for k in 0..24 {
            if stats[k].n > 0 && stats[k].de_ci95(white) < opts.target_de {
                continue;
            }
            converged = false;
            let first = stats[k].n;
            let add = sample_cone_until(
                &tracer,
                aims[k],
                opts.seed,
                k as u64 + 1,
                first,
                batch[k],
                deadline,
            );
            stats[k].merge(&add);
            // Next batch sized from the 1/√N law, at most doubling.
            let ci = stats[k].de_ci95(white);
            let need = (stats[k].n as f64 * (ci / opts.target_de).powi(2) * 1.1) as u64;
            batch[k] = need
                .saturating_sub(stats[k].n)
                .clamp(1024, stats[k].n.max(1024));
        }
        progress(SpotProgress {
            converged: stats
                .iter()
                .filter(|st| st.de_ci95(white) < opts.target_de)
                .count(),
            worst_de: stats.iter().map(|st| st.de_ci95(white)).fold(0.0, f64::max),
            seconds: start.elapsed().as_secs_f64(),
        });
        if converged || deadline.passed() {
            break;
        }
    }
    if let Some(k) = stats.iter().position(|st| st.n < 2) {
        return Err(SpotError::TimeLimit {
            seconds: opts.max_seconds,
            what: format!("patch {}", k + 1),
        });
    }
    let patches = stats
        .iter()
        .enumerate()
        .map(|(k, st)| {
            let uncertainty = Uncertainty::HalfWidth95 {
                de: st.de_ci95(white),
                sampling: Some(Sampling {
                    xyz_stderr: st.stderr(),
                    samples: st.n,
                }),
            };
            RenderedReading::new(k + 1, st.mean(), white, uncertainty)
        })
        .collect::<Vec<RenderedReading>>();
    check_finite(&patches, &stats)?;
    Ok(SpotResult {
        white,
        seconds: start.elapsed().as_secs_f64(),
        patches,
        converged,
    })
}

/// Refuses a reading that is no number (its XYZ, CIELAB, standard errors or uncertainty),
/// naming its patch.
fn check_finite(patches: &[RenderedReading], stats: &[XyzStats]) -> Result<(), SpotError> {
    if let Some((p, _)) = patches.iter().zip(stats).find(|(p, st)| {
        !(p.xyz.is_finite()
            && p.lab
                .iter()
                .chain(&st.stderr())
                .chain([&p.uncertainty.de_ab()])
                .all(|x| x.is_finite()))
    }) {
        return Err(SpotError::NonFinite {
            patch: p.patch,
            xyz: p.xyz.to_array(),
        });
    }
    Ok(())
}
