//! Propagating the readings' uncertainty to ΔE*ab and ΔE00: by Monte Carlo with a
//! bias-aware interval (the default) and by linearisation (first-order, for comparison).
//!
//! Both start from the same model: each reading's mean XYZ moves by a normal with the
//! mean's full covariance (given as factors), and its CIELAB coordinates get an extra
//! independent normal term per axis (a renderer's ΔE bound, a display model's
//! verification error). A covariance estimated from k repeats is uncertain itself: each
//! Monte Carlo draw scales that side's XYZ noise by √(ν/χ²_ν) with ν = k − 1, so any fixed
//! linear combination of X, Y, Z follows Student's t with ν degrees of freedom, as it
//! does for the sample (a stated repeatability or a renderer's error is taken as known).
//! The white is taken as exact: an error in it moves both readings' CIELAB alike, so ΔE
//! changes only in second order.
//!
//! Monte Carlo draws `draws` noise vectors per patch from the workspace's seeded generator
//! (the seed is mixed with the patch number, so a patch's interval does not depend on the
//! others) and inverts the test of each candidate truth ([`super::inversion`]): ΔE is a
//! length that noise inflates, and the percentiles of noisy ΔE about the observed readings
//! count that inflation twice. The linearised interval (ΔE ± 1.96σ) is wrong near ΔE = 0,
//! where ΔE is not differentiable.

use metamer_drivers::noise::SplitMix64;
use serde::{Deserialize, Serialize};

use super::montecarlo::{lab_noise, patch_interval, LabNoise, Metric};
use super::uncertain::lab_of;
pub use super::uncertain::{render_lab_sigma, Interval, Uncertain, Z975};

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
                "Monte Carlo: {draws} noise draws per patch (seed {seed}), the interval by inverting the test of each true difference (bias-aware: noise lengthens ΔE)"
            ),
            Propagation::Linear => {
                "linearisation: ΔE ± 1.96 σ, σ by central differences".to_string()
            }
        }
    }
}

/// The intervals of both colour differences of one patch, with the two readings' CIELAB
/// and their noise draws (Monte Carlo only) so a summary over patches can get its own
/// interval the same way.
#[derive(Clone, PartialEq)]
pub struct Propagated {
    pub de76: Interval,
    pub de00: Interval,
    pub reference_lab: Lab,
    pub test_lab: Lab,
    pub noise: Option<LabNoise>,
}

impl std::fmt::Debug for Propagated {
    // The draws are thousands of numbers; the intervals are what a reader needs.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "ΔE*ab {:?} ΔE00 {:?}", self.de76, self.de00)
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

