//! A 3D LUT fitted to scattered patches: the grid is chosen (N evenly spaced drive levels
//! per channel), not read off the data, and its nodes are found by regularised least
//! squares, so any patch set fits in memory and time linear in patches + N³.
//!
//! The table is a base model (whose curves are also the LUT's shapers) plus a correction c
//! at every node. The base is the shaper + matrix model, or on a set with ramps of every
//! channel PLVC (the ramps' own light, added), whichever cross-validates better: on ramps
//! with a few mixed patches PLVC keeps the ramps' chromaticity drift that a matrix cannot,
//! and the correction learns the mixtures. Each patch constrains the four nodes of its tetrahedron
//! through the interpolation weights; a discrete Laplacian (second differences along each
//! axis) keeps the correction smooth where cells hold no patches, so an empty region of
//! the cube follows the matrix model and its neighbours instead of drifting. Per channel of
//! XYZ the normal equations
//!   (Wᵀ Ω W + λ s DᵀD + μ s I) c = Wᵀ Ω (xyz − W·base)
//! are solved by Jacobi-preconditioned conjugate gradients without forming a matrix. Ω
//! weights each patch by dL*/dY at its luminance (the error is judged in CIELAB, where dark
//! colours are more sensitive), s is that weight at mid grey so λ has no unit, and λ is
//! chosen by k-fold cross-validation on held-out ΔE00. If the final table folds (noise in
//! dark readings can ask for it; a display cannot), `lut_unfold` refits it with the folded
//! tetrahedra's edges held along their channels.
//!
//! On a full grid of measured nodes with λ → 0 every node equals its measurement, which is
//! what the grid LUT of [`super::fit_lut`] stores.

use super::error::FitError;
use super::lut_unfold::{unfold, Held, Unfolded};
use super::plvc::fit_plvc;
use super::samples::{fold_of, Sample, SortedSamples};
use super::shaper_matrix::{default_knots, fit_shaper_matrix};
use super::{DisplayModel, Lut3d, ModelKind, Trc};
use crate::color::{delta_e2000, Xyz};

/// The regularisation weights cross-validation chooses from.
pub const LAMBDAS: [f64; 6] = [1e-4, 1e-3, 1e-2, 1e-1, 1.0, 10.0];

/// Folds of the cross-validation that picks λ.
const FOLDS: usize = 5;

/// Grid points per axis for a patch count: more patches can pin a finer grid, and the
/// grid never grows past 17³ = 4913 nodes whatever the input.
pub fn default_grid(patches: usize) -> usize {
    match patches {
        0..=299 => 9,
        300..=2999 => 13,
        _ => 17,
    }
}

/// A fitted scattered LUT and how its base and λ were chosen.
#[derive(Clone, Debug)]
pub struct ScatteredLut {
    pub lut: Lut3d,
    pub lambda: f64,
    /// (λ, cross-validated mean ΔE00) for every λ tried on the chosen base; empty when λ
    /// was given.
    pub cv: Vec<(f64, f64)>,
    /// The model the table corrects: shaper-matrix, or PLVC on a set with ramps where it
    /// predicts held-out patches better.
    pub base: ModelKind,
    /// Lattice edges held along their channel so the table does not fold (0 when the
    /// unconstrained fit folds nowhere; see `lut_unfold`).
    pub held_edges: usize,
}

/// Fits an N³ LUT (`grid` points per axis, ≥ 2) to `patches`; `lambda` None chooses it by
/// cross-validation from [`LAMBDAS`].
pub fn fit_lut_scattered(
    set: &SortedSamples,
    patches: &[Sample],
    grid: usize,
    lambda: Option<f64>,
) -> Result<ScatteredLut, FitError> {
    let kind = ModelKind::Lut;
    let failed = |message: String| FitError::Failed {
        model: kind,
        message,
    };
    if grid < 2 {
        return Err(failed(format!(
            "the grid needs at least 2 points per axis, not {grid}"
        )));
    }
    // Singular primaries are the user's measurement, not the base's fault: said as such.
    let shaper_matrix =
        fit_shaper_matrix(set, patches, default_knots(patches.len())).map_err(|e| match e {
            FitError::SingularPrimaries { .. } => e,
            e => failed(format!(
                "its shapers and start come from shaper-matrix, which failed: {e}"
            )),
        })?;
    let mut bases = vec![Base {
        kind: ModelKind::ShaperMatrix,
        shaper: shaper_matrix.trc.clone(),
        model: Box::new(shaper_matrix),
    }];
    // With ramps, PLVC reproduces every ramp reading and adds them in mixtures; the
    // cross-validation below keeps it only where it predicts held-out patches better.
    if let Ok(plvc) = fit_plvc(set) {
        bases.push(Base {
            kind: ModelKind::Plvc,
            shaper: plvc.shaper.clone(),
            model: Box::new(plvc),
        });
    }
    let level: Vec<f64> = (0..grid).map(|i| i as f64 / (grid - 1) as f64).collect();
    let levels = [level.clone(), level.clone(), level.clone()];
    let lambdas: Vec<f64> = lambda.map_or(LAMBDAS.to_vec(), |l| vec![l]);
    let mut best: Option<Fitted> = None;
    for base in bases {
        let fitted = fit_on_base(set, patches, &levels, base, &lambdas).map_err(failed)?;
        if best.as_ref().is_none_or(|b| fitted.score < b.score) {
            best = Some(fitted);
        }
    }
    let best = best.expect("shaper-matrix is always a base");
    let Unfolded {
        correction,
        held_edges,
    } = best.unfold();
    let nodes: Vec<[f64; 3]> = best
        .base_nodes
        .iter()
        .zip(&correction)
        .map(|(b, d)| std::array::from_fn(|k| b[k] + d[k]))
        .collect();
    let lut = Lut3d::from_parts(levels, best.shaper, nodes).map_err(failed)?;
    Ok(ScatteredLut {
        lut,
        lambda: best.lambda,
        cv: if lambda.is_some() {
            Vec::new()
        } else {
            best.cv
        },
        base: best.base,
        held_edges,
    })
}

