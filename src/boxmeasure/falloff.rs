//! The light's angular distribution from the fall-off readings: luminance of one tile seen
//! from signed angles in the horizontal and the vertical plane.
//!
//! Two forms are made from the same readings:
//! - a C-γ table of the measured points themselves (C = 0°, 90°, 180°, 270°: the four
//!   half-planes, γ at every measured angle), each value the reading divided by the
//!   normal luminance, linear between measured angles and extrapolated linearly from the
//!   last two angles out to γ = 90° (clamped to [0, the last value]); this is what the
//!   light files carry;
//! - the exponent m of cosᵐγ fitted to every off-normal point by least squares on
//!   ln f = m·ln cos γ (closed form: m = Σ ln f·ln cos γ / Σ (ln cos γ)²), the rotationally
//!   symmetric form the renderers read; its residual at each angle is reported.

use serde::{Deserialize, Serialize};

use super::plan::Plane;
use crate::light::{CGammaError, CGammaTable};

/// The mean luminance at each measured angle of one plane.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct PlaneReadings {
    pub plane: Plane,
    /// Signed angles, increasing.
    pub angles_deg: Vec<f64>,
    /// cd/m² at each angle.
    pub luminance: Vec<f64>,
}

/// One point's misfit of the cosᵐ curve.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Residual {
    pub plane: Plane,
    pub angle_deg: f64,
    /// Measured relative luminance.
    pub measured: f64,
    /// cosᵐγ.
    pub fitted: f64,
}

/// The distribution made from the readings.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LightDistribution {
    /// Normal luminance: the mean of both planes' 0° readings, cd/m².
    pub normal_luminance: f64,
    pub table: CGammaTable,
    pub cos_power: f64,
    pub residuals: Vec<Residual>,
    /// RMS of the residuals.
    pub rms: f64,
}

