//! A C-γ table: the relative luminance of a flat emitter as a function of direction.
//!
//! Conventions (those of the photometric C-plane system, CIE 121 / LM-63 "type C"):
//! γ is the angle from the emitter's normal (the side it emits into), 0°–90°; C is the
//! azimuth about the normal, measured from the emitter's `edge_u` (C = 0°) towards its
//! `edge_v` (C = 90°). A value is the luminance seen from that direction divided by the
//! luminance seen along the normal, so a Lambertian panel is 1 everywhere; the luminous
//! intensity of a panel of area A and normal luminance L₀ is I(C, γ) = L₀·A·f(C, γ)·cos γ.
//! Storing luminance rather than intensity keeps the table what a meter reads when it is
//! swung round the panel, which is how the paper measured its light's fall-off.

use serde::{Deserialize, Serialize};

/// Why a table is not a usable distribution.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CGammaError {
    #[error("{what} is empty")]
    Empty { what: &'static str },
    #[error("{what}[{index}] = {value}: angles must increase strictly and lie in {range}")]
    BadAngle {
        what: &'static str,
        index: usize,
        value: f64,
        range: &'static str,
    },
    #[error("gamma_deg must start at 0 and end at 90 (got {first}…{last})")]
    GammaSpan { first: f64, last: f64 },
    #[error("values has {got} C-planes, c_deg has {expected}")]
    PlaneCount { got: usize, expected: usize },
    #[error("values[{plane}] has {got} entries, gamma_deg has {expected}")]
    RowLength {
        plane: usize,
        got: usize,
        expected: usize,
    },
    #[error(
        "values[{plane}][{index}] (C {c_deg}°, γ {gamma_deg}°): relative luminance must be \
         finite, ≥ 0 and at most 1e6 times the normal's; got {value:.3e}"
    )]
    BadValue {
        plane: usize,
        index: usize,
        c_deg: f64,
        gamma_deg: f64,
        value: f64,
    },
    #[error("values[{plane}][0] = {value}: the luminance along the normal must be 1 (the table is relative to it)")]
    NotNormalised { plane: usize, value: f64 },
}

/// The largest relative luminance a table may hold. A panel's luminance at grazing angles
/// can exceed its normal luminance many times over (I/(I₀ cos γ) grows as cos γ → 0), but
/// not by a million: a value past that is a wrong unit or a broken file, and multiplied by
/// a luminance and an area it overflows what a renderer sums.
pub const MAX_RELATIVE: f64 = 1e6;

/// Relative luminance f(C, γ) on a grid of C-planes and γ angles.
///
/// One C-plane means a rotationally symmetric emitter. Between planes f is interpolated
/// linearly in C (periodically, across 360°), within a plane linearly in γ.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "CGammaFile", into = "CGammaFile")]
pub struct CGammaTable {
    c_deg: Vec<f64>,
    gamma_deg: Vec<f64>,
    /// values[c][γ]
    values: Vec<Vec<f64>>,
}

/// The table as written in JSON; validated into [`CGammaTable`].
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct CGammaFile {
    c_deg: Vec<f64>,
    gamma_deg: Vec<f64>,
    values: Vec<Vec<f64>>,
}

impl TryFrom<CGammaFile> for CGammaTable {
    type Error = CGammaError;
    fn try_from(f: CGammaFile) -> Result<Self, CGammaError> {
        CGammaTable::new(f.c_deg, f.gamma_deg, f.values)
    }
}

impl From<CGammaTable> for CGammaFile {
    fn from(t: CGammaTable) -> Self {
        CGammaFile {
            c_deg: t.c_deg,
            gamma_deg: t.gamma_deg,
            values: t.values,
        }
    }
}

/// Tolerance on f(·, 0) = 1: tables written with a few significant digits still load.
const NORMAL_TOLERANCE: f64 = 1e-6;

fn increasing(
    what: &'static str,
    a: &[f64],
    lo: f64,
    hi: f64,
    hi_open: bool,
    range: &'static str,
) -> Result<(), CGammaError> {
    if a.is_empty() {
        return Err(CGammaError::Empty { what });
    }
    for (i, &x) in a.iter().enumerate() {
        let above = if hi_open { x >= hi } else { x > hi };
        let not_increasing = i > 0 && x <= a[i - 1];
        if !x.is_finite() || x < lo || above || not_increasing {
            return Err(CGammaError::BadAngle {
                what,
                index: i,
                value: x,
                range,
            });
        }
    }
    Ok(())
}

