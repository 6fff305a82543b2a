//! The constant boundary of repeated 95 % intervals over a bounded number of looks (Pocock
//! 1977; as repeated confidence intervals, Jennison and Turnbull 1989): the c for which a
//! Brownian motion S observed at information times I₁ < … < I_K leaves the band
//! |S_k| ≤ c·√I_k at some look with probability α.
//!
//! The probability of staying in the band is computed by the recursion of Armitage,
//! McPherson and Rowe (1969): the density of S_k on the band, restricted to the paths that
//! stayed in it so far, is carried to the next look by convolving it with the normal
//! density of the increment, N(0, I_{k+1} − I_k). The band is cut into equal cells, the
//! density taken at each cell's midpoint, and the increment's density integrated exactly
//! over each cell (a difference of Φ), so that looks whose information hardly grows (a
//! reference side's fixed noise dominating) are carried as well as distant ones. The
//! published constants (Jennison and Turnbull, *Group Sequential Methods with Applications
//! to Clinical Trials*, 2000, Table 2.1: K = 2, 3, 4, 5, 10 equally spaced looks give 2.178,
//! 2.289, 2.361, 2.413, 2.555 for α = 0.05) are the test.

use super::distributions::normal_quantile;

/// Cells of the band at each look. The tests hold the published constants to 1.5e-3
/// with it.
const CELLS: usize = 160;

/// Φ to 1.5e-7 (Abramowitz and Stegun 7.1.26 for erf), fast enough for the recursion's
/// CELLS² evaluations per look.
fn phi_fast(x: f64) -> f64 {
    let z = x.abs() / std::f64::consts::SQRT_2;
    let t = 1.0 / (1.0 + 0.327_591_1 * z);
    let poly = t
        * (0.254_829_592
            + t * (-0.284_496_736
                + t * (1.421_413_741 + t * (-1.453_152_027 + t * 1.061_405_429))));
    let erf = 1.0 - poly * (-z * z).exp();
    if x >= 0.0 {
        0.5 * (1.0 + erf)
    } else {
        0.5 * (1.0 - erf)
    }
}

fn density_of(z: f64) -> f64 {
    (-0.5 * z * z).exp() / (2.0 * std::f64::consts::PI).sqrt()
}

/// The cells' midpoints and width over ±c·√I.
fn cells(c: f64, info: f64) -> (Vec<f64>, f64) {
    let half = c * info.sqrt();
    let h = 2.0 * half / CELLS as f64;
    (
        (0..CELLS).map(|j| -half + (j as f64 + 0.5) * h).collect(),
        h,
    )
}

/// The probability that S stays within ±c·√I_k at every look.
pub fn stay_probability(info: &[f64], c: f64) -> f64 {
    let Some(&first) = info.first() else {
        return 1.0;
    };
    // mass[j]: the probability of being in cell j at this look having stayed so far.
    let (mut mids, h) = cells(c, first);
    let sd = first.sqrt();
    let mut mass: Vec<f64> = mids
        .iter()
        .map(|&m| phi_fast((m + 0.5 * h) / sd) - phi_fast((m - 0.5 * h) / sd))
        .collect();
    let mut width = h;
    for pair in info.windows(2) {
        let step = (pair[1] - pair[0]).max(f64::MIN_POSITIVE).sqrt();
        let (next, h2) = cells(c, pair[1]);
        // The density at each midpoint, the mass spread evenly over its cell.
        let density: Vec<f64> = mass.iter().map(|m| m / width).collect();
        // With the density constant over each cell, the mass moving from cell [a, b] to
        // cell [a′, b′] is d·∫∫ φ_δ(t − s) ds dt = d·δ·(G((b′ − a)/δ) − G((a′ − a)/δ)
        // − G((b′ − b)/δ) + G((a′ − b)/δ)) with G(x) = x·Φ(x) + φ(x), Φ's antiderivative:
        // exact however narrow the increment is.
        // An increment much wider than the cells is integrated by the midpoint rule
        // instead, where G's four terms would cancel to a few digits.
        let g = |x: f64| x * phi_fast(x) + density_of(x);
        let wide = step > 4.0 * width.max(h2);
        mass = next
            .iter()
            .map(|&to| {
                let (a2, b2) = (to - 0.5 * h2, to + 0.5 * h2);
                mids.iter()
                    .zip(&density)
                    .map(|(&from, &d)| {
                        if wide {
                            return d * width * h2 * density_of((to - from) / step) / step;
                        }
                        let (a, b) = (from - 0.5 * width, from + 0.5 * width);
                        d * step
                            * (g((b2 - a) / step) - g((a2 - a) / step) - g((b2 - b) / step)
                                + g((a2 - b) / step))
                    })
                    .sum::<f64>()
                    .max(0.0)
            })
            .collect();
        mids = next;
        width = h2;
    }
    mass.iter().sum()
}

/// The constant c for which S leaves ±c·√I_k at some look of `info` with probability
/// `alpha` (two-sided), to 1e-4.
pub fn constant(info: &[f64], alpha: f64) -> f64 {
    // One look is the fixed-sample interval; more looks only widen it, and Bonferroni's
    // z of α/(2K) bounds it from above.
    let mut lo = normal_quantile(1.0 - alpha / 2.0);
    if info.len() <= 1 {
        return lo;
    }
    let mut hi = normal_quantile(1.0 - alpha / (2.0 * info.len() as f64));
    while hi - lo > 1e-4 {
        let mid = 0.5 * (lo + hi);
        if 1.0 - stay_probability(info, mid) > alpha {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Jennison and Turnbull (2000), Table 2.1, Pocock's constants for α = 0.05.
    #[test]
    fn equally_spaced_looks_give_pococks_published_constants() {
        for (k, want) in [
            (1, 1.960),
            (2, 2.178),
            (3, 2.289),
            (4, 2.361),
            (5, 2.413),
            (10, 2.555),
        ] {
            let info: Vec<f64> = (1..=k).map(|i| i as f64).collect();
            let got = constant(&info, 0.05);
            assert!((got - want).abs() < 1.5e-3, "K = {k}: {got} vs {want}");
        }
    }

    /// Looks whose information hardly grows are nearly one look: the constant falls to the
    /// fixed-sample 1.96 (a Brownian motion observed at I and I + ε).
    #[test]
    fn nearly_coincident_looks_are_nearly_one() {
        let c = constant(&[1.0, 1.0001], 0.05);
        assert!((c - 1.96).abs() < 0.01, "{c}");
        // Scaling every information time changes nothing.
        let a = constant(&[1.0, 2.0, 3.0], 0.05);
        let b = constant(&[10.0, 20.0, 30.0], 0.05);
        assert!((a - b).abs() < 2e-4, "{a} {b}");
    }
}
