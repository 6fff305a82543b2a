//! The fall-off models, f(γ) with f(0) = 1, and their least-squares fits.
//!
//! Every model is 1 along the normal by construction, so the normal reading only sets the
//! scale (the normal luminance) and the fit uses the off-normal angles alone. Residuals are
//! in relative luminance (reading / normal luminance − model).
//!
//! The parametric families (`lambertian`, `cos-power`, `cos-poly`, `lobes`) fit each
//! half-plane on its own: each is a function of cos γ, flat at the normal. A real luminaire
//! whose two sides differ in shape (a diffuser over an off-centre LED array) is not: its
//! luminance has a slope at the normal, the same seen from either side. The two plane
//! families fit a whole plane in the signed angle, so they are smooth across γ = 0:
//! `series` ([`super::series`]) and `spline` ([`super::spline`]). Either is stored as the
//! two halves' parameters, each half in its own γ ≥ 0, so the table and the chart evaluate
//! every model the same way.

use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

use super::search::{minimise_1d, nelder_mead, MAX_EXPONENT};
use super::series::{self, SERIES_TERMS};
use super::spline;

/// A family of fall-off curves.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum LdcModel {
    /// f = 1: the luminance does not depend on the direction.
    Lambertian,
    /// f = cosⁿγ.
    CosPower,
    /// f = a₀ + a₁·cos γ + a₂·cos²γ with a₀ + a₁ + a₂ = 1 (two free coefficients).
    CosPoly,
    /// f = a·cosⁿγ + (1 − a)·cosᵐγ, 0 ≤ a ≤ 1, n ≤ m: a broad and a narrow lobe.
    Lobes,
    /// Per plane, in the signed angle x: f = cosⁿx·(1 + b₁ sin x + … + b₄ sin⁴x).
    Series,
    /// Per plane: the lobes fit of each half plus a natural cubic spline in the signed
    /// angle through its residuals, so the curve passes through every reading.
    Spline,
}

impl LdcModel {
    /// The parametric families first, then the plane families.
    pub const ALL: [LdcModel; 6] = [
        LdcModel::Lambertian,
        LdcModel::CosPower,
        LdcModel::CosPoly,
        LdcModel::Lobes,
        LdcModel::Series,
        LdcModel::Spline,
    ];

    pub fn name(self) -> &'static str {
        match self {
            LdcModel::Lambertian => "lambertian",
            LdcModel::CosPower => "cos-power",
            LdcModel::CosPoly => "cos-poly",
            LdcModel::Lobes => "lobes",
            LdcModel::Series => "series",
            LdcModel::Spline => "spline",
        }
    }

    /// Whether one fit covers a whole plane (both halves, smooth across γ = 0) rather than
    /// each half-plane on its own.
    pub fn per_plane(self) -> bool {
        matches!(self, LdcModel::Series | LdcModel::Spline)
    }

    /// The fewest angles off the normal a fit needs: in each half-plane, and in each plane
    /// (both halves together). (Its residuals need one in each half-plane.)
    pub fn min_angles(self) -> (usize, usize) {
        match self {
            LdcModel::Lambertian => (0, 0),
            LdcModel::CosPower => (1, 2),
            LdcModel::CosPoly => (2, 4),
            LdcModel::Lobes => (3, 6),
            // Five coefficients per plane; a half with one angle would be extrapolated
            // from the other side.
            LdcModel::Series => (2, SERIES_TERMS + 1),
            // The lobes fit of each half is the spline's base.
            LdcModel::Spline => (3, 6),
        }
    }

    /// Free parameters of one plane fitted to `angles` readings off the normal: the
    /// measure of size by which `auto` prefers the smaller of two models that predict as
    /// well. An interpolant has one per reading besides its base.
    pub fn parameters(self, angles: usize) -> usize {
        match self {
            LdcModel::Lambertian => 0,
            LdcModel::CosPower => 2,
            LdcModel::CosPoly => 4,
            LdcModel::Series => SERIES_TERMS + 1,
            LdcModel::Lobes => 6,
            LdcModel::Spline => 6 + angles,
        }
    }
}

impl std::fmt::Display for LdcModel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

impl std::str::FromStr for LdcModel {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let t = s.trim().to_ascii_lowercase();
        LdcModel::ALL
            .into_iter()
            .find(|m| m.name() == t)
            .ok_or_else(|| {
                format!("unknown light distribution model '{s}': expected lambertian, cos-power, cos-poly, lobes, series or spline")
            })
    }
}

