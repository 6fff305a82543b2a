//! Tone reproduction curves: drive value 0–1 → normalised channel output, where 0 is the
//! black-corrected output at drive 0 and 1 the output at full drive (paper Eq. 9's R′, G′, B′).
//! Every curve is monotone non-decreasing and is continued beyond 0–1 (linearly, or by the
//! same formula) so an inverse can tell how far outside the gamut a target lies.

use serde::{Deserialize, Serialize};

/// One channel's curve.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "kebab-case")]
pub enum Trc {
    /// `d^γ` (the paper used γ = 2.2); odd-symmetric below 0.
    Power { gamma: f64 },
    /// Interpolation of a measured ramp: `drive` strictly increasing from 0 to 1, `value`
    /// non-decreasing. Between two measured levels the curve is linear in
    /// `value^(1/exponent)`, so it passes through every measurement like the paper's
    /// piecewise-linear PLCC, but follows a display's power-law-like shape between them
    /// instead of cutting its corners: with 9 levels on a γ 2.2 channel, a straight line
    /// makes the output at drive 0.06 2.3 times the true one, which shows as ΔE*ab errors
    /// of several units in dark colours. `exponent` 1 is the straight-line PLCC (and the value
    /// read from profiles written before the exponent existed). Continued beyond the ends
    /// with the end segments' slopes in that domain.
    Table {
        drive: Vec<f64>,
        value: Vec<f64>,
        #[serde(default = "linear_exponent")]
        exponent: f64,
    },
    /// Gain-offset-gamma (Berns, "Methods for characterizing CRT displays", Displays 16(4),
    /// 1996): `max(gain·d + offset, 0)^γ + flare` (GOG has flare = 0).
    Gog {
        gain: f64,
        offset: f64,
        gamma: f64,
        flare: f64,
    },
}

impl Trc {
    /// Normalised output for a drive value.
    pub fn eval(&self, d: f64) -> f64 {
        match self {
            Trc::Power { gamma } => d.signum() * d.abs().powf(*gamma),
            Trc::Table {
                drive,
                value,
                exponent,
            } => spow(interpolate(drive, value, *exponent, d), *exponent),
            Trc::Gog {
                gain,
                offset,
                gamma,
                flare,
            } => {
                let base = gain * d + offset;
                if base > 0.0 {
                    base.powf(*gamma) + flare
                } else {
                    // Continue linearly below the cut-off so the inverse stays defined.
                    *flare + base * gamma * 1e-3
                }
            }
        }
    }

    /// Drive value giving normalised output `v`, continued beyond 0–1.
    pub fn inverse(&self, v: f64) -> f64 {
        match self {
            Trc::Power { gamma } => v.signum() * v.abs().powf(1.0 / gamma),
            Trc::Table {
                drive,
                value,
                exponent,
            } => interpolate_inverse(drive, value, *exponent, spow(v, 1.0 / exponent)),
            Trc::Gog {
                gain,
                offset,
                gamma,
                flare,
            } => {
                let u = v - flare;
                let base = if u > 0.0 {
                    u.powf(1.0 / gamma)
                } else {
                    u / (gamma * 1e-3)
                };
                (base - offset) / gain
            }
        }
    }

