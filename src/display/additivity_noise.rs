//! How far the measured white may miss the additive sum R + G + B − 2K from the meter's noise
//! alone, on a set that does not repeat its patches.
//!
//! The check compares one reading with the sum of four others, and its noise is not that of
//! one reading: a saturated primary's chromaticity noise moves its X and Z by a large part of
//! themselves (a blue at y ≈ 0.06 turns 0.0005 in y into about 0.8 % of its Z), and the sum
//! carries that into the white. A perfectly additive simulated CRT read once per patch with
//! the CS-100A's noise (1σ 0.0005 in x and y, 0.1 % in Y) misses by up to ΔE00 1.2 over six
//! meter seeds, more than twice the tolerance of a verdict.
//!
//! Where patches were read more than once their spread says how noisy a reading is, in x, y
//! and Y. A set without repeats does not say it directly, but its ramps do. In the
//! brighter part of a ramp a reading's chromaticity changes smoothly with its luminance
//! (the channel's own drift and a fading share of black's light) and its luminance follows
//! a smooth curve of the drive in log–log coordinates, so what a level departs from the cubic
//! through two neighbours on either side is, to a good approximation, noise. On real
//! monitors measured through a video card's calibration the ramps are rougher than the
//! meter, since an 8-bit calibration curve steps each level's luminance by up to a per cent,
//! so repeats are preferred where a set has them. Either estimate is propagated through the
//! check by drawing each of the five readings' noise, scaled by how many readings were
//! averaged into it, from a seeded generator so that a fit is repeatable.

use super::model::samples::SortedSamples;
use super::model::Sample;
use crate::color::{delta_e2000, Xyz};

/// Levels darker than this share of the channel's full-on luminance are left out: there a
/// reading's chromaticity is mostly black's and bends quickly.
const BRIGHT_SHARE: f64 = 0.1;
/// Noise draws propagated through the check.
const DRAWS: usize = 512;
const SEED: u64 = 0x5EED_ADD1;

/// One reading's noise (1σ), from repeated patches or from the ramps' smoothness.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReadingNoise {
    /// In x and in y.
    pub xy: f64,
    /// Of Y, relative.
    pub y_rel: f64,
    /// Where it comes from.
    pub source: NoiseSource,
}

/// What a [`ReadingNoise`] rests on.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NoiseSource {
    /// Readings of patches measured more than once (degrees of freedom).
    Repeats(usize),
    /// Bright ramp levels judged against their neighbours.
    Ramps(usize),
}

impl std::fmt::Display for NoiseSource {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            NoiseSource::Repeats(_) => write!(f, "as the repeated patches show it"),
            NoiseSource::Ramps(_) => write!(f, "as the ramps' smoothness shows it"),
        }
    }
}

/// The spread of repeated readings about their patch's mean, pooled over every bright patch
/// read more than once; None without such repeats.
pub fn repeat_reading_noise(patches: &[Sample]) -> Option<ReadingNoise> {
    let key = |p: &Sample| p.rgb.map(|d| (d * 1e6).round() as i64);
    let mut groups: std::collections::BTreeMap<[i64; 3], Vec<Xyz>> = Default::default();
    for p in patches {
        groups.entry(key(p)).or_default().push(p.xyz);
    }
    let mean_y = |g: &[Xyz]| g.iter().map(|v| v[1]).sum::<f64>() / g.len() as f64;
    let brightest = groups.values().map(|g| mean_y(g)).fold(0.0, f64::max);
    let (mut sxy, mut sy, mut dof) = (0.0, 0.0, 0usize);
    // Dark repeats (black above all) scatter in chromaticity far more than the bright
    // readings the check adds up, so they are left out as on the ramps.
    for xyzs in groups.values().filter(|g| g.len() >= 2) {
        let n = xyzs.len() as f64;
        let mean_y = mean_y(xyzs);
        if mean_y <= 0.0 || mean_y < BRIGHT_SHARE * brightest {
            continue;
        }
        let c: Vec<[f64; 2]> = xyzs.iter().map(|v| xy(*v)).collect();
        let mean_c: [f64; 2] = std::array::from_fn(|k| c.iter().map(|v| v[k]).sum::<f64>() / n);
        sxy += c
            .iter()
            .map(|v| (v[0] - mean_c[0]).powi(2) + (v[1] - mean_c[1]).powi(2))
            .sum::<f64>();
        sy += xyzs
            .iter()
            .map(|v| (v[1] / mean_y - 1.0).powi(2))
            .sum::<f64>();
        dof += xyzs.len() - 1;
    }
    (dof > 0)
        .then(|| ReadingNoise {
            xy: (sxy / (2 * dof) as f64).sqrt(),
            y_rel: (sy / dof as f64).sqrt(),
            source: NoiseSource::Repeats(dof),
        })
        .filter(|n| n.xy.is_finite() && n.y_rel.is_finite())
}

