//! The radiosity system per wavelength band, solved by Gauss–Seidel.
//!
//! Light leaves a component's tiles with radiance S(λ)·(tile gain)·f(ω), and every other
//! bounce is Lambertian, so the outgoing radiance of element i due to that component is
//! L_i(λ) = S(λ)·ℓ_i(λ) with ℓ = ρ(λ) ∘ (g/π + F ℓ), g the element's direct irradiance
//! per unit source radiance. ℓ depends on λ only through the smooth reflectances, so it is
//! solved on a coarse band grid and interpolated linearly; the spectra stay at 1 nm.
//!
//! Gauss–Seidel converges when the largest reflectance times the fraction of light that
//! stays in the scene is below 1; a closed box with reflectances a little above 1 (measured
//! noise) and an absorbing emitter still qualifies but needs more sweeps, so the sweep
//! limit is generous and a solution that grows instead of settling is reported. In such a
//! room the change per sweep shrinks by a steady factor q close to ρ; once three sweeps
//! agree on it, the slowest mode's remaining sum Δ·q/(1 − q) is added in one step.

use rayon::prelude::*;

use super::super::geometry::VecOps;

use super::super::spectral::N_BINS;
use super::direct::{irradiance_factor, mean_factor_over};
use super::lights::Lights;
use super::mesh::{average_over, Mesh};
use crate::render::deadline::Deadline;
use crate::render::scene::Scene;

/// The wavelength nodes the system is solved at: every `step` bins from the first.
#[derive(Clone, Debug)]
pub struct Bands {
    pub bins: Vec<usize>,
}

impl Bands {
    /// Nodes every `step_nm` (≥ 1) from 380 nm, always including 780 nm.
    pub fn new(step_nm: usize) -> Bands {
        let step = step_nm.max(1);
        let mut bins: Vec<usize> = (0..N_BINS).step_by(step).collect();
        if *bins.last().unwrap_or(&0) != N_BINS - 1 {
            bins.push(N_BINS - 1);
        }
        Bands { bins }
    }

    pub fn len(&self) -> usize {
        self.bins.len()
    }

    pub fn is_empty(&self) -> bool {
        self.bins.is_empty()
    }

    /// Values at the nodes → every 1 nm bin, linearly.
    pub fn interpolate(&self, at_nodes: &[f64]) -> Vec<f64> {
        let mut out = vec![0.0; N_BINS];
        for (w, v) in self.bins.windows(2).zip(at_nodes.windows(2)) {
            let span = (w[1] - w[0]) as f64;
            for (k, o) in out[w[0]..=w[1]].iter_mut().enumerate() {
                let t = k as f64 / span;
                *o = v[0] * (1.0 - t) + v[1] * t;
            }
        }
        out
    }
}

/// g/π per element for each light component, averaged over the element (more nodes near
/// the light); None if the deadline passed.
pub fn sources(
    scene: &Scene,
    lights: &Lights,
    mesh: &Mesh,
    deadline: Deadline,
) -> Option<Vec<Vec<f64>>> {
    lights
        .comps
        .iter()
        .map(|c| {
            let e = &scene.emitters[c.emitter];
            if deadline.passed() {
                return None;
            }
            let ec = e.rect.centre();
            let esize = e.rect.edge_u.length().max(e.rect.edge_v.length());
            mesh.elements
                .par_iter()
                .map(|el| {
                    if deadline.passed() {
                        return None;
                    }
                    // Exact where the tiles are Lambertian: a point rule's error would
                    // differ between components and levels and spoil the extrapolation.
                    if let Some(f) = mean_factor_over(e, &c.weights, &el.rect) {
                        return Some(f);
                    }
                    let dist = el.rect.centre().minus(ec).length();
                    let nodes = ((1.0 + 4.0 * el.size / (dist - esize / 2.0).max(el.size)).ceil()
                        as usize)
                        .clamp(1, 8);
                    Some(
                        average_over(&el.rect, nodes, |x| {
                            irradiance_factor(e, &c.weights, x, el.rect.normal)
                        }) / std::f64::consts::PI,
                    )
                })
                .collect()
        })
        .collect()
}

/// Relative change below which Gauss–Seidel stops.
pub const TOLERANCE: f64 = 1e-10;