/// The fitted parameters of one half-plane.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "model", rename_all = "kebab-case")]
pub enum Params {
    Lambertian,
    CosPower {
        n: f64,
    },
    /// Coefficients of 1, cos γ, cos²γ.
    CosPoly {
        coeffs: [f64; 3],
    },
    Lobes {
        a: f64,
        n: f64,
        m: f64,
    },
    /// cosⁿγ·(1 + Σ b_k sinᵏγ) in this half's own γ ≥ 0 (the other half of the plane has
    /// the same n and the odd coefficients negated: sin(−γ) = −sin γ).
    Series {
        n: f64,
        b: [f64; SERIES_TERMS],
    },
    /// The lobes curve (a, n, m) plus a cubic spline through (knot, residual) with the
    /// given second derivatives (per degree²) at the knots; the first knot is 0°. Past the
    /// last knot the spline holds its last value.
    Spline {
        a: f64,
        n: f64,
        m: f64,
        knots_deg: Vec<f64>,
        residuals: Vec<f64>,
        curvature: Vec<f64>,
    },
}

impl Params {
    pub fn model(&self) -> LdcModel {
        match self {
            Params::Lambertian => LdcModel::Lambertian,
            Params::CosPower { .. } => LdcModel::CosPower,
            Params::CosPoly { .. } => LdcModel::CosPoly,
            Params::Lobes { .. } => LdcModel::Lobes,
            Params::Series { .. } => LdcModel::Series,
            Params::Spline { .. } => LdcModel::Spline,
        }
    }

    /// f(γ), γ in degrees within [0, 90]; may be negative for a polynomial extrapolated
    /// past the data (the table clamps it to 0).
    pub fn eval(&self, gamma_deg: f64) -> f64 {
        let c = gamma_deg.to_radians().cos().max(0.0);
        match self {
            Params::Lambertian => 1.0,
            Params::CosPower { n } => c.powf(*n),
            Params::CosPoly {
                coeffs: [a0, a1, a2],
            } => a0 + a1 * c + a2 * c * c,
            Params::Lobes { a, n, m } => a * c.powf(*n) + (1.0 - a) * c.powf(*m),
            Params::Series { n, b } => series::eval(*n, b, gamma_deg),
            Params::Spline {
                a,
                n,
                m,
                knots_deg,
                residuals,
                curvature,
            } => {
                a * c.powf(*n)
                    + (1.0 - a) * c.powf(*m)
                    + spline::eval(knots_deg, residuals, curvature, gamma_deg)
            }
        }
    }

    /// The parameters in words, for tables: `n=1.70`, `a=0.60 n=1.00 m=8.00`.
    pub fn describe(&self) -> String {
        match *self {
            Params::Lambertian => "-".into(),
            Params::CosPower { n } => format!("n={n:.3}"),
            Params::CosPoly {
                coeffs: [a0, a1, a2],
            } => {
                format!("a0={a0:.3} a1={a1:.3} a2={a2:.3}")
            }
            Params::Lobes { a, n, m } => format!("a={a:.3} n={n:.3} m={m:.3}"),
            Params::Series { n, b } => format!(
                "n={n:.3} b={}",
                b.iter()
                    .map(|v| format!("{v:+.3}"))
                    .collect::<Vec<_>>()
                    .join(",")
            ),
            Params::Spline {
                a,
                n,
                m,
                ref residuals,
                ..
            } => {
                let worst = residuals.iter().fold(0.0f64, |w, r| w.max(r.abs()));
                format!(
                    "lobes a={a:.3} n={n:.3} m={m:.3} + spline through {} residuals (largest {worst:.4})",
                    residuals.len() - 1
                )
            }
        }
    }
}

/// One half-plane's points: γ ≥ 0 in degrees, increasing, and relative luminance.
pub type HalfPoints<'a> = (&'a [f64], &'a [f64]);

/// Least-squares fit of `model` to one plane: `pos` and `neg` are its two halves (each in
/// its own γ ≥ 0); returns their parameters in that order. The caller guarantees
/// [`LdcModel::min_angles`].
pub fn fit_plane(model: LdcModel, pos: HalfPoints, neg: HalfPoints) -> [Params; 2] {
    match model {
        LdcModel::Series => {
            let (n, b) = series::fit(pos, neg);
            let mirrored = series::mirrored(&b);
            [Params::Series { n, b }, Params::Series { n, b: mirrored }]
        }
        LdcModel::Spline => fit_spline(pos, neg),
        _ => [fit_half(model, pos.0, pos.1), fit_half(model, neg.0, neg.1)],
    }
}