impl CGammaTable {
    /// A validated table: C-planes strictly increasing in [0°, 360°), γ strictly increasing
    /// from 0° to 90°, one row per plane, values finite, in [0, [`MAX_RELATIVE`]] and 1
    /// along the normal.
    pub fn new(
        c_deg: Vec<f64>,
        gamma_deg: Vec<f64>,
        values: Vec<Vec<f64>>,
    ) -> Result<CGammaTable, CGammaError> {
        increasing("c_deg", &c_deg, 0.0, 360.0, true, "[0, 360)")?;
        increasing("gamma_deg", &gamma_deg, 0.0, 90.0, false, "[0, 90]")?;
        let (first, last) = (gamma_deg[0], gamma_deg[gamma_deg.len() - 1]);
        if first != 0.0 || last != 90.0 {
            return Err(CGammaError::GammaSpan { first, last });
        }
        if values.len() != c_deg.len() {
            return Err(CGammaError::PlaneCount {
                got: values.len(),
                expected: c_deg.len(),
            });
        }
        for (plane, row) in values.iter().enumerate() {
            if row.len() != gamma_deg.len() {
                return Err(CGammaError::RowLength {
                    plane,
                    got: row.len(),
                    expected: gamma_deg.len(),
                });
            }
            if let Some((index, &value)) = row
                .iter()
                .enumerate()
                .find(|(_, v)| !(v.is_finite() && (0.0..=MAX_RELATIVE).contains(*v)))
            {
                return Err(CGammaError::BadValue {
                    plane,
                    index,
                    c_deg: c_deg[plane],
                    gamma_deg: gamma_deg[index],
                    value,
                });
            }
            if (row[0] - 1.0).abs() > NORMAL_TOLERANCE {
                return Err(CGammaError::NotNormalised {
                    plane,
                    value: row[0],
                });
            }
        }
        Ok(CGammaTable {
            c_deg,
            gamma_deg,
            values,
        })
    }

    /// A rotationally symmetric table from one profile f(γ).
    pub fn symmetric(gamma_deg: Vec<f64>, values: Vec<f64>) -> Result<CGammaTable, CGammaError> {
        CGammaTable::new(vec![0.0], gamma_deg, vec![values])
    }

    pub fn c_deg(&self) -> &[f64] {
        &self.c_deg
    }

    pub fn gamma_deg(&self) -> &[f64] {
        &self.gamma_deg
    }

    /// values()[c][γ]
    pub fn values(&self) -> &[Vec<f64>] {
        &self.values
    }

    /// f at (C, γ) in degrees; C any real (taken modulo 360), γ clamped to [0, 90].
    pub fn at(&self, c_deg: f64, gamma_deg: f64) -> f64 {
        let g = gamma_deg.clamp(0.0, 90.0);
        let n = self.c_deg.len();
        if n == 1 {
            return self.along(0, g);
        }
        let c = c_deg.rem_euclid(360.0);
        // The plane at or below c, wrapping below the first plane to the last.
        let hi = self.c_deg.partition_point(|&x| x <= c);
        let (i0, i1) = if hi == 0 || hi == n {
            (n - 1, 0)
        } else {
            (hi - 1, hi)
        };
        let c0 = self.c_deg[i0];
        let span = (self.c_deg[i1] - c0).rem_euclid(360.0);
        let t = if span > 0.0 {
            (c - c0).rem_euclid(360.0) / span
        } else {
            0.0
        };
        (1.0 - t) * self.along(i0, g) + t * self.along(i1, g)
    }

    /// f for a unit direction given in the emitter's frame: x along `edge_u`, y along
    /// `edge_v`, z along the emitting normal. Directions behind the panel give 0.
    pub fn factor(&self, local: [f64; 3]) -> f64 {
        let [x, y, z] = local;
        if z.is_nan() || z <= 0.0 {
            return 0.0;
        }
        let gamma = x.hypot(y).atan2(z).to_degrees();
        let c = if x == 0.0 && y == 0.0 {
            0.0
        } else {
            y.atan2(x).to_degrees()
        };
        self.at(c, gamma)
    }

