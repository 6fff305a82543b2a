//! The `series` family: one plane in its signed angle x (positive in the plane's first
//! half, negative in the other),
//!
//! f(x) = cosⁿx · (1 + b₁ sin x + b₂ sin²x + b₃ sin³x + b₄ sin⁴x).
//!
//! The cos-power factor carries the fall-off towards the grazing angles (it is 0 at 90°
//! for n > 0, as a panel's luminance need not be but its intensity is); the polynomial in
//! sin x carries what makes the two sides differ: its odd terms give the slope at the
//! normal that a skewed luminaire has, the same seen from either side, and its even terms
//! bend both sides alike. f is smooth across x = 0 and 1 there.
//!
//! For a given n the coefficients are a linear least-squares problem, so the search runs
//! over n alone (grid, then golden section), as for `cos-power`.

use nalgebra::{DMatrix, DVector};

use super::search::{minimise_1d, MAX_EXPONENT};

/// Coefficients b₁ … b₄ of the polynomial in sin x.
pub const SERIES_TERMS: usize = 4;

/// f(γ) of one half, γ in degrees within [0, 90], coefficients in that half's own γ.
pub fn eval(n: f64, b: &[f64; SERIES_TERMS], gamma_deg: f64) -> f64 {
    let g = gamma_deg.to_radians();
    let (s, c) = (g.sin(), g.cos().max(0.0));
    let mut poly = 1.0;
    let mut sk = 1.0;
    for bk in b {
        sk *= s;
        poly += bk * sk;
    }
    c.powf(n) * poly
}

/// The least-squares fit to one plane's halves `pos` (x = γ) and `neg` (x = −γ), each
/// given as (angles in degrees, relative luminance): n and the coefficients in `pos`'s γ
/// (`neg`'s are [`mirrored`]).
pub fn fit(pos: (&[f64], &[f64]), neg: (&[f64], &[f64])) -> (f64, [f64; SERIES_TERMS]) {
    let x: Vec<f64> = pos
        .0
        .iter()
        .map(|g| g.to_radians())
        .chain(neg.0.iter().map(|g| -g.to_radians()))
        .collect();
    let y: Vec<f64> = pos.1.iter().chain(neg.1).copied().collect();
    let sin: Vec<f64> = x.iter().map(|v| v.sin()).collect();
    let cos: Vec<f64> = x.iter().map(|v| v.cos().max(0.0)).collect();
    let solve = |n: f64| -> (f64, [f64; SERIES_TERMS]) {
        let base: Vec<f64> = cos.iter().map(|c| c.powf(n)).collect();
        let a = DMatrix::from_fn(x.len(), SERIES_TERMS, |i, k| {
            base[i] * sin[i].powi(k as i32 + 1)
        });
        let r = DVector::from_iterator(y.len(), y.iter().zip(&base).map(|(y, b)| y - b));
        // SVD gives the minimum-norm coefficients when the angles cannot tell the terms
        // apart, instead of failing.
        let coef = a
            .clone()
            .svd(true, true)
            .solve(&r, 1e-12)
            .unwrap_or_else(|_| DVector::zeros(SERIES_TERMS));
        let sse = (&a * &coef - &r).norm_squared();
        let mut b = [0.0; SERIES_TERMS];
        for (k, v) in b.iter_mut().enumerate() {
            *v = coef[k];
        }
        (if sse.is_finite() { sse } else { f64::INFINITY }, b)
    };
    let n = minimise_1d(|n| solve(n).0, 0.0, MAX_EXPONENT, 400);
    (n, solve(n).1)
}

/// The coefficients of the plane's other half in its own γ: sin(−γ) = −sin γ, so the odd
/// terms change sign.
pub fn mirrored(b: &[f64; SERIES_TERMS]) -> [f64; SERIES_TERMS] {
    let mut m = *b;
    for v in m.iter_mut().step_by(2) {
        *v = -*v;
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    fn half(f: impl Fn(f64) -> f64, sign: f64) -> (Vec<f64>, Vec<f64>) {
        let g: Vec<f64> = (1..=4).map(|k| 20.0 * k as f64).collect();
        let y = g.iter().map(|&g| f(sign * g)).collect();
        (g, y)
    }

    #[test]
    fn a_skewed_cos_power_is_recovered_and_smooth_across_the_normal() {
        // cos^0.8 x · (1 + 0.1 sin x): a member of the family.
        let truth = |x: f64| {
            let r = x.to_radians();
            r.cos().powf(0.8) * (1.0 + 0.1 * r.sin())
        };
        let (gp, yp) = half(truth, 1.0);
        let (gn, yn) = half(truth, -1.0);
        let (n, b) = fit((&gp, &yp), (&gn, &yn));
        let (p, q) = (|g| eval(n, &b, g), |g| eval(n, &mirrored(&b), g));
        for x in [-70.0, -35.0, -5.0, 5.0, 25.0, 65.0] {
            let got = if x >= 0.0 { p(x) } else { q(-x) };
            assert!((got - truth(x)).abs() < 1e-6, "{x}: {got} vs {}", truth(x));
        }
        // The slope at the normal, 0.1 per radian, is the same from both sides.
        let h = 1e-4;
        let right = (p(h) - 1.0) / h.to_radians();
        let left = (1.0 - q(h)) / h.to_radians();
        assert!((right - 0.1).abs() < 1e-3 && (left - 0.1).abs() < 1e-3);
    }
}