    /// Whether the curve's parameters describe a curve at all: a loaded profile can hold
    /// anything, and an empty or unordered table, a NaN or a zero gamma would make
    /// evaluation index out of bounds or answer NaN for every colour.
    pub fn check(&self) -> Result<(), String> {
        let finite = |name: &str, v: f64| {
            if v.is_finite() {
                Ok(())
            } else {
                Err(format!("{name} is {v}, not a finite number"))
            }
        };
        match self {
            Trc::Power { gamma } => {
                finite("gamma", *gamma)?;
                if *gamma <= 0.0 {
                    return Err(format!("gamma is {gamma}; it must be > 0"));
                }
            }
            Trc::Table {
                drive,
                value,
                exponent,
            } => {
                if drive.len() < 2 || drive.len() != value.len() {
                    return Err(format!(
                        "a table needs at least 2 drive levels and one value per level, found \
                         {} drive levels and {} values",
                        drive.len(),
                        value.len()
                    ));
                }
                finite("exponent", *exponent)?;
                if *exponent <= 0.0 {
                    return Err(format!("exponent is {exponent}; it must be > 0"));
                }
                for (&d, &v) in drive.iter().zip(value) {
                    finite("a drive level", d)?;
                    finite("a value", v)?;
                }
                if let Some(w) = drive.windows(2).find(|w| w[1] <= w[0]) {
                    return Err(format!(
                        "drive levels must increase, but {} follows {}",
                        w[1], w[0]
                    ));
                }
                if let Some(w) = value.windows(2).find(|w| w[1] < w[0]) {
                    return Err(format!(
                        "values must not decrease, but {} follows {}",
                        w[1], w[0]
                    ));
                }
            }
            Trc::Gog {
                gain,
                offset,
                gamma,
                flare,
            } => {
                for (name, v) in [
                    ("gain", *gain),
                    ("offset", *offset),
                    ("gamma", *gamma),
                    ("flare", *flare),
                ] {
                    finite(name, v)?;
                }
                if *gain <= 0.0 || *gamma <= 0.0 {
                    return Err(format!(
                        "gain ({gain}) and gamma ({gamma}) must be > 0 for a rising curve"
                    ));
                }
            }
        }
        Ok(())
    }

    /// A ramp table, made monotone by pool-adjacent-violators so measurement noise near
    /// black cannot make the curve fold back (which would give two drives for one output),
    /// interpolated in the domain of the ramp's least-squares power law.
    pub fn table_from_ramp(points: &[(f64, f64)]) -> Trc {
        let (drive, value) = isotonic(points);
        let exponent = fit_power_gamma(points);
        Trc::Table {
            drive,
            value,
            exponent,
        }
    }
}

/// A curve's inverse with its constants precomputed, for per-pixel use: a ramp table's
/// nodes are raised to 1/exponent once here instead of inside every binary search. Gives
/// the same values as [`Trc::inverse`]; also holds the curve's outputs at drive 0 and 1.
#[derive(Clone, Debug)]
pub struct FastInverse {
    curve: Trc,
    /// Table nodes as `value^(1/exponent)`; empty for the other curves.
    root: Vec<f64>,
    /// Output at drive 0 and at drive 1.
    pub range: (f64, f64),
}

impl Default for FastInverse {
    fn default() -> Self {
        FastInverse::new(&Trc::Power { gamma: 1.0 })
    }
}

impl FastInverse {
    pub fn new(curve: &Trc) -> FastInverse {
        let root = match curve {
            Trc::Table {
                value, exponent, ..
            } => value.iter().map(|&v| spow(v, 1.0 / exponent)).collect(),
            _ => Vec::new(),
        };
        FastInverse {
            curve: curve.clone(),
            root,
            range: (curve.eval(0.0), curve.eval(1.0)),
        }
    }

    pub fn inverse(&self, v: f64) -> f64 {
        match &self.curve {
            Trc::Table {
                drive, exponent, ..
            } => interpolate_inverse_root(drive, &self.root, spow(v, 1.0 / exponent)),
            other => other.inverse(v),
        }
    }
}

fn linear_exponent() -> f64 {
    1.0
}

/// Sign-preserving power, so values a little below black (noise) stay ordered.
fn spow(v: f64, e: f64) -> f64 {
    v.signum() * v.abs().powf(e)
}

/// Interpolates `y^(1/e)` linearly at `t`.
fn interpolate(x: &[f64], y: &[f64], e: f64, t: f64) -> f64 {
    let n = x.len();
    let i = match x.partition_point(|&v| v <= t) {
        0 => 0,
        k if k >= n => n - 2,
        k => k - 1,
    };
    let (x0, x1) = (x[i], x[i + 1]);
    let (y0, y1) = (spow(y[i], 1.0 / e), spow(y[i + 1], 1.0 / e));
    y0 + (y1 - y0) * (t - x0) / (x1 - x0)
}

/// The drive at which the interpolated `y^(1/e)` reaches `u`.
fn interpolate_inverse(x: &[f64], y: &[f64], e: f64, u: f64) -> f64 {
    let root: Vec<f64> = y.iter().map(|&w| spow(w, 1.0 / e)).collect();
    interpolate_inverse_root(x, &root, u)
}