/// A model the table corrects, and whose curves shape its axes.
struct Base {
    kind: ModelKind,
    shaper: [Trc; 3],
    model: Box<dyn DisplayModel>,
}

/// The table fitted on one base.
struct Fitted {
    base: ModelKind,
    shaper: [Trc; 3],
    base_nodes: Vec<[f64; 3]>,
    correction: Vec<[f64; 3]>,
    lambda: f64,
    cv: Vec<(f64, f64)>,
    /// The lowest cross-validated mean ΔE00 (0 when nothing was cross-validated).
    score: f64,
    rows: Vec<Row>,
    problem: Problem,
    stiffness: f64,
}

fn fit_on_base(
    set: &SortedSamples,
    patches: &[Sample],
    levels: &[Vec<f64>; 3],
    base: Base,
    lambdas: &[f64],
) -> Result<Fitted, String> {
    let grid = levels[0].len();
    let mut base_nodes = Vec::with_capacity(grid * grid * grid);
    for &r in &levels[0] {
        for &g in &levels[1] {
            for &b in &levels[2] {
                base_nodes.push(base.model.forward([r, g, b]).into());
            }
        }
    }
    let lut = Lut3d::from_parts(levels.clone(), base.shaper.clone(), base_nodes.clone())?;
    let white = set.white.unwrap_or_else(|| base.model.forward([1.0; 3]));
    let yw = white[1];
    let slope = |y: f64| 116.0 / 3.0 / yw * (y / yw).max(0.008856).powf(-2.0 / 3.0);
    let rows: Vec<Row> = patches
        .iter()
        .map(|p| {
            let w = lut.weights(p.rgb);
            let at_base: [f64; 3] =
                std::array::from_fn(|k| w.iter().map(|&(i, f)| f * base_nodes[i][k]).sum::<f64>());
            let omega = slope(p.xyz[1].max(0.0));
            Row {
                w,
                omega2: omega * omega,
                target: std::array::from_fn(|k| p.xyz[k] - at_base[k]),
            }
        })
        .collect();
    let scale = slope(0.2 * yw).powi(2);
    let problem = Problem { grid, scale };
    let wl = white;
    let mut cv = Vec::new();
    for &l in lambdas {
        let mut sum = 0.0;
        let mut count = 0usize;
        for fold in 0..FOLDS.min(patches.len()) {
            let train: Vec<&Row> = rows
                .iter()
                .enumerate()
                .filter(|(i, _)| fold_of(*i) % FOLDS != fold)
                .map(|(_, r)| r)
                .collect();
            let c = problem.solve(&train, l);
            for (i, (row, p)) in rows.iter().zip(patches).enumerate() {
                if fold_of(i) % FOLDS == fold {
                    let f = predict(row, &base_nodes, &c);
                    sum += delta_e2000(Xyz::from(f).to_lab(wl), p.xyz.to_lab(wl));
                    count += 1;
                }
            }
        }
        cv.push((l, sum / count.max(1) as f64));
    }
    let (lambda, score) = cv
        .iter()
        .copied()
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .ok_or("no regularisation weight to try")?;
    let all: Vec<&Row> = rows.iter().collect();
    let correction = problem.solve(&all, lambda);
    Ok(Fitted {
        base: base.kind,
        shaper: base.shaper,
        base_nodes,
        correction,
        lambda,
        cv,
        score,
        rows,
        problem,
        // A held edge off by a fraction δ of the primaries' light costs about as much as a
        // reading off by δ·Y_white at mid grey.
        stiffness: scale * yw * yw,
    })
}

