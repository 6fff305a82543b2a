//! One instrument's repeatability in one mode, pooled across the targets it read.
//!
//! The stated repeatability gives the shape of one reading's XYZ covariance at each level
//! (Y relative, x and y absolute for the CS-100A: a dim or saturated target scatters more
//! in XYZ than a bright grey, in proportion). What the targets' repeats estimate is one
//! factor s² on it: each target j with kⱼ readings xᵢ about their mean x̄ⱼ and stated
//! covariance Σⱼ at that mean gives Qⱼ = Σᵢ (xᵢ − x̄ⱼ)ᵀ Σⱼ⁻¹ (xᵢ − x̄ⱼ), which for normal
//! readings with covariance s²Σⱼ is s²·χ² with 3(kⱼ − 1) degrees of freedom, whatever the
//! target's level. So ŝ² = ΣQⱼ / ν with ν = 3·Σ(kⱼ − 1), and ν·ŝ²/s² is χ²_ν: the figure
//! and its degrees of freedom are what the intervals need. 24 spots read twice give ν = 72.
//! It is honest as long as the shape is (the instrument's scatter grows with the level as
//! stated); the tests draw readings with a scale of 1 and of 2 and find it within its
//! χ² interval at the stated rate.

use super::RepeatNoise;
use crate::color::Xyz;
use crate::validation::covariance;
use crate::validation::repeatability::{self, Repeatability};

/// The sum of the targets' whitened squared residuals and its degrees of freedom.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Pool {
    pub sum: f64,
    pub dof: usize,
}

impl Pool {
    /// Adds one target's readings; a target with one reading, or without a stated
    /// covariance at its level (no chromaticity), adds nothing.
    pub fn add(&mut self, readings: &[Xyz], stated: &Repeatability) {
        let (mean, cov) = covariance::sample(readings);
        self.add_sample(mean, &cov, readings.len(), stated);
    }

    /// Adds one target's `k` readings given as their mean and sample covariance (divisor
    /// k − 1): Qⱼ = (k − 1)·tr(Σⱼ⁻¹ S), the same sum as the readings' own.
    pub fn add_sample(
        &mut self,
        mean: Xyz,
        cov: &covariance::Cov3,
        k: usize,
        stated: &Repeatability,
    ) {
        if k < 2 {
            return;
        }
        let Some(inverse) = repeatability::covariance(stated, mean).and_then(|c| inverse(&c))
        else {
            return;
        };
        let trace: f64 = (0..3)
            .map(|i| (0..3).map(|j| inverse[i][j] * cov[j][i]).sum::<f64>())
            .sum();
        self.sum += (k - 1) as f64 * trace;
        self.dof += 3 * (k - 1);
    }

    /// The pooled factor on the stated covariance, with its degrees of freedom; the stated
    /// figure itself, known, while the pool is empty.
    pub fn noise(&self, stated: Repeatability) -> RepeatNoise {
        if self.dof == 0 {
            return RepeatNoise::stated(stated);
        }
        RepeatNoise {
            stated,
            scale2: self.sum / self.dof as f64,
            dof: Some(self.dof as f64),
        }
    }
}

fn inverse(c: &covariance::Cov3) -> Option<covariance::Cov3> {
    let m = nalgebra::Matrix3::from_fn(|i, j| c[i][j]);
    let inv = m.try_inverse()?;
    Some([0, 1, 2].map(|i| [0, 1, 2].map(|j| inv[(i, j)])))
}
