//! Propagating the readings' uncertainty to ΔE*ab and ΔE00: by Monte Carlo (the default)
//! and by linearisation (first-order, for comparison).
//!
//! Both start from the same model: each reading's X, Y, Z are independent normals about
//! the mean with the reading's standard uncertainty, and its CIELAB coordinates get an
//! extra independent normal term per axis (a renderer's ΔE bound, a display model's
//! verification error). The white is taken as exact: an error in it moves both readings'
//! CIELAB alike, so ΔE changes only in second order.
//!
//! Monte Carlo draws `draws` samples per patch from the workspace's seeded generator (the
//! seed is mixed with the patch number, so a patch's interval does not depend on the
//! others) and takes the 2.5th and 97.5th percentiles: this stays right near ΔE = 0, where
//! ΔE is not differentiable and the linearised interval (ΔE ± 1.96σ) is wrong.

use metamer_drivers::noise::SplitMix64;
use serde::{Deserialize, Serialize};

use crate::color::{delta_e2000, delta_e76, Lab, Xyz};

/// How the intervals are computed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Propagation {
    /// Percentiles of Monte Carlo draws.
    MonteCarlo { draws: usize, seed: u64 },
    /// ΔE ± 1.96 σ with σ from central differences.
    Linear,
}

impl Default for Propagation {
    fn default() -> Self {
        Propagation::MonteCarlo {
            draws: 4000,
            seed: 1,
        }
    }
}

impl Propagation {
    pub fn describe(self) -> String {
        match self {
            Propagation::MonteCarlo { draws, seed } => format!(
                "Monte Carlo: {draws} draws per patch (seed {seed}), 2.5th–97.5th percentiles"
            ),
            Propagation::Linear => {
                "linearisation: ΔE ± 1.96 σ, σ by central differences".to_string()
            }
        }
    }
}

/// One side of a comparison with its uncertainty.
#[derive(Clone, Debug, PartialEq)]
pub struct Uncertain {
    pub xyz: [f64; 3],
    /// Independent standard-normal factors, each moving XYZ along its vector.
    pub factors: Vec<[f64; 3]>,
    /// Extra standard uncertainty of each CIELAB coordinate.
    pub u_lab: f64,
}

/// A 95 % interval.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Interval {
    pub lo: f64,
    pub hi: f64,
}

/// The intervals of both colour differences of one patch, and each draw's values (Monte
/// Carlo only; empty otherwise) so a summary over patches can get its own interval.
#[derive(Clone, PartialEq)]
pub struct Propagated {
    pub de76: Interval,
    pub de00: Interval,
    pub draws76: Vec<f64>,
    pub draws00: Vec<f64>,
}

impl std::fmt::Debug for Propagated {
    // The draws are thousands of numbers; the intervals are what a reader needs.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "ΔE*ab {:?} ΔE00 {:?}", self.de76, self.de00)
    }
}

/// The 97.5th percentile of the standard normal.
pub const Z975: f64 = 1.959_963_985;

/// How a renderer states a patch's ΔE*ab uncertainty.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RenderStatement {
    /// A path tracer's 95 % half-width, 1.96·√(tr Σ) of its estimate's CIELAB covariance.
    HalfWidth95,
    /// A deterministic solver's bound on the error vector's length.
    Bound,
}

/// The per-axis standard uncertainty in CIELAB that a renderer's per-patch ΔE*ab statement
/// stands for, the error taken as isotropic: a half-width h = 1.96·√(3σ²) gives
/// σ = h / (1.96·√3); a bound is taken as the 95th percentile of the error's length,
/// σ = b / √χ²₃(0.95).
pub fn render_lab_sigma(de: f64, how: RenderStatement) -> f64 {
    match how {
        RenderStatement::HalfWidth95 => de / (Z975 * 3f64.sqrt()),
        RenderStatement::Bound => de / super::readings::CHI3_95,
    }
}

/// Both colour differences with the factors set to `z`: the reference's XYZ factors, the
/// test's, then three CIELAB factors for each side.
struct Model<'a> {
    reference: &'a Uncertain,
    test: &'a Uncertain,
    white: Xyz,
}

