//! Repeated readings of one target: their mean, their spread against what the instrument's
//! noise allows, and the readings that lie too far off to be noise (outliers).
//!
//! The noise model is each instrument's stated repeatability (1σ of one reading), the one
//! the session flags readings by ([`Repeatability`]): the i1Pro's grows below full signal,
//! so a dim tile integrated the driver's longest time is allowed its larger scatter.
//!
//! An outlier is a reading whose Y lies more than [`OUTLIER_SIGMAS`] noise σ from the median
//! of its group (the median, not the mean, so the outlier does not hide itself); outliers
//! are left out of the mean and reported, never dropped silently. A group whose spread
//! (outliers left out) is beyond what the noise gives once in a thousand groups is flagged
//! as spreading more than the instrument: the target moved, drifted or was not held still.
//! The test is χ²: (n − 1)·s²/σ² against its 0.999 quantile with n − 1 degrees of freedom
//! (Wilson–Hilferty: k·(1 − 2/(9k) + z·√(2/(9k)))³ with z = 3.090, within 3 % of the
//! tabulated quantile for k = 1 and closer beyond).

use metamer_drivers::Reading;
use serde::{Deserialize, Serialize};

use crate::color::{Spectrum, Xyz};
use crate::session::Entry;
use crate::validation::covariance::{self, Cov3};
pub use crate::validation::repeatability::Repeatability;

/// Distance from the median, in noise σ, beyond which a reading is an outlier. At 5σ a
/// normal reading is flagged about once in 1.7 million.
pub const OUTLIER_SIGMAS: f64 = 5.0;
/// The standard normal quantile of 0.999.
const Z_999: f64 = 3.090_232;

/// The 0.999 quantile of χ² with `k` degrees of freedom (Wilson–Hilferty).
pub fn chi2_999(k: usize) -> f64 {
    let k = k as f64;
    let a = 2.0 / (9.0 * k);
    k * (1.0 - a + Z_999 * a.sqrt()).powi(3)
}

/// A group of repeated readings reduced.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GroupStats {
    /// Readings in the group.
    pub n: usize,
    /// Mean XYZ of the readings kept.
    pub xyz: Xyz,
    /// Standard deviation of Y of the readings kept (0 for one reading).
    pub sd_y: f64,
    /// Sample covariance of X, Y, Z of one reading among those kept (0 for one reading):
    /// a meter's noise in x, y moves X and Z together, and a yellow's Z by far more than
    /// its Y.
    #[serde(default)]
    pub cov: Cov3,
    /// The noise σ of Y the instrument allows at this level.
    pub noise_y: f64,
    /// Repeat numbers (0-based) left out as outliers.
    pub outliers: Vec<usize>,
    /// The readings kept spread more than the noise allows.
    pub spread_exceeds_noise: bool,
}

/// Why a group cannot be reduced.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum StatsError {
    #[error("no readings")]
    Empty,
    #[error("reading {repeat} has no spectrum: a spectral instrument is needed here")]
    NoSpectrum { repeat: usize },
    #[error("the spectra of reading {repeat} are on other wavelengths than reading 1's")]
    Grid { repeat: usize },
}

fn median(v: &[f64]) -> f64 {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let n = s.len();
    if n % 2 == 1 {
        s[n / 2]
    } else {
        0.5 * (s[n / 2 - 1] + s[n / 2])
    }
}

/// Which of the Ys are outliers (needs three readings: with two, neither can be told
/// from the other).
fn outliers(ys: &[f64], noise: Repeatability) -> Vec<usize> {
    if ys.len() < 3 {
        return Vec::new();
    }
    let m = median(ys);
    let sigma = noise.sigma_y(m).max(f64::MIN_POSITIVE);
    ys.iter()
        .enumerate()
        .filter(|(_, y)| ((*y - m) / sigma).abs() > OUTLIER_SIGMAS)
        .map(|(i, _)| i)
        .collect()
}

/// Each group's noise figure for its outlier and spread tests where many targets are
/// read alike (the tiles): the stated figure times the factor pooled over the *other*
/// groups' repeats, as the spots' is pooled (each group's Y scatter whitened by the stated
/// σ at its level: Σ(y − ȳ)²/σ², with k − 1 degrees of freedom), so a group that scatters
/// does not widen its own test. The stated figure where the others have no repeats.
pub fn pooled_noise(groups: &[Vec<f64>], noise: Repeatability) -> Vec<Repeatability> {
    let parts: Vec<(f64, usize)> = groups
        .iter()
        .map(|ys| {
            if ys.len() < 2 {
                return (0.0, 0);
            }
            let mean = ys.iter().sum::<f64>() / ys.len() as f64;
            let sigma = noise.sigma_y(mean).max(f64::MIN_POSITIVE);
            let q = ys.iter().map(|y| ((y - mean) / sigma).powi(2)).sum();
            (q, ys.len() - 1)
        })
        .collect();
    let (sum, dof) = parts.iter().fold((0.0, 0), |(s, d), (q, k)| (s + q, d + k));
    parts
        .iter()
        .map(|(q, k)| match dof - k {
            0 => noise,
            others => {
                let factor = ((sum - q) / others as f64).sqrt();
                crate::validation::repeatability::scaled(&noise, factor)
            }
        })
        .collect()
}

