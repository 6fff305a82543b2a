//! The light's spatial model: each tile's value (its luminance, or its radiance in one
//! band) as a quadratic in the tile's position on the panel, fitted by least squares to
//! the tiles read, and what the tiles not read would add to the error of the 24 spots.
//!
//! The quadratic (1, u, v, u², uv, v² in the panel's coordinates scaled to [−1, 1]) is the
//! smallest smooth surface that holds a fall-off towards the edges and a tilt across the
//! panel, what a backlit panel shows; a tile's own scatter about it is what the
//! cross-validated residual of the tiles read measures, and an unread tile takes the
//! model's value with that scatter, widened by the fit's own uncertainty there (its
//! leverage).

use nalgebra::{DMatrix, DVector};

use super::decision::RoundDecision;
use super::rule::AdaptiveRule;
use crate::color::Spectrum;
use crate::measure_box::plan::{BoxPlan, BoxStep, Geometry, Target};
use crate::measure_box::scene::{patch_centre, tile_centre};
use crate::session::Entry;
use crate::validation::JND_DE76;

/// Terms of the quadratic.
pub const TERMS: usize = 6;

/// ΔL* per unit relative luminance error at the white (dL*/dY · Y = 116/3 · (Y/Yn)^⅓,
/// largest at Y = Yn): a bound on a patch's ΔE*ab from a luminance error of its light.
pub const DL_PER_RELATIVE_Y: f64 = 116.0 / 3.0;

/// A tile's position scaled to [−1, 1] across the panel (u along the columns, v along the
/// rows); a panel one tile across sits at 0.
pub fn position(g: &Geometry, row: usize, col: usize) -> (f64, f64) {
    let scaled = |i: usize, n: usize| {
        let half = ((n as f64 - 1.0) / 2.0).max(1.0);
        (i as f64 - (n as f64 - 1.0) / 2.0) / half
    };
    (scaled(col, g.cols), scaled(row, g.rows))
}

fn terms(u: f64, v: f64) -> [f64; TERMS] {
    [1.0, u, v, u * u, u * v, v * v]
}

/// A quadratic fitted to values at tile positions, for several channels at once (bands of
/// a spectrum) on the same design.
#[derive(Clone, Debug)]
pub struct SpatialFit {
    /// (XᵀX)⁻¹ of the design.
    inverse: DMatrix<f64>,
    /// One coefficient vector per channel.
    coefficients: Vec<DVector<f64>>,
    /// Each tile's leverage hᵢᵢ, in the order fitted.
    leverage: Vec<f64>,
    /// Each tile's residual per channel.
    residuals: Vec<Vec<f64>>,
}

impl SpatialFit {
    /// Fits `values[i][channel]` at `positions[i]`; None with fewer tiles than terms or a
    /// design that does not determine them (every tile in one row, say).
    pub fn new(positions: &[(f64, f64)], values: &[Vec<f64>]) -> Option<SpatialFit> {
        let n = positions.len();
        if n < TERMS || values.len() != n {
            return None;
        }
        let channels = values[0].len();
        let x = DMatrix::from_fn(n, TERMS, |i, k| terms(positions[i].0, positions[i].1)[k]);
        let inverse = (x.transpose() * &x).try_inverse()?;
        let hat = &x * &inverse * x.transpose();
        let leverage: Vec<f64> = (0..n).map(|i| hat[(i, i)]).collect();
        let mut coefficients = Vec::with_capacity(channels);
        let mut residuals = vec![vec![0.0; channels]; n];
        for c in 0..channels {
            let y = DVector::from_fn(n, |i, _| values[i][c]);
            let b = &inverse * x.transpose() * &y;
            let fitted = &x * &b;
            for i in 0..n {
                residuals[i][c] = y[i] - fitted[i];
            }
            coefficients.push(b);
        }
        Some(SpatialFit {
            inverse,
            coefficients,
            leverage,
            residuals,
        })
    }

    /// The model's value of every channel at (u, v).
    pub fn predict(&self, u: f64, v: f64) -> Vec<f64> {
        let t = terms(u, v);
        self.coefficients
            .iter()
            .map(|b| (0..TERMS).map(|k| t[k] * b[k]).sum())
            .collect()
    }