impl Model<'_> {
    fn len(&self) -> usize {
        self.reference.factors.len() + self.test.factors.len() + 6
    }

    fn lab(side: &Uncertain, z: &[f64], zl: &[f64], white: Xyz) -> Lab {
        let mut xyz = side.xyz;
        for (f, zi) in side.factors.iter().zip(z) {
            for (x, v) in xyz.iter_mut().zip(f) {
                *x += v * zi;
            }
        }
        let l = Xyz::from_array(xyz).to_lab(white);
        Lab::new(
            l.l + side.u_lab * zl[0],
            l.a + side.u_lab * zl[1],
            l.b + side.u_lab * zl[2],
        )
    }

    fn eval(&self, z: &[f64]) -> (f64, f64) {
        let nr = self.reference.factors.len();
        let nt = self.test.factors.len();
        let (zr, rest) = z.split_at(nr);
        let (zt, zl) = rest.split_at(nt);
        let r = Self::lab(self.reference, zr, &zl[..3], self.white);
        let t = Self::lab(self.test, zt, &zl[3..], self.white);
        (delta_e76(r, t), delta_e2000(r, t))
    }
}

/// The 95 % intervals of ΔE*ab and ΔE00 between `reference` and `test` in CIELAB relative
/// to `white`; `patch` keys the Monte Carlo stream.
pub fn propagate(
    reference: &Uncertain,
    test: &Uncertain,
    white: Xyz,
    how: Propagation,
    patch: usize,
) -> Propagated {
    let model = Model {
        reference,
        test,
        white,
    };
    let n = model.len();
    let zero = vec![0.0; n];
    let (d76, d00) = model.eval(&zero);
    let uncertain = !reference.factors.is_empty()
        || !test.factors.is_empty()
        || reference.u_lab > 0.0
        || test.u_lab > 0.0;
    let point = Propagated {
        de76: Interval { lo: d76, hi: d76 },
        de00: Interval { lo: d00, hi: d00 },
        draws76: Vec::new(),
        draws00: Vec::new(),
    };
    if !uncertain {
        return point;
    }
    match how {
        Propagation::MonteCarlo { draws, seed } => {
            let mut rng = SplitMix64::new(SplitMix64::mix(seed ^ ((patch as u64) << 32)));
            let mut draws76 = Vec::with_capacity(draws);
            let mut draws00 = Vec::with_capacity(draws);
            let mut z = zero;
            for _ in 0..draws {
                for zi in z.iter_mut() {
                    *zi = rng.normal();
                }
                let (a, b) = model.eval(&z);
                draws76.push(a);
                draws00.push(b);
            }
            Propagated {
                de76: percentiles(&draws76).unwrap_or(point.de76),
                de00: percentiles(&draws00).unwrap_or(point.de00),
                draws76,
                draws00,
            }
        }
        Propagation::Linear => {
            let (mut v76, mut v00) = (0.0, 0.0);
            // A step well inside one standard uncertainty, where ΔE is close to linear.
            let h = 1e-3;
            for i in 0..n {
                let (mut up, mut down) = (zero.clone(), zero.clone());
                up[i] = h;
                down[i] = -h;
                let (u76, u00) = model.eval(&up);
                let (w76, w00) = model.eval(&down);
                v76 += ((u76 - w76) / (2.0 * h)).powi(2);
                v00 += ((u00 - w00) / (2.0 * h)).powi(2);
            }
            let around = |d: f64, v: f64| Interval {
                lo: (d - Z975 * v.sqrt()).max(0.0),
                hi: d + Z975 * v.sqrt(),
            };
            Propagated {
                de76: around(d76, v76),
                de00: around(d00, v00),
                draws76: Vec::new(),
                draws00: Vec::new(),
            }
        }
    }
}