/// [`pooled_noise`] of groups of journal entries (a stage's targets, each its repeats),
/// on the stated figure of the first one's instrument and mode.
pub fn pooled_noise_of<T, D>(groups: &[(T, Vec<&Entry<D>>)]) -> Vec<Repeatability> {
    let Some(first) = groups.first().and_then(|(_, g)| g.first()) else {
        return Vec::new();
    };
    let stated = crate::validation::repeatability::stated(&first.reading.instrument, first.mode);
    let ys: Vec<Vec<f64>> = groups
        .iter()
        .map(|(_, g)| g.iter().map(|e| e.reading.xyz[1]).collect())
        .collect();
    pooled_noise(&ys, stated)
}

/// Reduces the readings of one target.
pub fn group(readings: &[&Reading], noise: Repeatability) -> Result<GroupStats, StatsError> {
    if readings.is_empty() {
        return Err(StatsError::Empty);
    }
    let ys: Vec<f64> = readings.iter().map(|r| r.xyz[1]).collect();
    let out = outliers(&ys, noise);
    let kept: Vec<&Reading> = readings
        .iter()
        .enumerate()
        .filter(|(i, _)| !out.contains(i))
        .map(|(_, r)| *r)
        .collect();
    let k = kept.len() as f64;
    let xs: Vec<Xyz> = kept.iter().map(|r| r.xyz).collect();
    let (xyz, cov) = covariance::sample(&xs);
    let sd_y = cov[1][1].sqrt();
    let noise_y = noise.sigma_y(xyz[1]);
    Ok(GroupStats {
        n: readings.len(),
        xyz,
        sd_y,
        cov,
        noise_y,
        spread_exceeds_noise: kept.len() > 1
            && (k - 1.0) * sd_y * sd_y > chi2_999(kept.len() - 1) * noise_y * noise_y,
        outliers: out,
    })
}