    /// The leverage of a new point: the fit's variance there in units of one tile's.
    pub fn leverage_at(&self, u: f64, v: f64) -> f64 {
        let t = DVector::from_row_slice(&terms(u, v));
        (t.transpose() * &self.inverse * &t)[(0, 0)]
    }

    /// Tile i's leave-one-out residual in channel c: eᵢ / (1 − hᵢᵢ), exact for least
    /// squares; None where the tile alone fixes a term (hᵢᵢ = 1).
    pub fn loo_residual(&self, i: usize, c: usize) -> Option<f64> {
        let h = self.leverage[i];
        (1.0 - h > 1e-9).then(|| self.residuals[i][c] / (1.0 - h))
    }
}

/// How far each tile's light reaches each patch directly: tile k's share of patch p's
/// direct irradiance, `share[k][p]`, each column summing to 1. The spots are linear in the
/// tiles' emission, so a relative error δ in tile k moves patch p's light by
/// `share[k][p]`·δ through the direct path; the light reflected by the walls first mixes
/// every tile's alike, so its share is nearer the uniform 1/N and the direct share bounds
/// the spread of the sensitivities. The emitter is taken as Lambertian: the tiles come
/// before the fall-off is read, and the chart faces the panel within about 30°, where the
/// simulated and the paper's light stay within 10 % of it.
pub fn direct_shares(g: &Geometry, patches: &[usize]) -> Vec<Vec<f64>> {
    let tiles: Vec<[f64; 3]> = (0..g.rows)
        .flat_map(|r| (0..g.cols).map(move |c| (r, c)))
        .map(|(r, c)| tile_centre(g, r, c))
        .collect();
    let mut share = vec![vec![0.0; patches.len()]; tiles.len()];
    for (p, &patch) in patches.iter().enumerate() {
        let at = patch_centre(g, patch);
        // Both normals lie along x (the panel's into the box, the chart's out of its
        // wall): cos θ = cos θ' = dx / r, so the form factor goes as dx² / r⁴.
        let f: Vec<f64> = tiles
            .iter()
            .map(|t| {
                let d = [at[0] - t[0], at[1] - t[1], at[2] - t[2]];
                let r2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
                d[0] * d[0] / (r2 * r2)
            })
            .collect();
        let sum: f64 = f.iter().sum();
        for (k, fk) in f.iter().enumerate() {
            share[k][p] = fk / sum;
        }
    }
    share
}

/// Each tile read, [row, col], with its mean luminance, in first-read order.
pub fn tiles_read(taken: &[Entry<BoxStep>]) -> Vec<([usize; 2], f64)> {
    let mut sums: Vec<([usize; 2], f64, usize)> = Vec::new();
    for e in taken {
        if let Target::Tile { row, col } = e.data.target {
            match sums.iter_mut().find(|s| s.0 == [row, col]) {
                Some(s) => {
                    s.1 += e.reading.xyz[1];
                    s.2 += 1;
                }
                None => sums.push(([row, col], e.reading.xyz[1], 1)),
            }
        }
    }
    sums.into_iter()
        .map(|(t, y, n)| (t, y / n as f64))
        .collect()
}