    fn eval(&self, z: &[f64]) -> (f64, f64) {
        let nr = self.reference.factors.len();
        let nt = self.test.factors.len();
        let (zr, rest) = z.split_at(nr);
        let (zt, zl) = rest.split_at(nt);
        let r = lab_of(self.reference, zr, &zl[..3], self.white);
        let t = lab_of(self.test, zt, &zl[3..], self.white);
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
    let (rl, tl) = (reference.xyz.to_lab(white), test.xyz.to_lab(white));
    let uncertain = !reference.factors.is_empty()
        || !test.factors.is_empty()
        || reference.u_lab > 0.0
        || test.u_lab > 0.0;
    let point = Propagated {
        de76: Interval { lo: d76, hi: d76 },
        de00: Interval { lo: d00, hi: d00 },
        reference_lab: rl,
        test_lab: tl,
        noise: None,
    };
    if !uncertain {
        return point;
    }
    match how {
        Propagation::MonteCarlo { draws, seed } => {
            let key = SplitMix64::mix(seed ^ ((patch as u64) << 32));
            let noise = lab_noise(reference, test, white, draws, &mut SplitMix64::new(key));
            Propagated {
                de76: patch_interval(rl, tl, &noise, Metric::De76, key),
                de00: patch_interval(rl, tl, &noise, Metric::De00, key),
                noise: Some(noise),
                ..point
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
                ..point
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const WHITE: Xyz = Xyz::new(95.047, 100.0, 108.883);

    fn exact(xyz: Xyz) -> Uncertain {
        Uncertain {
            xyz,
            factors: Vec::new(),
            dof: None,
            u_lab: 0.0,
        }
    }

    /// Two neutral greys at L* = 50 and 60 (Y/Yn = ((L*+16)/116)³: 0.18418652 and
    /// 0.28123334), the test one with an isotropic CIELAB error σ = 0.5 per axis: ΔE*ab/σ
    /// is a noncentral χ₃, and the interval of its noncentrality for an observed 10/0.5 =
    /// 20 is [17.9873, 21.9122]·0.5 (SciPy: ncx2.cdf(20², 3, λ²) = 0.975 and 0.025), i.e.
    /// [8.9937, 10.9561]: centred 0.025 below the estimate, where the percentiles of noisy
    /// ΔE about the readings would sit 0.025 above it.
    #[test]
    fn isotropic_lab_noise_gives_the_noncentral_chi_interval() {
        let g = |y: f64| WHITE.scaled(y);
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
        // Monte Carlo's own error on a 2.5 % quantile with 20 000 draws is about 0.01.
        assert!((mc.de76.lo - 8.9937).abs() < 0.03, "{:?}", mc.de76);
        assert!((mc.de76.hi - 10.9561).abs() < 0.03, "{:?}", mc.de76);
        let lin = propagate(&r, &t, WHITE, Propagation::Linear, 1);
        assert!((lin.de76.lo - 9.02).abs() < 1e-3, "{:?}", lin.de76);
        assert!((lin.de76.hi - 10.98).abs() < 1e-3, "{:?}", lin.de76);
    }

    /// Monte Carlo and linearisation agree on a patch whose ΔE is large against its
    /// uncertainty (ColorChecker-like red vs a shifted one, 0.2 % XYZ noise).
    #[test]
    fn monte_carlo_and_linearisation_agree_far_from_zero() {
        let r = Uncertain {
            xyz: Xyz::new(21.0, 12.0, 5.0),
            factors: vec![[0.04, 0.0, 0.0], [0.0, 0.024, 0.0], [0.0, 0.0, 0.01]],
            dof: None,
            u_lab: 0.0,
        };
        let t = Uncertain {
            xyz: Xyz::new(19.0, 12.5, 6.5),
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
        for (m, l, w, tol) in [
            (mc.de76, lin.de76, width, 0.05),
            (mc.de00, lin.de00, lin.de00.hi - lin.de00.lo, 0.08),
        ] {
            assert!(
                (m.lo - l.lo).abs() < tol * w && (m.hi - l.hi).abs() < tol * w,
                "{mc:?} / {lin:?}"
            );
        }
        // The same seed gives the same interval.
        assert_eq!(mc, propagate(&r, &t, WHITE, how, 15));
    }

    /// A covariance from 3 repeats (2 degrees of freedom) widens the interval of a linear
    /// quantity by Student's t: far from 0, ΔE*ab of greys apart in L* moves with ΔL*
    /// alone, so the half-width is t₂(0.975)·σ = 4.3027σ against 1.96σ when σ is known.
    #[test]
    fn an_estimated_covariance_widens_the_interval_by_students_t() {
        let g = |y: f64| WHITE.scaled(y);
        // σ of Y 0.05 along the grey axis (a* and b* stay 0).
        let axis = [0.950_47 * 0.05, 0.05, 1.088_83 * 0.05];
        let t = |dof| Uncertain {
            xyz: g(0.281_233_34),
            factors: vec![axis],
            dof,
            u_lab: 0.0,
        };
        let r = exact(g(0.184_186_52));
        let how = Propagation::MonteCarlo {
            draws: 40_000,
            seed: 4,
        };
        // dL*/dY at Y = 28.123334 (L* 60): (116/3)·(116/76)²/100 = 0.900799 per unit of Y.
        let sigma = 0.05 * 0.900_799;
        let known = propagate(&r, &t(None), WHITE, how, 2).de76;
        let estimated = propagate(&r, &t(Some(2)), WHITE, how, 2).de76;
        let half = |i: Interval| 0.5 * (i.hi - i.lo);
        assert!((half(known) / sigma - 1.96).abs() < 0.05, "{known:?}");
        assert!(
            (half(estimated) / sigma - 4.3027).abs() < 0.2,
            "{estimated:?}"
        );
    }

    #[test]
    fn no_uncertainty_gives_a_point() {
        let r = exact(Xyz::new(20.0, 21.0, 22.0));
        let p = propagate(&r, &r, WHITE, Propagation::default(), 2);
        assert_eq!(p.de76, Interval { lo: 0.0, hi: 0.0 });
        assert!(p.noise.is_none());
    }
}