/// The 2.5th and 97.5th percentiles (linear interpolation between order statistics).
pub fn percentiles(values: &[f64]) -> Option<Interval> {
    if values.is_empty() {
        return None;
    }
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    let q = |p: f64| {
        let x = p * (v.len() - 1) as f64;
        let (i, f) = (x.floor() as usize, x.fract());
        v[i] + (v[(i + 1).min(v.len() - 1)] - v[i]) * f
    };
    Some(Interval {
        lo: q(0.025),
        hi: q(0.975),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const WHITE: Xyz = Xyz::new(95.047, 100.0, 108.883);

    fn exact(xyz: [f64; 3]) -> Uncertain {
        Uncertain {
            xyz,
            factors: Vec::new(),
            u_lab: 0.0,
        }
    }

    /// Two neutral greys at L* = 50 and 60 (Y/Yn = ((L*+16)/116)³: 0.18418652 and
    /// 0.28123334), the test one with an isotropic CIELAB error σ = 0.5 per axis. Far from
    /// 0, ΔE*ab ≈ |ΔL* + e_L| is normal with sd 0.5: the interval is 10 ± 1.96·0.5.
    #[test]
    fn isotropic_lab_noise_gives_the_analytic_interval() {
        let g = |y: f64| [WHITE.x * y, WHITE.y * y, WHITE.z * y];
        let r = exact(g(0.184_186_52));
        let t = Uncertain {
            u_lab: 0.5,
            ..exact(g(0.281_233_34))
        };
        let mc = propagate(
            &r,
            &t,
            WHITE,
            Propagation::MonteCarlo {
                draws: 20_000,
                seed: 3,
            },
            1,
        );
        // The two perpendicular terms add σ²/D = 0.025 to ΔE; Monte Carlo's own error on a
        // 2.5 % quantile with 20 000 draws is about 0.01.
        assert!((mc.de76.lo - (10.025 - 0.98)).abs() < 0.03, "{:?}", mc.de76);
        assert!((mc.de76.hi - (10.025 + 0.98)).abs() < 0.03, "{:?}", mc.de76);
        let lin = propagate(&r, &t, WHITE, Propagation::Linear, 1);
        assert!((lin.de76.lo - 9.02).abs() < 1e-3, "{:?}", lin.de76);
        assert!((lin.de76.hi - 10.98).abs() < 1e-3, "{:?}", lin.de76);
    }

    /// Monte Carlo and linearisation agree on a patch whose ΔE is large against its
    /// uncertainty (ColorChecker-like red vs a shifted one, 0.2 % XYZ noise).
    #[test]
    fn monte_carlo_and_linearisation_agree_far_from_zero() {
        let r = Uncertain {
            xyz: [21.0, 12.0, 5.0],
            factors: vec![[0.04, 0.0, 0.0], [0.0, 0.024, 0.0], [0.0, 0.0, 0.01]],
            u_lab: 0.0,
        };
        let t = Uncertain {
            xyz: [19.0, 12.5, 6.5],
            ..r.clone()
        };
        let how = Propagation::MonteCarlo {
            draws: 20_000,
            seed: 9,
        };
        let mc = propagate(&r, &t, WHITE, how, 15);
        let lin = propagate(&r, &t, WHITE, Propagation::Linear, 15);
        let width = lin.de76.hi - lin.de76.lo;
        assert!(width > 0.5, "{width}");
        assert!(
            (mc.de76.lo - lin.de76.lo).abs() < 0.05 * width,
            "{:?} {:?} / {:?} {:?}",
            mc.de76,
            mc.de00,
            lin.de76,
            lin.de00
        );
        assert!(
            (mc.de76.hi - lin.de76.hi).abs() < 0.05 * width,
            "{:?} {:?} / {:?} {:?}",
            mc.de76,
            mc.de00,
            lin.de76,
            lin.de00
        );
        let w00 = lin.de00.hi - lin.de00.lo;
        assert!(
            (mc.de00.lo - lin.de00.lo).abs() < 0.08 * w00,
            "{:?} {:?} / {:?} {:?}",
            mc.de76,
            mc.de00,
            lin.de76,
            lin.de00
        );
        assert!(
            (mc.de00.hi - lin.de00.hi).abs() < 0.08 * w00,
            "{:?} {:?} / {:?} {:?}",
            mc.de76,
            mc.de00,
            lin.de76,
            lin.de00
        );
        // The same seed gives the same interval.
        assert_eq!(mc, propagate(&r, &t, WHITE, how, 15));
    }

    #[test]
    fn no_uncertainty_gives_a_point_and_percentiles_by_hand() {
        let r = exact([20.0, 21.0, 22.0]);
        let p = propagate(&r, &r, WHITE, Propagation::default(), 2);
        assert_eq!(p.de76, Interval { lo: 0.0, hi: 0.0 });
        // 0..=100: the 2.5th percentile is 2.5, the 97.5th 97.5.
        let v: Vec<f64> = (0..=100).map(f64::from).collect();
        assert_eq!(percentiles(&v), Some(Interval { lo: 2.5, hi: 97.5 }));
    }
}
