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
    /// Piecewise-linear interpolation of a measured ramp: `drive` strictly increasing from 0 to
    /// 1, `value` non-decreasing; continued linearly with the end segments' slopes.
    Table { drive: Vec<f64>, value: Vec<f64> },
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
            Trc::Table { drive, value } => interpolate(drive, value, d),
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
            Trc::Table { drive, value } => interpolate_inverse(drive, value, v),
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

    /// A ramp table, made monotone by pool-adjacent-violators so measurement noise near
    /// black cannot make the curve fold back (which would give two drives for one output).
    pub fn table_from_ramp(points: &[(f64, f64)]) -> Trc {
        let (drive, value) = isotonic(points);
        Trc::Table { drive, value }
    }
}

fn interpolate(x: &[f64], y: &[f64], t: f64) -> f64 {
    let n = x.len();
    let i = match x.partition_point(|&v| v <= t) {
        0 => 0,
        k if k >= n => n - 2,
        k => k - 1,
    };
    let (x0, x1, y0, y1) = (x[i], x[i + 1], y[i], y[i + 1]);
    y0 + (y1 - y0) * (t - x0) / (x1 - x0)
}

fn interpolate_inverse(x: &[f64], y: &[f64], v: f64) -> f64 {
    let n = y.len();
    // First segment whose end reaches v; flat segments resolve to their first drive.
    let i = match y.partition_point(|&w| w < v) {
        0 => 0,
        k if k >= n => n - 2,
        k => k - 1,
    };
    let (x0, x1, y0, y1) = (x[i], x[i + 1], y[i], y[i + 1]);
    if y1 == y0 {
        return if v <= y0 { x0 } else { x1 };
    }
    x0 + (x1 - x0) * (v - y0) / (y1 - y0)
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
        let t = Trc::table_from_ramp(&[(0.0, 0.0), (0.5, 0.2), (1.0, 1.0)]);
        assert!((t.eval(0.25) - 0.1).abs() < 1e-12);
        assert!((t.eval(0.75) - 0.6).abs() < 1e-12);
        // slope of the last segment 1.6 continues beyond 1
        assert!((t.eval(1.5) - 1.8).abs() < 1e-12);
        assert!((t.inverse(0.6) - 0.75).abs() < 1e-12);
        assert!((t.inverse(1.8) - 1.5).abs() < 1e-12);
        assert!((t.inverse(-0.1) + 0.25).abs() < 1e-12);
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
}