/// The drive at which the straight lines through (x, root) reach `u`.
fn interpolate_inverse_root(x: &[f64], root: &[f64], u: f64) -> f64 {
    let n = root.len();
    // First segment whose end reaches u; flat segments resolve to their first drive.
    let i = match root.partition_point(|&w| w < u) {
        0 => 0,
        k if k >= n => n - 2,
        k => k - 1,
    };
    let (x0, x1, y0, y1) = (x[i], x[i + 1], root[i], root[i + 1]);
    if y1 == y0 {
        return if u <= y0 { x0 } else { x1 };
    }
    x0 + (x1 - x0) * (u - y0) / (y1 - y0)
}

/// Sorts by drive, averages repeated drives and fits the closest non-decreasing sequence in
/// least squares (pool-adjacent-violators).
fn isotonic(points: &[(f64, f64)]) -> (Vec<f64>, Vec<f64>) {
    let mut p: Vec<(f64, f64)> = points.to_vec();
    p.sort_by(|a, b| a.0.total_cmp(&b.0));
    // (drive, mean value, weight) blocks; repeated drives merge first.
    let mut drives: Vec<(f64, f64, f64)> = Vec::new();
    for (d, v) in p {
        match drives.last_mut() {
            Some(last) if (last.0 - d).abs() < 1e-12 => {
                last.1 = (last.1 * last.2 + v) / (last.2 + 1.0);
                last.2 += 1.0;
            }
            _ => drives.push((d, v, 1.0)),
        }
    }
    // blocks: (first index, last index, mean, weight)
    let mut blocks: Vec<(usize, usize, f64, f64)> = Vec::new();
    for (i, &(_, v, w)) in drives.iter().enumerate() {
        blocks.push((i, i, v, w));
        while blocks.len() > 1 {
            let b = blocks[blocks.len() - 1];
            let a = blocks[blocks.len() - 2];
            if a.2 <= b.2 {
                break;
            }
            let w = a.3 + b.3;
            blocks.truncate(blocks.len() - 2);
            blocks.push((a.0, b.1, (a.2 * a.3 + b.2 * b.3) / w, w));
        }
    }
    let mut value = vec![0.0; drives.len()];
    for (a, b, m, _) in blocks {
        value[a..=b].iter_mut().for_each(|v| *v = m);
    }
    (drives.iter().map(|d| d.0).collect(), value)
}