/// Least-squares fit of a half-plane `model` to points (γ in degrees, relative
/// luminance). The caller guarantees [`LdcModel::min_angles`]; the plane families are
/// fitted by [`fit_plane`] (given here, they see this half mirrored onto the other).
pub fn fit_half(model: LdcModel, gamma_deg: &[f64], y: &[f64]) -> Params {
    let c: Vec<f64> = gamma_deg.iter().map(|g| g.to_radians().cos()).collect();
    match model {
        LdcModel::Series | LdcModel::Spline => {
            fit_plane(model, (gamma_deg, y), (gamma_deg, y))[0].clone()
        }
        LdcModel::Lambertian => Params::Lambertian,
        LdcModel::CosPower => {
            let sse = |n: f64| sse(&c, y, |ci| ci.powf(n));
            Params::CosPower {
                n: minimise_1d(sse, 0.0, MAX_EXPONENT, 2000),
            }
        }
        LdcModel::CosPoly => fit_cos_poly(&c, y),
        LdcModel::Lobes => fit_lobes(&c, y),
    }
}

/// The `spline` fit (see [`super::spline`]) to one plane's halves `pos` (signed angle γ)
/// and `neg` (−γ); each half's parameters, `pos` first.
fn fit_spline(pos: HalfPoints, neg: HalfPoints) -> [Params; 2] {
    let base = [
        fit_half(LdcModel::Lobes, pos.0, pos.1),
        fit_half(LdcModel::Lobes, neg.0, neg.1),
    ];
    let residual = |p: &Params, g: &[f64], y: &[f64]| -> Vec<f64> {
        g.iter().zip(y).map(|(&g, &y)| y - p.eval(g)).collect()
    };
    let rp = residual(&base[0], pos.0, pos.1);
    let rn = residual(&base[1], neg.0, neg.1);
    // Knots across the plane: the negative half mirrored, the normal, the positive half.
    let mut x: Vec<f64> = neg.0.iter().rev().map(|g| -g).collect();
    let mut y: Vec<f64> = rn.iter().rev().copied().collect();
    x.push(0.0);
    y.push(0.0);
    x.extend_from_slice(pos.0);
    y.extend_from_slice(&rp);
    let m = spline::natural_curvature(&x, &y);
    let zero = neg.0.len();
    let half = |base: &Params, g: &[f64], r: &[f64], curv: Vec<f64>| -> Params {
        let Params::Lobes { a, n, m } = *base else {
            unreachable!("the base is a lobes fit")
        };
        let mut knots_deg = vec![0.0];
        knots_deg.extend_from_slice(g);
        let mut residuals = vec![0.0];
        residuals.extend_from_slice(r);
        Params::Spline {
            a,
            n,
            m,
            knots_deg,
            residuals,
            curvature: curv,
        }
    };
    let curv_pos: Vec<f64> = m[zero..].to_vec();
    let curv_neg: Vec<f64> = m[..=zero].iter().rev().copied().collect();
    [
        half(&base[0], pos.0, &rp, curv_pos),
        half(&base[1], neg.0, &rn, curv_neg),
    ]
}

fn sse(c: &[f64], y: &[f64], f: impl Fn(f64) -> f64) -> f64 {
    c.iter().zip(y).map(|(&ci, &yi)| (f(ci) - yi).powi(2)).sum()
}

/// y − 1 = a₁(c − 1) + a₂(c² − 1) is linear in (a₁, a₂); a₀ = 1 − a₁ − a₂.
fn fit_cos_poly(c: &[f64], y: &[f64]) -> Params {
    let a = DMatrix::from_fn(c.len(), 2, |i, j| c[i].powi(j as i32 + 1) - 1.0);
    let b = DVector::from_iterator(y.len(), y.iter().map(|v| v - 1.0));
    // SVD gives the minimum-norm solution when the points cannot tell the two terms apart
    // (all at one angle), instead of failing.
    let x = a
        .svd(true, true)
        .solve(&b, 1e-12)
        .unwrap_or_else(|_| DVector::zeros(2));
    let (a1, a2) = (x[0], x[1]);
    Params::CosPoly {
        coeffs: [1.0 - a1 - a2, a1, a2],
    }
}