/// The mean spectrum of the readings `stats` kept.
pub fn mean_spectrum(readings: &[&Reading], stats: &GroupStats) -> Result<Spectrum, StatsError> {
    let mut first: Option<&Spectrum> = None;
    let mut sum: Vec<f64> = Vec::new();
    let mut kept = 0usize;
    for (i, r) in readings.iter().enumerate() {
        let s = r
            .spectrum
            .as_ref()
            .ok_or(StatsError::NoSpectrum { repeat: i + 1 })?;
        if stats.outliers.contains(&i) {
            continue;
        }
        match first {
            None => {
                first = Some(s);
                sum = s.values().to_vec();
            }
            Some(f) => {
                if f.wavelengths_nm() != s.wavelengths_nm() {
                    return Err(StatsError::Grid { repeat: i + 1 });
                }
                sum.iter_mut().zip(s.values()).for_each(|(a, b)| *a += b);
            }
        }
        kept += 1;
    }
    let f = first.ok_or(StatsError::Empty)?;
    let values = sum.into_iter().map(|v| v / kept as f64).collect();
    let mut out = Spectrum::new(f.wavelengths_nm().to_vec(), values)
        .map_err(|_| StatsError::Grid { repeat: 1 })?
        .with_outside(f.outside());
    if let Some(q) = f.quantity() {
        out = out.with_quantity(q);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use metamer_drivers::MeasureMode;

    fn reading(y: f64) -> Reading {
        Reading {
            timestamp_s: 0.0,
            ..Reading::from_yxy(y, 0.3, 0.3, "cs100a")
        }
    }

    /// The pooled figure by hand: three tiles at Y = 100 (CS-100A σ 0.2 there), each read
    /// twice, 0.4 apart, then 0.2, then 0.6: whitened sums (0.4/0.2)²/2 = 2, 0.5 and 4.5
    /// on one degree of freedom each. The first tile is tested against the other two's
    /// (0.5 + 4.5)/2 = 2.5, σ × √2.5; a tile alone keeps the stated figure.
    #[test]
    fn each_group_is_tested_against_the_others_pooled_figure() {
        let noise = crate::validation::repeatability::stated("cs100a", MeasureMode::Emissive);
        let sigma = noise.sigma_y(100.0);
        let pair = |d: f64| vec![100.0 - d / 2.0, 100.0 + d / 2.0];
        let groups = [pair(2.0 * sigma), pair(sigma), pair(3.0 * sigma)];
        let pooled = pooled_noise(&groups, noise);
        let whitened = [2.0, 0.5, 4.5];
        for (j, tested) in pooled.iter().enumerate() {
            let others = (whitened.iter().sum::<f64>() - whitened[j]) / 2.0;
            let got = tested.sigma_y(100.0) / sigma;
            assert!((got - others.sqrt()).abs() < 1e-6, "tile {j}: {got}");
        }
        assert!((pooled[0].sigma_y(100.0) / sigma - 2.5f64.sqrt()).abs() < 1e-6);
        assert_eq!(pooled_noise(&[pair(sigma)], noise), vec![noise]);
    }

    #[test]
    fn a_reading_five_sigma_off_the_median_is_an_outlier_and_left_out_of_the_mean() {
        let noise = crate::validation::repeatability::stated("cs100a", MeasureMode::Emissive);
        // σ = 0.1 at Y = 100: 100.3 is 3σ off (kept), 101 is 10σ off (outlier).
        let ys = [100.0, 100.1, 99.9, 100.3, 101.0];
        let rs: Vec<Reading> = ys.iter().map(|&y| reading(y)).collect();
        let refs: Vec<&Reading> = rs.iter().collect();
        let g = group(&refs, noise).unwrap();
        assert_eq!(g.outliers, vec![4]);
        assert!((g.xyz[1] - 100.075).abs() < 1e-9, "{g:?}");
        // sd of 100, 100.1, 99.9, 100.3 = 0.1708: 3·0.1708²/0.1² = 8.75 < χ²(3) 16.27.
        assert!((g.sd_y - 0.170_782_512_765_993_3).abs() < 1e-9, "{g:?}");
        assert!(!g.spread_exceeds_noise);
    }

    #[test]
    fn a_spread_beyond_the_noise_is_flagged_and_two_readings_have_no_outlier() {
        let noise = crate::validation::repeatability::stated("i1pro", MeasureMode::Reflective);
        let rs: Vec<Reading> = [20.0, 21.0].iter().map(|&y| reading(y)).collect();
        let refs: Vec<&Reading> = rs.iter().collect();
        let g = group(&refs, noise).unwrap();
        assert!(g.outliers.is_empty());
        // sd = 0.7071: 1·0.5/0.04 = 12.5 > χ²(1) ≈ 11.
        assert!(g.spread_exceeds_noise, "{g:?}");
        let rs: Vec<Reading> = [20.0, 20.6].iter().map(|&y| reading(y)).collect();
        let refs: Vec<&Reading> = rs.iter().collect();
        // sd = 0.4243: 0.18/0.04 = 4.5, within the noise.
        assert!(!group(&refs, noise).unwrap().spread_exceeds_noise);
        assert_eq!(group(&[], noise).unwrap_err(), StatsError::Empty);
    }

    #[test]
    fn the_chi2_quantile_is_near_the_table() {
        // 0.999 quantiles of χ² (NIST/SEMATECH e-Handbook, table 1.3.6.7.4).
        for (k, want) in [(1, 10.828), (4, 18.467), (10, 29.588), (30, 59.703)] {
            let got = chi2_999(k);
            assert!((got / want - 1.0).abs() < 0.035, "{k}: {got} vs {want}");
        }
    }

    /// A dim tile read by the i1Pro at its longest integration scatters more than a bright
    /// one, and the figure allows it: at 20 cd/m² σ is 0.3417 % (0.15 %·√5 with 0.013/20 in
    /// quadrature), 0.0683 cd/m²; five readings with sd 0.1 give 4·0.1²/0.0683² = 8.6 <
    /// χ²(4) ≈ 18.5, where a flat 0.1 % (σ 0.02) would give 100 and flag it.
    #[test]
    fn a_dim_i1pro_tile_is_allowed_the_scatter_of_its_level() {
        let i1 = crate::validation::repeatability::stated("i1pro", MeasureMode::Emissive);
        // Mean 20, deviations −0.1, −0.1, 0, 0.1, 0.1: sd = √(0.04/4) = 0.1.
        let rs: Vec<Reading> = [19.9, 19.9, 20.0, 20.1, 20.1]
            .iter()
            .map(|&y| Reading::from_yxy(y, 0.3, 0.3, "i1pro"))
            .collect();
        let refs: Vec<&Reading> = rs.iter().collect();
        let g = group(&refs, i1).unwrap();
        assert!((g.noise_y - 0.068_33).abs() < 1e-4, "{g:?}");
        assert!(!g.spread_exceeds_noise && g.outliers.is_empty(), "{g:?}");
        // Three times the scatter (sd 0.3: 4·0.09/0.0683² = 77; each reading within 4.4σ
        // of the median, no outlier) is flagged.
        let wide: Vec<Reading> = [19.7, 19.7, 20.0, 20.3, 20.3]
            .iter()
            .map(|&y| Reading::from_yxy(y, 0.3, 0.3, "i1pro"))
            .collect();
        let refs: Vec<&Reading> = wide.iter().collect();
        let g = group(&refs, i1).unwrap();
        assert!(g.spread_exceeds_noise && g.outliers.is_empty(), "{g:?}");
    }
}
