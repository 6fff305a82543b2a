//! One side of a comparison and its uncertainty, the 95 % interval, and how a renderer's
//! statement of its own error becomes a CIELAB uncertainty: what the propagation, the
//! Monte Carlo draws, the test inversion and the readings all speak of, and what an
//! interval says about the JND.

use serde::{Deserialize, Serialize};

use crate::color::{Lab, Xyz};
use crate::render::spot::Uncertainty;

/// The 95th percentile of the length of a 3-D isotropic normal vector in units of its
/// per-axis σ (√χ²₃(0.95) = √7.8147): converts a renderer's 95 % ΔE half-width to a
/// per-axis standard uncertainty in CIELAB.
pub const CHI3_95: f64 = 2.795_483;

/// One side of a comparison with its uncertainty.
#[derive(Clone, Debug, PartialEq)]
pub struct Uncertain {
    pub xyz: Xyz,
    /// Independent standard-normal factors, each moving XYZ along its vector: their
    /// Σ f fᵀ is the covariance of the mean.
    pub factors: Vec<[f64; 3]>,
    /// Degrees of freedom of that covariance where it was estimated from repeats (k − 1);
    /// None where it is known (an instrument's stated repeatability, a renderer's error).
    pub dof: Option<usize>,
    /// Extra standard uncertainty of each CIELAB coordinate.
    pub u_lab: f64,
}

/// The just noticeable difference in ΔE*ab the paper uses (after Sharma 2003).
pub const JND_DE76: f64 = 2.3;

/// What the interval of a patch's ΔE*ab says about the JND.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum JndVerdict {
    Below,
    Above,
    Undecided,
}

impl JndVerdict {
    pub fn of(interval: Interval) -> JndVerdict {
        if interval.hi < JND_DE76 {
            JndVerdict::Below
        } else if interval.lo > JND_DE76 {
            JndVerdict::Above
        } else {
            JndVerdict::Undecided
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            JndVerdict::Below => "below",
            JndVerdict::Above => "above",
            JndVerdict::Undecided => "undecided",
        }
    }
}

/// A 95 % interval.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Interval {
    pub lo: f64,
    pub hi: f64,
}

impl Interval {
    pub fn contains(self, v: f64) -> bool {
        self.lo <= v && v <= self.hi
    }
}

/// The 97.5th percentile of the standard normal.
pub const Z975: f64 = 1.959_963_985;

/// The per-axis standard uncertainty in CIELAB that a renderer's per-patch ΔE*ab statement
/// stands for, the error taken as isotropic: a half-width h = 1.96·√(3σ²) gives
/// σ = h / (1.96·√3); a bound is taken as the 95th percentile of the error's length,
/// σ = b / √χ²₃(0.95).
pub fn render_lab_sigma(statement: Uncertainty) -> f64 {
    match statement {
        Uncertainty::HalfWidth95 { de, .. } => de / (Z975 * 3f64.sqrt()),
        Uncertainty::Bound { de, .. } => de / CHI3_95,
    }
}

/// The CIELAB of `side` with its XYZ factors set to `z` and its CIELAB factors to `zl`.
pub fn lab_of(side: &Uncertain, z: &[f64], zl: &[f64], white: Xyz) -> Lab {
    let mut xyz = side.xyz;
    for (f, zi) in side.factors.iter().zip(z) {
        for (i, v) in f.iter().enumerate() {
            xyz[i] += v * zi;
        }
    }
    let l = xyz.to_lab(white);
    Lab::new(
        l.l + side.u_lab * zl[0],
        l.a + side.u_lab * zl[1],
        l.b + side.u_lab * zl[2],
    )
}