/// For fixed exponents the best weight is a linear least-squares problem
/// (y − cᵐ = a·(cⁿ − cᵐ)), so the search runs over (n, m) only: a grid, then Nelder–Mead.
fn fit_lobes(c: &[f64], y: &[f64]) -> Params {
    // The best weight and the sum of squares for the powers cⁿ and cᵐ at the points.
    let weight_and_sse = |pn: &[f64], pm: &[f64]| -> (f64, f64) {
        let (mut uu, mut ur) = (0.0, 0.0);
        for ((&p, &q), &yi) in pn.iter().zip(pm).zip(y) {
            uu += (p - q).powi(2);
            ur += (p - q) * (yi - q);
        }
        let a = if uu < 1e-300 {
            1.0
        } else {
            (ur / uu).clamp(0.0, 1.0)
        };
        let sse = pn
            .iter()
            .zip(pm)
            .zip(y)
            .map(|((&p, &q), &yi)| (a * p + (1.0 - a) * q - yi).powi(2))
            .sum();
        (a, sse)
    };
    let powers = |e: f64| -> Vec<f64> { c.iter().map(|ci| ci.powf(e)).collect() };
    let cost = |p: [f64; 2]| -> f64 {
        let n = p[0].clamp(0.0, MAX_EXPONENT);
        let m = p[1].clamp(0.0, MAX_EXPONENT);
        weight_and_sse(&powers(n), &powers(m)).1
    };
    // Exponents spaced quadratically: fine where panel lights live (0…10), coarse above.
    // Their powers are computed once for the whole grid.
    const K: usize = 60;
    let grid: Vec<f64> = (0..=K)
        .map(|k| MAX_EXPONENT * (k as f64 / K as f64).powi(2))
        .collect();
    let table: Vec<Vec<f64>> = grid.iter().map(|&e| powers(e)).collect();
    let mut best = ([0.0, 0.0], f64::INFINITY);
    for i in 0..grid.len() {
        for j in i..grid.len() {
            let v = weight_and_sse(&table[i], &table[j]).1;
            if v < best.1 {
                best = ([grid[i], grid[j]], v);
            }
        }
    }
    let step = (MAX_EXPONENT / (K * K) as f64)
        .max(best.0[1] * 0.1)
        .max(0.05);
    let p = nelder_mead(cost, best.0, step, 2000);
    let (mut n, mut m) = (p[0].clamp(0.0, MAX_EXPONENT), p[1].clamp(0.0, MAX_EXPONENT));
    if n > m {
        std::mem::swap(&mut n, &mut m);
    }
    let a = weight_and_sse(&powers(n), &powers(m)).0;
    Params::Lobes { a, n, m }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(f: impl Fn(f64) -> f64) -> (Vec<f64>, Vec<f64>) {
        let g: Vec<f64> = (1..=7).map(|k| 10.0 * k as f64).collect();
        let y = g.iter().map(|&x| f(x)).collect();
        (g, y)
    }

    fn cos(g: f64) -> f64 {
        g.to_radians().cos()
    }

    #[test]
    fn cos_power_recovers_its_exponent() {
        let (g, y) = sample(|x| cos(x).powf(1.7));
        let Params::CosPower { n } = fit_half(LdcModel::CosPower, &g, &y) else {
            panic!("wrong model")
        };
        assert!((n - 1.7).abs() < 1e-6, "{n}");
    }

    #[test]
    fn cos_poly_recovers_its_coefficients() {
        // 0.2 + 0.5c + 0.3c²: coefficients sum to 1.
        let (g, y) = sample(|x| 0.2 + 0.5 * cos(x) + 0.3 * cos(x).powi(2));
        let Params::CosPoly { coeffs } = fit_half(LdcModel::CosPoly, &g, &y) else {
            panic!("wrong model")
        };
        for (got, want) in coeffs.iter().zip([0.2, 0.5, 0.3]) {
            assert!((got - want).abs() < 1e-9, "{coeffs:?}");
        }
    }

    #[test]
    fn lobes_recover_a_mix() {
        let (g, y) = sample(|x| 0.6 * cos(x) + 0.4 * cos(x).powi(8));
        let p = fit_half(LdcModel::Lobes, &g, &y);
        for x in [5.0, 25.0, 45.0, 65.0, 80.0] {
            let want = 0.6 * cos(x) + 0.4 * cos(x).powi(8);
            assert!(
                (p.eval(x) - want).abs() < 1e-4 * want.max(0.01),
                "{p:?} at {x}"
            );
        }
    }

    #[test]
    fn model_names_round_trip() {
        for m in LdcModel::ALL {
            assert_eq!(m.name().parse::<LdcModel>().unwrap(), m);
        }
        assert!("gauss".parse::<LdcModel>().is_err());
    }
}