/// The unread tiles' predicted effect on the spots, JND, and the tile whose own share of
/// it is largest (None when every tile is read), from the tiles read with their mean
/// luminance; None when the model cannot be fitted to them.
pub fn unread_effect(
    plan: &BoxPlan,
    read: &[([usize; 2], f64)],
) -> Option<(f64, Option<[usize; 2]>)> {
    let g = &plan.geometry;
    let mean = read.iter().map(|r| r.1).sum::<f64>() / read.len().max(1) as f64;
    if mean.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
        return None;
    }
    let positions: Vec<(f64, f64)> = read.iter().map(|r| position(g, r.0[0], r.0[1])).collect();
    let values: Vec<Vec<f64>> = read.iter().map(|r| vec![r.1 / mean]).collect();
    let fit = SpatialFit::new(&positions, &values)?;
    let loo: Vec<f64> = (0..read.len())
        .filter_map(|i| fit.loo_residual(i, 0))
        .collect();
    if loo.is_empty() {
        return None;
    }
    // The scatter of a tile about the model, pooled over the tiles read.
    let scatter = (loo.iter().map(|e| e * e).sum::<f64>() / loo.len() as f64).sqrt();
    let share = direct_shares(g, &plan.patches);
    let mut per_patch = vec![0.0; plan.patches.len()];
    let mut worst: Option<([usize; 2], f64)> = None;
    for row in 0..g.rows {
        for col in 0..g.cols {
            if read.iter().any(|r| r.0 == [row, col]) {
                continue;
            }
            let (u, v) = position(g, row, col);
            let sd = scatter * (1.0 + fit.leverage_at(u, v)).sqrt();
            let k = row * g.cols + col;
            let mut largest: f64 = 0.0;
            for (p, total) in per_patch.iter_mut().enumerate() {
                let d = share[k][p] * sd;
                *total += d * d;
                largest = largest.max(d);
            }
            if worst.is_none_or(|w| largest > w.1) {
                worst = Some(([row, col], largest));
            }
        }
    }
    let effect = per_patch.iter().copied().fold(0.0, f64::max).sqrt() * DL_PER_RELATIVE_Y;
    Some((effect / JND_DE76, worst.map(|w| w.0)))
}

/// The tiles' next round: the unread tile that adds most to the spots' error, unless the
/// unread tiles' effect is within the rule's figure or the cap is reached.
pub fn choose(plan: &BoxPlan, rule: &AdaptiveRule, taken: &[Entry<BoxStep>]) -> RoundDecision {
    let read = tiles_read(taken);
    let all = plan.geometry.rows * plan.geometry.cols;
    let unread_all = || -> Vec<Target> {
        (0..all)
            .map(|k| (k / plan.geometry.cols, k % plan.geometry.cols))
            .filter(|&(row, col)| !read.iter().any(|r| r.0 == [row, col]))
            .map(|(row, col)| Target::Tile { row, col })
            .collect()
    };
    let Some((effect, worst)) = unread_effect(plan, &read) else {
        let next = unread_all();
        return RoundDecision {
            why: format!(
                "the spatial model cannot be fitted to {} tile(s): every tile is read",
                read.len()
            ),
            next,
            figure: f64::NAN,
        };
    };
    let stop = |why: String| RoundDecision {
        next: Vec::new(),
        figure: effect,
        why,
    };
    match worst {
        None => stop("every tile is read".into()),
        Some(_) if effect <= rule.tile_effect_jnd => stop(format!(
            "the unread tiles move no spot by more than {effect:.3} JND (at most {})",
            rule.tile_effect_jnd
        )),
        Some(_) if read.len() >= rule.max_tiles => stop(format!(
            "{} tiles read, the most the rule reads; the unread ones may move a spot by {effect:.3} JND",
            read.len()
        )),
        Some([row, col]) => RoundDecision {
            next: vec![Target::Tile { row, col }],
            figure: effect,
            why: format!(
                "the unread tiles may move a spot by {effect:.3} JND (more than {}): tile {row},{col} adds most",
                rule.tile_effect_jnd
            ),
        },
    }
}