    fn along(&self, plane: usize, g: f64) -> f64 {
        let gs = &self.gamma_deg;
        let row = &self.values[plane];
        let k = gs.partition_point(|&x| x <= g);
        if k == 0 {
            return row[0];
        }
        if k == gs.len() {
            return row[gs.len() - 1];
        }
        let t = (g - gs[k - 1]) / (gs[k] - gs[k - 1]);
        (1.0 - t) * row[k - 1] + t * row[k]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn four_planes() -> CGammaTable {
        // f = 1 − a·γ/90 with a = 0.2, 0.4, 0.6, 0.8 in C = 0, 90, 180, 270.
        let g = vec![0.0, 45.0, 90.0];
        let rows = [0.2, 0.4, 0.6, 0.8]
            .iter()
            .map(|a| vec![1.0, 1.0 - a / 2.0, 1.0 - a])
            .collect();
        CGammaTable::new(vec![0.0, 90.0, 180.0, 270.0], g, rows).unwrap()
    }

    #[test]
    fn interpolates_linearly_in_gamma_and_c() {
        let t = four_planes();
        // In plane C = 0 at γ = 22.5: 1 − 0.2·0.25 = 0.95.
        assert!((t.at(0.0, 22.5) - 0.95).abs() < 1e-12);
        // Halfway between C = 0 (a = 0.2) and 90 (a = 0.4) at γ = 90: 1 − 0.3 = 0.7.
        assert!((t.at(45.0, 90.0) - 0.7).abs() < 1e-12);
        // Across the wrap, halfway between C = 270 (0.8) and 360 ≡ 0 (0.2): 1 − 0.5.
        assert!((t.at(315.0, 90.0) - 0.5).abs() < 1e-12);
        assert!((t.at(-45.0, 90.0) - 0.5).abs() < 1e-12);
    }

    #[test]
    fn local_direction_maps_to_c_and_gamma() {
        let t = four_planes();
        let s = std::f64::consts::FRAC_1_SQRT_2;
        // 45° towards +edge_v is C = 90, γ = 45: 1 − 0.4/2.
        assert!((t.factor([0.0, s, s]) - 0.8).abs() < 1e-12);
        // 45° towards −edge_u is C = 180: 1 − 0.6/2.
        assert!((t.factor([-s, 0.0, s]) - 0.7).abs() < 1e-12);
        assert_eq!(t.factor([0.0, 0.0, 1.0]), 1.0);
        assert_eq!(t.factor([0.0, 0.0, -1.0]), 0.0);
    }

    #[test]
    fn rejects_bad_tables() {
        let g = vec![0.0, 90.0];
        assert!(matches!(
            CGammaTable::symmetric(vec![0.0, 60.0], vec![1.0, 0.5]),
            Err(CGammaError::GammaSpan { .. })
        ));
        assert!(matches!(
            CGammaTable::symmetric(g.clone(), vec![0.0, 0.5]),
            Err(CGammaError::NotNormalised { .. })
        ));
        assert!(matches!(
            CGammaTable::symmetric(g.clone(), vec![1.0, -0.1]),
            Err(CGammaError::BadValue { .. })
        ));
        assert!(matches!(
            CGammaTable::symmetric(g.clone(), vec![1.0, f64::NAN]),
            Err(CGammaError::BadValue { .. })
        ));
        assert!(matches!(
            CGammaTable::new(vec![0.0, 0.0], g.clone(), vec![vec![1.0, 0.0]; 2]),
            Err(CGammaError::BadAngle { what: "c_deg", .. })
        ));
        assert!(matches!(
            CGammaTable::new(vec![360.0], g.clone(), vec![vec![1.0, 0.0]]),
            Err(CGammaError::BadAngle { what: "c_deg", .. })
        ));
        assert!(matches!(
            CGammaTable::new(vec![0.0], g, vec![]),
            Err(CGammaError::PlaneCount { .. })
        ));
    }

    #[test]
    fn json_round_trip_validates() {
        let t = four_planes();
        let s = serde_json::to_string(&t).unwrap();
        let back: CGammaTable = serde_json::from_str(&s).unwrap();
        assert_eq!(back, t);
        let bad = r#"{"c_deg":[0],"gamma_deg":[0,90],"values":[[2,1]]}"#;
        let e = serde_json::from_str::<CGammaTable>(bad).unwrap_err();
        assert!(e.to_string().contains("must be 1"), "{e}");
    }
}