/// Readings that make no distribution.
#[derive(Debug, thiserror::Error)]
pub enum FalloffError {
    #[error(
        "the {0} plane has no reading at 0° (the normal, which the distribution is relative to)"
    )]
    NoNormal(&'static str),
    #[error("the {plane} plane's reading at {angle_deg}° is {value} cd/m²: luminance must be finite and > 0 on the normal, ≥ 0 elsewhere")]
    Bad {
        plane: &'static str,
        angle_deg: f64,
        value: f64,
    },
    #[error("the distribution table: {0}")]
    Table(#[from] CGammaError),
}

/// One half-plane's relative values on `gammas` (0 … 90): measured points on that side,
/// linear between them, the normal 1, extrapolated to 90°.
fn half_plane(points: &[(f64, f64)], gammas: &[f64]) -> Vec<f64> {
    // points: (γ, f) with γ ≥ 0 increasing, starting (0, 1).
    gammas
        .iter()
        .map(|&g| {
            let k = points.partition_point(|p| p.0 <= g);
            if k == points.len() {
                let n = points.len();
                if n < 2 {
                    return 1.0;
                }
                let ((ga, fa), (gb, fb)) = (points[n - 2], points[n - 1]);
                let slope = (fb - fa) / (gb - ga);
                (fb + slope * (g - gb)).clamp(0.0, fb)
            } else {
                let ((ga, fa), (gb, fb)) = (points[k - 1], points[k]);
                fa + (fb - fa) * (g - ga) / (gb - ga)
            }
        })
        .collect()
}

/// The distribution of `horizontal` and `vertical` readings.
pub fn distribution(
    horizontal: &PlaneReadings,
    vertical: &PlaneReadings,
) -> Result<LightDistribution, FalloffError> {
    for p in [horizontal, vertical] {
        for (&a, &l) in p.angles_deg.iter().zip(&p.luminance) {
            let ok = l.is_finite() && if a == 0.0 { l > 0.0 } else { l >= 0.0 };
            if !ok {
                return Err(FalloffError::Bad {
                    plane: p.plane.name(),
                    angle_deg: a,
                    value: l,
                });
            }
        }
    }
    let normal = |p: &PlaneReadings| {
        p.angles_deg
            .iter()
            .position(|&a| a == 0.0)
            .map(|i| p.luminance[i])
            .ok_or(FalloffError::NoNormal(p.plane.name()))
    };
    let l0 = 0.5 * (normal(horizontal)? + normal(vertical)?);
    let mut gammas: Vec<f64> = vec![0.0, 90.0];
    for p in [horizontal, vertical] {
        gammas.extend(p.angles_deg.iter().map(|a| a.abs()));
    }
    gammas.sort_by(f64::total_cmp);
    gammas.dedup();
    // Half-planes in C order 0, 90, 180, 270: (plane, side).
    let halves = [
        (horizontal, 1.0),
        (vertical, 1.0),
        (horizontal, -1.0),
        (vertical, -1.0),
    ];
    let mut values = Vec::new();
    let mut residuals = Vec::new();
    let (mut num, mut den) = (0.0, 0.0);
    for (p, side) in halves {
        let mut points: Vec<(f64, f64)> = vec![(0.0, 1.0)];
        for (&a, &l) in p.angles_deg.iter().zip(&p.luminance) {
            if a * side > 0.0 {
                points.push((a.abs(), l / l0));
            }
        }
        points.sort_by(|a, b| a.0.total_cmp(&b.0));
        for &(g, f) in &points[1..] {
            let lc = g.to_radians().cos().ln();
            if f > 0.0 {
                num += f.ln() * lc;
                den += lc * lc;
            }
        }
        values.push(half_plane(&points, &gammas));
    }
    let cos_power = if den > 0.0 { (num / den).max(0.0) } else { 0.0 };
    for p in [horizontal, vertical] {
        for (&a, &l) in p.angles_deg.iter().zip(&p.luminance) {
            residuals.push(Residual {
                plane: p.plane,
                angle_deg: a,
                measured: l / l0,
                fitted: a.to_radians().cos().powf(cos_power),
            });
        }
    }
    let rms = (residuals
        .iter()
        .map(|r| (r.measured - r.fitted).powi(2))
        .sum::<f64>()
        / residuals.len().max(1) as f64)
        .sqrt();
    let table = CGammaTable::new(vec![0.0, 90.0, 180.0, 270.0], gammas, values)?;
    Ok(LightDistribution {
        normal_luminance: l0,
        table,
        cos_power,
        residuals,
        rms,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plane(plane: Plane, f: impl Fn(f64) -> f64) -> PlaneReadings {
        let angles_deg: Vec<f64> = (-4..=4).map(|k| 20.0 * f64::from(k)).collect();
        PlaneReadings {
            plane,
            luminance: angles_deg.iter().map(|&a| 80.0 * f(a)).collect(),
            angles_deg,
        }
    }

    #[test]
    fn a_cos_power_light_gives_its_exponent_and_the_table_holds_the_points() {
        let cos = |a: f64, m: f64| a.to_radians().cos().powf(m);
        let d = distribution(
            &plane(Plane::Horizontal, |a| cos(a, 1.5)),
            &plane(Plane::Vertical, |a| cos(a, 1.5)),
        )
        .unwrap();
        assert!((d.cos_power - 1.5).abs() < 1e-12, "{}", d.cos_power);
        assert!(d.rms < 1e-12);
        assert_eq!(d.normal_luminance, 80.0);
        // A measured point, and halfway between 20° and 40° on the C = 270° side.
        assert!((d.table.at(0.0, 60.0) - cos(60.0, 1.5)).abs() < 1e-12);
        let mid = 0.5 * (cos(20.0, 1.5) + cos(40.0, 1.5));
        assert!((d.table.at(270.0, 30.0) - mid).abs() < 1e-12);
        // 90°: the 60°→80° line carried on, clamped at 0.
        let (f60, f80) = (cos(60.0, 1.5), cos(80.0, 1.5));
        let want = (f80 + (f80 - f60) / 2.0).max(0.0);
        assert!((d.table.at(90.0, 90.0) - want).abs() < 1e-12);
    }

    #[test]
    fn asymmetric_planes_stay_apart_and_bad_readings_are_named() {
        let h = plane(Plane::Horizontal, |a| if a > 0.0 { 0.5 } else { 1.0 });
        let v = plane(Plane::Vertical, |_| 1.0);
        let d = distribution(&h, &v).unwrap();
        assert_eq!(d.table.at(0.0, 40.0), 0.5);
        assert_eq!(d.table.at(180.0, 40.0), 1.0);
        let mut bad = v.clone();
        bad.luminance[4] = 0.0;
        let e = distribution(&h, &bad).unwrap_err().to_string();
        assert!(
            e.contains("vertical plane's reading at 0° is 0 cd/m²"),
            "{e}"
        );
    }
}