/// Every tile's spectrum, row by row: those read (`tiles`' `Some`) as given, the others
/// the spatial model's, fitted to them band by band on the first read tile's grid; None
/// when the model cannot be fitted to the tiles read.
pub fn complete_spectra(g: &Geometry, tiles: &[Option<Spectrum>]) -> Option<Vec<Spectrum>> {
    let first = tiles.iter().flatten().next()?;
    let grid = first.wavelengths_nm().to_vec();
    let read: Vec<(usize, &Spectrum)> = tiles
        .iter()
        .enumerate()
        .filter_map(|(k, s)| s.as_ref().map(|s| (k, s)))
        .collect();
    let positions: Vec<(f64, f64)> = read
        .iter()
        .map(|&(k, _)| position(g, k / g.cols, k % g.cols))
        .collect();
    let values: Vec<Vec<f64>> = read
        .iter()
        .map(|(_, s)| grid.iter().map(|&l| s.value_at(l)).collect())
        .collect();
    let fit = SpatialFit::new(&positions, &values)?;
    (0..g.rows * g.cols)
        .map(|k| match &tiles[k] {
            Some(s) => Some(s.clone()),
            None => {
                let (u, v) = position(g, k / g.cols, k % g.cols);
                Spectrum::new(grid.clone(), fit.predict(u, v))
                    .ok()
                    .map(|s| s.with_outside(first.outside()))
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A panel whose luminance is 100·(1 − 0.03(u² + v²))·(1 + 0.04u + 0.03v): expanded,
    /// a quadratic plus the cubic terms 100·(−0.0012u³ − 0.0009u²v − 0.0012uv² − 0.0009v³),
    /// which the model cannot hold. Fitted to the 3 × 3 subset of a 5 × 5 panel, each cubic
    /// monomial is replaced by its own least-squares quadratic on that subset: u³ by u
    /// (equal at u ∈ {−1, 0, 1}; off by |u³ − u| ≤ 0.375 at the tiles), u²v by 2v/3
    /// (Σu²v² / Σv² = 4/6; off by |v(u² − 2/3)| ≤ 2/3 at the tiles), and so uv², v³. The
    /// error at any tile is then at most 100·(0.0012·0.375 + 0.0009·2/3 + 0.0012·2/3 +
    /// 0.0009·0.375) = 0.219 cd/m², the bound taken.
    #[test]
    fn the_model_recovers_an_analytic_panel_from_the_subset() {
        let g = Geometry::default();
        let truth =
            |u: f64, v: f64| 100.0 * (1.0 - 0.03 * (u * u + v * v)) * (1.0 + 0.04 * u + 0.03 * v);
        let subset: Vec<(usize, usize)> = [0, 2, 4]
            .iter()
            .flat_map(|&r| [0, 2, 4].map(move |c| (r, c)))
            .collect();
        let positions: Vec<(f64, f64)> = subset.iter().map(|&(r, c)| position(&g, r, c)).collect();
        let values: Vec<Vec<f64>> = positions.iter().map(|&(u, v)| vec![truth(u, v)]).collect();
        let fit = SpatialFit::new(&positions, &values).unwrap();
        let mut worst: f64 = 0.0;
        for r in 0..5 {
            for c in 0..5 {
                let (u, v) = position(&g, r, c);
                worst = worst.max((fit.predict(u, v)[0] - truth(u, v)).abs());
            }
        }
        assert!(worst <= 0.219, "{worst}");
        // A pure quadratic is recovered to rounding, and its leave-one-out residuals vanish.
        let quad = |u: f64, v: f64| 100.0 - 3.0 * u * u - 2.0 * v * v + 4.0 * u + 3.0 * v + u * v;
        let values: Vec<Vec<f64>> = positions.iter().map(|&(u, v)| vec![quad(u, v)]).collect();
        let fit = SpatialFit::new(&positions, &values).unwrap();
        let (u, v) = position(&g, 1, 3);
        assert!((fit.predict(u, v)[0] - quad(u, v)).abs() < 1e-9);
        assert!((0..9).all(|i| fit.loo_residual(i, 0).unwrap().abs() < 1e-9));
        // The centre of a 3 × 3 design: hᵢᵢ by hand. The columns 1, u, v, u², uv, v² at
        // u, v ∈ {−1, 0, 1} give XᵀX with Σ1 = 9, Σu² = Σv² = 6, Σu⁴ = 6, Σu²v² = 4,
        // Σ(uv)² = 4, Σu² cross 1 = 6; at the centre only the constant is 1, so
        // h = [(XᵀX)⁻¹]₀₀, which for the block [[9, 6, 6], [6, 6, 4], [6, 4, 6]] is 5/9.
        assert!((fit.leverage_at(0.0, 0.0) - 5.0 / 9.0).abs() < 1e-12);
    }

    /// Every patch's shares sum to 1, and the tiles nearest the chart's centre (the middle
    /// of the panel, facing it) have the largest.
    #[test]
    fn the_direct_shares_favour_the_tiles_facing_the_chart() {
        let g = Geometry::default();
        let share = direct_shares(&g, &[15]);
        let sum: f64 = share.iter().map(|s| s[0]).sum();
        assert!((sum - 1.0).abs() < 1e-12);
        let centre = share[12][0];
        assert!(share.iter().all(|s| s[0] <= centre + 1e-15));
        assert!(share[0][0] < centre);
    }
}