/// Pooled departure of each bright ramp level from the cubic through its two neighbours on
/// either side, each scaled by its variance under pure noise; None with fewer than three
/// such levels. A cubic, not the line through the nearest two, because a smooth curve bends
/// between neighbours by as much as a meter's noise on a 16-step ramp, and a cubic's own
/// miss shrinks with the fourth power of the step.
pub fn ramp_noise(set: &SortedSamples) -> Option<ReadingNoise> {
    let (mut sxy, mut sy, mut levels) = (0.0, 0.0, 0usize);
    for (c, ramp) in set.ramps.iter().enumerate() {
        let full = set.primaries[c]?[1];
        let counts = &set.ramp_readings[c];
        for i in 2..ramp.len().saturating_sub(2) {
            let around = [i - 2, i - 1, i + 1, i + 2];
            if ramp[i - 2].1[1] < BRIGHT_SHARE * full || ramp[i - 2].0 <= 0.0 {
                continue;
            }
            let n = |j: usize| counts.get(j).copied().unwrap_or(1).max(1) as f64;
            // Chromaticity against luminance.
            let w = lagrange(around.map(|j| ramp[j].1[1]), ramp[i].1[1]);
            let var = 1.0 / n(i) + (0..4).map(|k| w[k] * w[k] / n(around[k])).sum::<f64>();
            for k in 0..2 {
                let r =
                    xy(ramp[i].1)[k] - (0..4).map(|m| w[m] * xy(ramp[around[m]].1)[k]).sum::<f64>();
                sxy += r * r / var;
            }
            // ln Y against ln drive.
            let w = lagrange(around.map(|j| ramp[j].0.ln()), ramp[i].0.ln());
            let var = 1.0 / n(i) + (0..4).map(|k| w[k] * w[k] / n(around[k])).sum::<f64>();
            let r = ramp[i].1[1].ln()
                - (0..4)
                    .map(|m| w[m] * ramp[around[m]].1[1].ln())
                    .sum::<f64>();
            sy += r * r / var;
            levels += 1;
        }
    }
    (levels >= 3)
        .then(|| ReadingNoise {
            xy: (sxy / (2 * levels) as f64).sqrt(),
            y_rel: (sy / levels as f64).sqrt(),
            source: NoiseSource::Ramps(levels),
        })
        .filter(|n| n.xy.is_finite() && n.y_rel.is_finite())
}

/// Weights of the cubic through four abscissae at `at`.
fn lagrange(x: [f64; 4], at: f64) -> [f64; 4] {
    std::array::from_fn(|k| {
        (0..4)
            .filter(|&m| m != k)
            .map(|m| (at - x[m]) / (x[k] - x[m]))
            .product()
    })
}

/// Root-mean-square ΔE00 (CIELAB relative to `white`) by which noise of the size `noise`
/// moves the white against the additive sum; None unless black, white and the three
/// primaries were measured.
pub fn check_noise_de00(set: &SortedSamples, noise: ReadingNoise, white: Xyz) -> Option<f64> {
    let measured = set.white?;
    let black = set.black?;
    let prim = [set.primaries[0]?, set.primaries[1]?, set.primaries[2]?];
    let count = |c: usize| set.ramp_readings[c].last().copied().unwrap_or(1).max(1) as f64;
    let mut rng = metamer_drivers::noise::SplitMix64::new(SEED);
    let mut shift = |v: Xyz, n: f64| -> [f64; 3] {
        let s = v[0] + v[1] + v[2];
        let scale = 1.0 / n.sqrt();
        let y = v[1] * (1.0 + noise.y_rel * scale * rng.normal());
        let cx = v[0] / s + noise.xy * scale * rng.normal();
        let cy = v[1] / s + noise.xy * scale * rng.normal();
        let moved = [cx / cy * y, y, (1.0 - cx - cy) / cy * y];
        std::array::from_fn(|k| moved[k] - v[k])
    };
    let mut sum2 = 0.0;
    for _ in 0..DRAWS {
        let dw = shift(measured, set.white_readings.max(1) as f64);
        let dk = shift(black, set.black_readings.max(1) as f64);
        let dp: [[f64; 3]; 3] = std::array::from_fn(|c| shift(prim[c], count(c)));
        let moved: [f64; 3] = std::array::from_fn(|k| {
            measured[k] + dw[k] - (dp[0][k] + dp[1][k] + dp[2][k] - 2.0 * dk[k])
        });
        let e = delta_e2000(Xyz::from(moved).to_lab(white), measured.to_lab(white));
        sum2 += e * e;
    }
    Some((sum2 / DRAWS as f64).sqrt()).filter(|e| e.is_finite())
}

fn xy(v: Xyz) -> [f64; 2] {
    let s = v[0] + v[1] + v[2];
    [v[0] / s, v[1] / s]
}

#[cfg(test)]
mod tests {
    use super::*;
    use metamer_drivers::noise::SplitMix64;