impl Fitted {
    /// The correction refitted so the table does not fold (see `lut_unfold`), and how many
    /// edges that held; done for the chosen base only, since the choice rests on the
    /// cross-validated score.
    fn unfold(&self) -> Unfolded {
        let all: Vec<&Row> = self.rows.iter().collect();
        // Per channel, the share of its light between consecutive (evenly spaced) levels.
        let n = self.problem.grid;
        let steps: [Vec<f64>; 3] = std::array::from_fn(|c| {
            let at = |i: usize| self.shaper[c].eval(i as f64 / (n - 1) as f64);
            (0..n - 1)
                .map(|i| (at(i + 1) - at(i)) / (at(n - 1) - at(0)))
                .collect()
        });
        unfold(
            n,
            &steps,
            &self.base_nodes,
            self.correction.clone(),
            self.stiffness,
            |held, rho, start| self.problem.solve_held(&all, self.lambda, held, rho, start),
        )
    }
}

/// One patch in the normal equations.
struct Row {
    w: [(usize, f64); 4],
    omega2: f64,
    /// Measured XYZ minus the base model's interpolated XYZ.
    target: [f64; 3],
}

fn predict(row: &Row, base: &[[f64; 3]], c: &[[f64; 3]]) -> [f64; 3] {
    std::array::from_fn(|k| row.w.iter().map(|&(i, f)| f * (base[i][k] + c[i][k])).sum())
}

/// A small ridge so nodes no patch and no second difference pins (a null space of the
/// Laplacian) stay at the base model.
const RIDGE: f64 = 1e-6;

struct Problem {
    grid: usize,
    scale: f64,
}

impl Problem {
    fn nodes(&self) -> usize {
        self.grid.pow(3)
    }

    /// Adds λ·s·DᵀD·x to `out`, D the second differences along each axis.
    fn add_laplacian(&self, x: &[f64], weight: f64, out: &mut [f64]) {
        let n = self.grid;
        let strides = [n * n, n, 1];
        for i in 0..n {
            for j in 0..n {
                for k in 0..n {
                    let idx = [i, j, k];
                    let centre = (i * n + j) * n + k;
                    for (axis, &stride) in strides.iter().enumerate() {
                        if idx[axis] == 0 || idx[axis] + 1 == n {
                            continue;
                        }
                        let (a, b) = (centre - stride, centre + stride);
                        let d = weight * (x[a] - 2.0 * x[centre] + x[b]);
                        out[a] += d;
                        out[centre] -= 2.0 * d;
                        out[b] += d;
                    }
                }
            }
        }
    }

    fn apply(&self, rows: &[&Row], lambda: f64, x: &[f64], out: &mut [f64]) {
        let ridge = RIDGE * self.scale;
        for (o, v) in out.iter_mut().zip(x) {
            *o = ridge * v;
        }
        for r in rows {
            let v: f64 = r.w.iter().map(|&(i, f)| f * x[i]).sum();
            for &(i, f) in &r.w {
                out[i] += r.omega2 * f * v;
            }
        }
        self.add_laplacian(x, lambda * self.scale, out);
    }

    /// The corrections at every node for the rows given.
    fn solve(&self, rows: &[&Row], lambda: f64) -> Vec<[f64; 3]> {
        let v = self.nodes();
        let diag = self.diagonal(rows, lambda);
        let mut out = vec![[0.0; 3]; v];
        for k in 0..3 {
            let mut rhs = vec![0.0; v];
            self.add_rhs(rows, k, &mut rhs);
            let x = conjugate_gradients(
                |x, y| self.apply(rows, lambda, x, y),
                &rhs,
                &diag,
                None,
                1e-10,
            );
            for (o, xi) in out.iter_mut().zip(x) {
                o[k] = xi;
            }
        }
        out
    }

