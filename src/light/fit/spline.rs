//! The `spline` family: a curve through every reading of a plane.
//!
//! Each half is first fitted with `lobes` (the richest parametric shape); what it misses,
//! the residual at each reading, is then interpolated across the whole plane by a natural
//! cubic spline in the signed angle, with a knot at the normal where the residual is 0
//! (every model is 1 there). So the curve is the readings themselves, joined by the lobes
//! shape plus a smooth correction that is continuous with its first and second derivative
//! across γ = 0. Past the outermost reading the correction holds its last value and the
//! lobes shape carries the fall-off to 90°.
//!
//! A natural spline (second derivative 0 at both ends) is the interpolant of least
//! integrated squared curvature through the points; with the lobes fit taking the bulk of
//! the shape, what it bends is small.

/// The spline's value at γ (degrees, ≥ 0) of one half: knots increasing from 0, values
/// and second derivatives at them; the last value past the last knot.
pub fn eval(knots: &[f64], values: &[f64], curvature: &[f64], gamma_deg: f64) -> f64 {
    let n = knots.len().min(values.len()).min(curvature.len());
    if n == 0 {
        return 0.0;
    }
    if gamma_deg >= knots[n - 1] {
        return values[n - 1];
    }
    if gamma_deg <= knots[0] {
        return values[0];
    }
    let i = knots[..n]
        .partition_point(|&k| k <= gamma_deg)
        .clamp(1, n - 1)
        - 1;
    let (x0, x1) = (knots[i], knots[i + 1]);
    let h = x1 - x0;
    let (a, b) = (x1 - gamma_deg, gamma_deg - x0);
    let (m0, m1) = (curvature[i], curvature[i + 1]);
    m0 * a * a * a / (6.0 * h)
        + m1 * b * b * b / (6.0 * h)
        + (values[i] / h - m0 * h / 6.0) * a
        + (values[i + 1] / h - m1 * h / 6.0) * b
}

/// Second derivatives of the natural cubic spline through (x, y), x increasing: the
/// tridiagonal system of continuous first derivatives, solved by elimination.
pub fn natural_curvature(x: &[f64], y: &[f64]) -> Vec<f64> {
    let n = x.len();
    let mut m = vec![0.0; n];
    if n < 3 {
        return m;
    }
    // Rows 1 … n−2: h₀M₀ + 2(h₀+h₁)M₁ + h₁M₂ = 6(Δ₁ − Δ₀), with M₀ = M_{n−1} = 0.
    let k = n - 2;
    let mut diag = vec![0.0; k];
    let mut upper = vec![0.0; k];
    let mut rhs = vec![0.0; k];
    for j in 0..k {
        let (h0, h1) = (x[j + 1] - x[j], x[j + 2] - x[j + 1]);
        diag[j] = 2.0 * (h0 + h1);
        upper[j] = h1;
        rhs[j] = 6.0 * ((y[j + 2] - y[j + 1]) / h1 - (y[j + 1] - y[j]) / h0);
    }
    for j in 1..k {
        let lower = x[j + 1] - x[j];
        let w = lower / diag[j - 1];
        diag[j] -= w * upper[j - 1];
        rhs[j] -= w * rhs[j - 1];
    }
    for j in (0..k).rev() {
        let next = if j + 1 < k { m[j + 2] } else { 0.0 };
        m[j + 1] = (rhs[j] - upper[j] * next) / diag[j];
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_natural_spline_of_a_cubic_bend_matches_the_closed_form() {
        // Through (0,0), (1,1), (2,0): M₁ = 6·(−1 − 1)/(2·2) = −3, and s(0.5) = 11/16.
        let x = [0.0, 1.0, 2.0];
        let y = [0.0, 1.0, 0.0];
        let m = natural_curvature(&x, &y);
        assert_eq!(m, vec![0.0, -3.0, 0.0]);
        assert!((eval(&x, &y, &m, 0.5) - 11.0 / 16.0).abs() < 1e-15);
        // A straight line is its own spline, and past the end the last value holds.
        let y = [1.0, 3.0, 5.0, 7.0];
        let x = [0.0, 1.0, 2.0, 3.0];
        let m = natural_curvature(&x, &y);
        assert!(m.iter().all(|v| v.abs() < 1e-14), "{m:?}");
        assert!((eval(&x, &y, &m, 2.25) - 5.5).abs() < 1e-14);
        assert_eq!(eval(&x, &y, &m, 9.0), 7.0);
    }

    #[test]
    fn the_curve_passes_through_every_reading_and_is_smooth_at_the_normal() {
        use crate::light::fit::models::{fit_plane, LdcModel};
        let truth = |x: f64| {
            let r = x.to_radians();
            (-(r / 0.9).powi(2)).exp() * (1.0 - 0.05 * r.sin())
        };
        let g: Vec<f64> = (1..=4).map(|k| 20.0 * k as f64).collect();
        let yp: Vec<f64> = g.iter().map(|&g| truth(g)).collect();
        let yn: Vec<f64> = g.iter().map(|&g| truth(-g)).collect();
        let [p, q] = fit_plane(LdcModel::Spline, (&g, &yp), (&g, &yn));
        for (k, &gk) in g.iter().enumerate() {
            assert!((p.eval(gk) - yp[k]).abs() < 1e-12);
            assert!((q.eval(gk) - yn[k]).abs() < 1e-12);
        }
        assert!((p.eval(0.0) - 1.0).abs() < 1e-12 && (q.eval(0.0) - 1.0).abs() < 1e-12);
        // Both halves' corrections meet at 0 with one slope (in the signed angle): the
        // lobes shapes are flat there, so the slopes of f itself agree.
        let h = 1e-5;
        let right = (p.eval(h) - p.eval(0.0)) / h;
        let left = (q.eval(0.0) - q.eval(h)) / h;
        assert!((right - left).abs() < 1e-6, "{right} vs {left}");
    }
}