/// Least-squares exponent of `d^γ` through ramp points (golden-section search on ln γ;
/// the sum of squares is unimodal in γ for a monotone ramp).
pub fn fit_power_gamma(points: &[(f64, f64)]) -> f64 {
    let cost = |g: f64| -> f64 { points.iter().map(|&(d, s)| (d.powf(g) - s).powi(2)).sum() };
    let (mut a, mut b) = (0.1f64.ln(), 10.0f64.ln());
    let phi = (5f64.sqrt() - 1.0) / 2.0;
    let mut x1 = b - phi * (b - a);
    let mut x2 = a + phi * (b - a);
    let (mut f1, mut f2) = (cost(x1.exp()), cost(x2.exp()));
    for _ in 0..100 {
        if f1 <= f2 {
            b = x2;
            x2 = x1;
            f2 = f1;
            x1 = b - phi * (b - a);
            f1 = cost(x1.exp());
        } else {
            a = x1;
            x1 = x2;
            f1 = f2;
            x2 = a + phi * (b - a);
            f2 = cost(x2.exp());
        }
    }
    (0.5 * (a + b)).exp()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn power_and_inverse() {
        let t = Trc::Power { gamma: 2.2 };
        assert!((t.eval(0.5) - 0.5f64.powf(2.2)).abs() < 1e-15);
        assert!((t.inverse(t.eval(0.3)) - 0.3).abs() < 1e-12);
        assert!((t.inverse(-0.25) + 0.25f64.powf(1.0 / 2.2)).abs() < 1e-12);
    }

    #[test]
    fn table_interpolates_extrapolates_and_inverts() {
        let t = Trc::Table {
            drive: vec![0.0, 0.5, 1.0],
            value: vec![0.0, 0.2, 1.0],
            exponent: 1.0,
        };
        assert!((t.eval(0.25) - 0.1).abs() < 1e-12);
        assert!((t.eval(0.75) - 0.6).abs() < 1e-12);
        // slope of the last segment 1.6 continues beyond 1
        assert!((t.eval(1.5) - 1.8).abs() < 1e-12);
        assert!((t.inverse(0.6) - 0.75).abs() < 1e-12);
        assert!((t.inverse(1.8) - 1.5).abs() < 1e-12);
        assert!((t.inverse(-0.1) + 0.25).abs() < 1e-12);
    }

    /// On a power-law channel the table is exact between its levels, and it still passes
    /// through every level; a straight line is not (hand check: from (0.125, 0.01037) to
    /// (0.25, 0.04736) it gives 0.0289 at 0.1875, where the channel gives 0.0252).
    #[test]
    fn table_follows_a_power_law_between_levels() {
        let levels: Vec<(f64, f64)> = (0..=8)
            .map(|i| {
                let d = i as f64 / 8.0;
                (d, d.powf(2.2))
            })
            .collect();
        let t = Trc::table_from_ramp(&levels);
        for &(d, v) in &levels {
            assert!((t.eval(d) - v).abs() < 1e-12, "{d}");
        }
        for d in [0.03, 0.1875, 0.6, 0.97] {
            let want = f64::powf(d, 2.2);
            assert!((t.eval(d) - want).abs() < 1e-6 * want.max(1e-3), "{d}");
            assert!((t.inverse(want) - d).abs() < 1e-6, "{d}");
        }
        let straight = Trc::Table {
            drive: levels.iter().map(|p| p.0).collect(),
            value: levels.iter().map(|p| p.1).collect(),
            exponent: 1.0,
        };
        let mid = (0.125f64.powf(2.2) + 0.25f64.powf(2.2)) / 2.0;
        assert!((straight.eval(0.1875) - mid).abs() < 1e-12);
        assert!((mid - 0.02887).abs() < 1e-4 && (0.1875f64.powf(2.2) - 0.02516).abs() < 1e-4);
    }

    #[test]
    fn isotonic_pools_violators_and_averages_repeats() {
        let (d, v) = isotonic(&[(0.0, 0.0), (0.2, 0.1), (0.1, 0.3), (0.5, 0.5), (0.5, 0.7)]);
        assert_eq!(d, vec![0.0, 0.1, 0.2, 0.5]);
        // 0.3 then 0.1 pool to 0.2; the two 0.5 readings average to 0.6
        assert_eq!(v, vec![0.0, 0.2, 0.2, 0.6]);
    }

    #[test]
    fn gog_round_trip() {
        let t = Trc::Gog {
            gain: 0.95,
            offset: 0.05,
            gamma: 2.4,
            flare: 0.0,
        };
        assert!((t.eval(1.0) - 1.0).abs() < 1e-12);
        for d in [0.0, 0.1, 0.7, 1.0, 1.2] {
            assert!((t.inverse(t.eval(d)) - d).abs() < 1e-10, "{d}");
        }
    }

    #[test]
    fn fast_inverse_matches_the_curve() {
        let ramp: Vec<(f64, f64)> = (0..=8)
            .map(|i| {
                let d = i as f64 / 8.0;
                (d, d.powf(2.3) + 0.002 * (d * 9.0).sin())
            })
            .collect();
        let curves = [
            Trc::table_from_ramp(&ramp),
            Trc::Power { gamma: 2.2 },
            Trc::Gog {
                gain: 1.1,
                offset: -0.1,
                gamma: 2.4,
                flare: 0.01,
            },
        ];
        for t in &curves {
            let f = FastInverse::new(t);
            assert_eq!(f.range, (t.eval(0.0), t.eval(1.0)));
            for i in -20..=140 {
                let v = i as f64 / 100.0;
                assert_eq!(f.inverse(v), t.inverse(v), "{t:?} at {v}");
            }
        }
    }
}