    /// As [`Self::solve`], with every held edge pulled to its target by the penalty
    /// ρ·(u·(c_to − c_from) − target)². u mixes X, Y and Z, so the three are solved as one
    /// system (laid out X block, Y block, Z block), started from `start`.
    fn solve_held(
        &self,
        rows: &[&Row],
        lambda: f64,
        held: &[Held],
        rho: f64,
        start: &[[f64; 3]],
    ) -> Vec<[f64; 3]> {
        let v = self.nodes();
        let one = self.diagonal(rows, lambda);
        let mut diag: Vec<f64> = (0..3).flat_map(|_| one.iter().copied()).collect();
        let mut rhs = vec![0.0; 3 * v];
        for k in 0..3 {
            self.add_rhs(rows, k, &mut rhs[k * v..(k + 1) * v]);
        }
        for h in held {
            for k in 0..3 {
                diag[k * v + h.from] += rho * h.u[k] * h.u[k];
                diag[k * v + h.to] += rho * h.u[k] * h.u[k];
                rhs[k * v + h.to] += rho * h.target * h.u[k];
                rhs[k * v + h.from] -= rho * h.target * h.u[k];
            }
        }
        let apply = |x: &[f64], out: &mut [f64]| {
            for k in 0..3 {
                let block = k * v..(k + 1) * v;
                self.apply(rows, lambda, &x[block.clone()], &mut out[block]);
            }
            for h in held {
                let g: f64 = (0..3)
                    .map(|k| h.u[k] * (x[k * v + h.to] - x[k * v + h.from]))
                    .sum();
                for k in 0..3 {
                    out[k * v + h.to] += rho * h.u[k] * g;
                    out[k * v + h.from] -= rho * h.u[k] * g;
                }
            }
        };
        let x0: Vec<f64> = (0..3 * v).map(|i| start[i % v][i / v]).collect();
        // Started warm, each refit stops at a relative residual of 10⁻⁸: half the
        // iterations of 10⁻¹⁰ for the same table on the Surface Pro's halves, where 10⁻⁶
        // already led the rounds to a different (and 0.06 ΔE00 worse) table.
        let x = conjugate_gradients(apply, &rhs, &diag, Some(x0), 1e-8);
        (0..v).map(|i| [x[i], x[v + i], x[2 * v + i]]).collect()
    }

    /// The Jacobi preconditioner: the diagonal of one channel's normal matrix.
    fn diagonal(&self, rows: &[&Row], lambda: f64) -> Vec<f64> {
        let mut diag = vec![RIDGE * self.scale; self.nodes()];
        for r in rows {
            for &(i, f) in &r.w {
                diag[i] += r.omega2 * f * f;
            }
        }
        let lap_diag = laplacian_diagonal(self.grid);
        for (d, l) in diag.iter_mut().zip(&lap_diag) {
            *d += lambda * self.scale * l;
        }
        diag
    }

    /// Adds Wᵀ Ω (target) of XYZ channel k to `rhs`.
    fn add_rhs(&self, rows: &[&Row], k: usize, rhs: &mut [f64]) {
        for r in rows {
            for &(i, f) in &r.w {
                rhs[i] += r.omega2 * f * r.target[k];
            }
        }
    }
}

/// The diagonal of DᵀD on an n³ grid: per axis, a node centring a second difference gets
/// 4, one ending a difference 1 each.
fn laplacian_diagonal(n: usize) -> Vec<f64> {
    let per_axis = |i: usize| -> f64 {
        let mut d = 0.0;
        if i > 0 && i + 1 < n {
            d += 4.0;
        }
        if i + 2 < n {
            d += 1.0;
        }
        if i >= 2 {
            d += 1.0;
        }
        d
    };
    let mut out = Vec::with_capacity(n * n * n);
    for i in 0..n {
        for j in 0..n {
            for k in 0..n {
                out.push(per_axis(i) + per_axis(j) + per_axis(k));
            }
        }
    }
    out
}

/// Jacobi-preconditioned conjugate gradients for a symmetric positive definite operator,
/// from `start` or from zero, until the residual is `tolerance` of |b|.
fn conjugate_gradients(
    apply: impl Fn(&[f64], &mut [f64]),
    b: &[f64],
    diag: &[f64],
    start: Option<Vec<f64>>,
    tolerance: f64,
) -> Vec<f64> {
    let n = b.len();
    let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
    let mut ap = vec![0.0; n];
    let (mut x, mut r) = match start {
        Some(x) => {
            apply(&x, &mut ap);
            let r = b.iter().zip(&ap).map(|(b, a)| b - a).collect();
            (x, r)
        }
        None => (vec![0.0; n], b.to_vec()),
    };
    let mut z: Vec<f64> = r.iter().zip(diag).map(|(r, d)| r / d).collect();
    let mut p = z.clone();
    let mut rz = dot(&r, &z);
    let stop = tolerance * tolerance * dot(b, b).max(1e-300);
    for _ in 0..(4 * n).max(100) {
        if dot(&r, &r) <= stop {
            break;
        }
        apply(&p, &mut ap);
        let pap = dot(&p, &ap);
        if pap <= 0.0 {
            break;
        }
        let alpha = rz / pap;
        for i in 0..n {
            x[i] += alpha * p[i];
            r[i] -= alpha * ap[i];
        }
        for i in 0..n {
            z[i] = r[i] / diag[i];
        }
        let rz_next = dot(&r, &z);
        let beta = rz_next / rz;
        rz = rz_next;
        for i in 0..n {
            p[i] = z[i] + beta * p[i];
        }
    }
    x
}