    /// BT.709 primaries at 80/160/30 cd/m²-ish, power-law curves, a dim bluish black: the
    /// readings of every ramp level (`levels` per channel), black and white, with the given
    /// 1σ noise in x, y and relative Y.
    fn ramp_set(levels: usize, xy_sigma: f64, y_sigma: f64, seed: u64) -> Vec<Sample> {
        let prim = [[41.2, 21.3, 1.9], [35.8, 71.5, 11.9], [18.0, 7.2, 95.0]];
        let black = [0.05, 0.05, 0.08];
        let mut rng = SplitMix64::new(seed);
        let mut read = |v: [f64; 3]| -> [f64; 3] {
            let s = v[0] + v[1] + v[2];
            let y = v[1] * (1.0 + y_sigma * rng.normal());
            let cx = v[0] / s + xy_sigma * rng.normal();
            let cy = v[1] / s + xy_sigma * rng.normal();
            [cx / cy * y, y, (1.0 - cx - cy) / cy * y]
        };
        let mut out = vec![Sample {
            rgb: [0.0; 3],
            xyz: read(black).into(),
        }];
        for c in 0..3 {
            for k in 1..=levels {
                let d = k as f64 / levels as f64;
                let l = d.powf(2.2);
                let mut rgb = [0.0; 3];
                rgb[c] = d;
                out.push(Sample {
                    rgb,
                    xyz: read(std::array::from_fn(|i| black[i] + l * prim[c][i])).into(),
                });
            }
        }
        let white = std::array::from_fn(|i| black[i] + (0..3).map(|c| prim[c][i]).sum::<f64>());
        out.push(Sample {
            rgb: [1.0; 3],
            xyz: read(white).into(),
        });
        out
    }

    /// The ramps give back the noise they were read with: over eight sets of 3 × 48 levels
    /// (about 700 bright levels, so the pooled estimate's own scatter is a few per cent) the
    /// mean estimate is within 15 % of the truth in x, y and Y; and a noise-free set's
    /// curves alone give less than a tenth of it.
    #[test]
    fn the_ramps_show_the_noise_they_were_read_with() {
        let (mut xy_sum, mut y_sum) = (0.0, 0.0);
        for seed in 1..=8 {
            let set = SortedSamples::new(&ramp_set(48, 5e-4, 1e-3, seed));
            let n = ramp_noise(&set).unwrap();
            assert!(matches!(n.source, NoiseSource::Ramps(l) if l > 60), "{n:?}");
            xy_sum += n.xy / 8.0;
            y_sum += n.y_rel / 8.0;
        }
        assert!((xy_sum / 5e-4 - 1.0).abs() < 0.15, "xy {xy_sum}");
        assert!((y_sum / 1e-3 - 1.0).abs() < 0.15, "Y {y_sum}");
        let clean = ramp_noise(&SortedSamples::new(&ramp_set(16, 0.0, 0.0, 1))).unwrap();
        assert!(clean.xy < 5e-5 && clean.y_rel < 1e-4, "{clean:?}");
    }

    /// By hand: a white read at Y 100 and 102 with one chromaticity, a green at 50 and 50:
    /// Y deviations ±1/101 and 0, two degrees of freedom, so y_rel = √(2/101² / 2) = 1/101;
    /// x and y do not move. The black read twice (Y 0.05 and 0.10) is too dark to count.
    #[test]
    fn repeats_give_the_spread_of_bright_readings_by_hand() {
        let p = |rgb: [f64; 3], xyz: [f64; 3]| Sample {
            rgb,
            xyz: xyz.into(),
        };
        let patches = [
            p([1.0; 3], [95.0, 100.0, 108.0]),
            p([1.0; 3], [96.9, 102.0, 110.16]),
            p([0.0, 1.0, 0.0], [25.0, 50.0, 8.0]),
            p([0.0, 1.0, 0.0], [25.0, 50.0, 8.0]),
            p([0.0; 3], [0.05, 0.05, 0.08]),
            p([0.0; 3], [0.02, 0.1, 0.3]),
            p([1.0, 0.0, 0.0], [40.0, 20.0, 2.0]),
        ];
        let n = repeat_reading_noise(&patches).unwrap();
        assert_eq!(n.source, NoiseSource::Repeats(2));
        assert!((n.y_rel - 1.0 / 101.0).abs() < 1e-12, "{n:?}");
        assert!(n.xy < 1e-12, "{n:?}");
        assert!(repeat_reading_noise(&patches[..1]).is_none());
    }

    /// Without noise the white does not move; for small noise the move scales with it.
    #[test]
    fn the_checks_noise_is_nil_without_noise_and_scales_with_it() {
        let set = SortedSamples::new(&ramp_set(16, 0.0, 0.0, 1));
        let white = set.white.unwrap();
        let at = |xy, y_rel| {
            let source = NoiseSource::Ramps(1);
            check_noise_de00(&set, ReadingNoise { xy, y_rel, source }, white).unwrap()
        };
        assert_eq!(at(0.0, 0.0), 0.0);
        let (one, two) = (at(1e-4, 2e-4), at(2e-4, 4e-4));
        assert!(one > 0.0 && (two / one - 2.0).abs() < 0.05, "{one} {two}");
    }
}