/// Most Gauss–Seidel sweeps: a scene that loses 1 % of its light per bounce needs about
/// 2,300 to reach [`TOLERANCE`]; beyond this the reflectances are not physical.
pub const MAX_SWEEPS: usize = 20_000;

/// ℓ on the band grid (N × bands, row-major), the sweeps it took (the slowest band chunk)
/// and an estimate of its largest relative error left by stopping the iteration.
pub struct Solution {
    pub l: Vec<f64>,
    pub sweeps: usize,
    pub rel_err: f64,
}

/// Why Gauss–Seidel gave no solution.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SolveFailure {
    /// The deadline passed.
    Time,
    /// The light grows or does not settle: the reflectances return more than they receive.
    Diverges { sweeps: usize },
}

/// ℓ (N × bands, row-major) for one emitter's source `src`; `refl` is N × bands. `warm`
/// starts the iteration from a neighbouring solution (the white scene from the scene's).
/// Returns the solution and the number of sweeps. Bands whose reflectances are the same on
/// every element have the same solution, so each distinct band is solved once (a grey
/// room is one system, not 81).
pub fn solve(
    mesh: &Mesh,
    refl: &[f64],
    src: &[f64],
    bands: usize,
    warm: Option<&[f64]>,
    deadline: Deadline,
) -> Result<Solution, SolveFailure> {
    let n = mesh.elements.len();
    let column = |b: usize| (0..n).map(move |i| refl[i * bands + b]);
    let mut distinct: Vec<usize> = Vec::new();
    let mut of_band = Vec::with_capacity(bands);
    for b in 0..bands {
        match distinct.iter().position(|&d| column(d).eq(column(b))) {
            Some(k) => of_band.push(k),
            None => {
                of_band.push(distinct.len());
                distinct.push(b);
            }
        }
    }
    if distinct.len() == bands {
        return solve_bands(mesh, refl, src, bands, warm, deadline);
    }
    let nd = distinct.len();
    let pick = |m: &[f64]| -> Vec<f64> {
        (0..n)
            .flat_map(|i| distinct.iter().map(move |&b| m[i * bands + b]))
            .collect()
    };
    let warm_d = warm.map(pick);
    let sol = solve_bands(mesh, &pick(refl), src, nd, warm_d.as_deref(), deadline)?;
    let l = (0..n)
        .flat_map(|i| {
            of_band
                .iter()
                .map(|&k| sol.l[i * nd + k])
                .collect::<Vec<_>>()
        })
        .collect();
    Ok(Solution { l, ..sol })
}

/// Gauss–Seidel stalls when the change shrinks by more than this factor per sweep (a bright
/// closed room: about ρ per sweep); its slowest mode is then extrapolated.
const ACCELERATE_ABOVE: f64 = 0.5;

/// One Gauss–Seidel sweep over ℓ (N × k, row-major) with reflectances `r` (N × k): the
/// largest change and the largest value.
fn sweep(
    mesh: &Mesh,
    src: &[f64],
    r: &[f64],
    l: &mut [f64],
    acc: &mut [f64],
    k: usize,
) -> (f64, f64) {
    let n = mesh.elements.len();
    let mut change: f64 = 0.0;
    let mut size: f64 = 0.0;
    for i in 0..n {
        acc.iter_mut().for_each(|a| *a = src[i]);
        let row = &mesh.form[i * n..(i + 1) * n];
        for (j, &f) in row.iter().enumerate() {
            if f != 0.0 {
                let lj = &l[j * k..(j + 1) * k];
                for (a, v) in acc.iter_mut().zip(lj) {
                    *a += f * v;
                }
            }
        }
        let li = &mut l[i * k..(i + 1) * k];
        for ((v, a), rr) in li.iter_mut().zip(acc.iter()).zip(&r[i * k..(i + 1) * k]) {
            let new = rr * a;
            change = change.max((new - *v).abs());
            size = size.max(new.abs());
            *v = new;
        }
    }
    (change, size)
}

/// One chunk of bands solved: its radiosities, its sweeps and its algebraic error estimate.
type BandChunk = (Vec<f64>, usize, f64);

fn solve_bands(
    mesh: &Mesh,
    refl: &[f64],
    src: &[f64],
    bands: usize,
    warm: Option<&[f64]>,
    deadline: Deadline,
) -> Result<Solution, SolveFailure> {
    let n = mesh.elements.len();
    // Bands are independent: split them over the cores, each chunk its own Gauss–Seidel.
    let chunk = bands.div_ceil(rayon::current_num_threads().max(1)).max(1);
    let ranges: Vec<(usize, usize)> = (0..bands)
        .step_by(chunk)
        .map(|b| (b, (b + chunk).min(bands)))
        .collect();
    let parts: Vec<Result<BandChunk, SolveFailure>> = ranges
        .par_iter()
        .map(|&(b0, b1)| {
            let k = b1 - b0;
            let mut l = vec![0.0; n * k];
            let mut r = vec![0.0; n * k];
            for i in 0..n {
                r[i * k..(i + 1) * k].copy_from_slice(&refl[i * bands + b0..i * bands + b1]);
                if let Some(w) = warm {
                    l[i * k..(i + 1) * k].copy_from_slice(&w[i * bands + b0..i * bands + b1]);
                }
            }
            let mut acc = vec![0.0; k];
            let mut before = vec![0.0; n * k];
            let mut sweeps = 0;
            let mut last_change = f64::INFINITY;
            let mut last_ratio = f64::NAN;
            let mut accelerated = false;
            // The slowest contraction seen: after an extrapolation the last two sweeps may
            // show a faster mode while the slowest one still holds what is left.
            let mut slowest: f64 = 0.0;
            let rel_err;
            loop {
                sweeps += 1;
                if deadline.passed() {
                    return Err(SolveFailure::Time);
                }
                before.copy_from_slice(&l);
                let (change, size) = sweep(mesh, src, &r, &mut l, &mut acc, k);
                // After an extrapolation the error estimate needs two plain sweeps.
                let may_stop = last_change.is_finite() || !accelerated;
                if change <= TOLERANCE * size && may_stop {
                    // What the sweeps not taken would still add: a contraction by q per
                    // sweep leaves change·q/(1 − q), q from the last two sweeps.
                    let q = if last_change.is_finite() && last_change > 0.0 {
                        (change / last_change).max(slowest).min(0.999)
                    } else {
                        0.999
                    };
                    rel_err = if size > 0.0 {
                        change / size * q / (1.0 - q)
                    } else {
                        0.0
                    };
                    break;
                }
                if sweeps >= MAX_SWEEPS || !size.is_finite() || size > 1e30 {
                    return Err(SolveFailure::Diverges { sweeps });
                }
                let ratio = change / last_change;
                if ratio.is_finite() {
                    slowest = slowest.max(ratio);
                }
                if ratio > ACCELERATE_ABOVE
                    && ratio < 1.0
                    && (ratio - last_ratio).abs() <= 0.01 * ratio
                {
                    // The slowest mode dominates: add its remaining sum Δ·q/(1 − q) now.
                    let gain = ratio / (1.0 - ratio);
                    for (v, b) in l.iter_mut().zip(&before) {
                        *v += (*v - b) * gain;
                    }
                    accelerated = true;
                    last_change = f64::INFINITY;
                    last_ratio = f64::NAN;
                    continue;
                }
                last_ratio = ratio;
                last_change = change;
            }
            Ok((l, sweeps, rel_err))
        })
        .collect();
    merge(&ranges, parts, n, bands)
}

/// The band chunks' solutions put back together (N × bands), with the most sweeps and the
/// largest error estimate of any chunk.
fn merge(
    ranges: &[(usize, usize)],
    parts: Vec<Result<BandChunk, SolveFailure>>,
    n: usize,
    bands: usize,
) -> Result<Solution, SolveFailure> {
    let mut out = vec![0.0; n * bands];
    let mut sweeps = 0;
    let mut rel_err: f64 = 0.0;
    for ((b0, b1), part) in ranges.iter().zip(parts) {
        let (l, s, e) = part?;
        let k = b1 - b0;
        sweeps = sweeps.max(s);
        rel_err = rel_err.max(e);
        for i in 0..n {
            out[i * bands + b0..i * bands + b1].copy_from_slice(&l[i * k..(i + 1) * k]);
        }
    }
    Ok(Solution {
        l: out,
        sweeps,
        rel_err,
    })
}
