//! PLVC, the piecewise-linear model assuming variation in chromaticity (Post & Calhoun, "An
//! evaluation of methods for producing desired colors on CRT monitors", Color Res. Appl.
//! 14(4), 1989, beside PLCC): each channel contributes its own measured light, not a scalar
//! times a fixed primary, so
//!   XYZ(r, g, b) = K + Σ_c (XYZ_c(d_c) − K),
//! with XYZ_c(d) the channel's ramp reading at drive d (and K black), interpolated between
//! the ramp's levels. It assumes additivity but not constant chromaticity: a channel whose
//! colour drifts as it dims (LCD leakage, a phosphor's tail) is reproduced along its ramp and
//! in every mixture, which is what a set of single-channel ramps can support.
//!
//! A measured white is the one mixture such a set holds, and the model passes through it:
//! the white's departure from additivity, ΔW = W − (R + G + B − 2K), is added to each
//! mixture in proportion to the light its channels share, (l_r + l_g + l_b − max l) / 2 with
//! l the channels' luminances as fractions of their full-on ones. That share is 0 on every
//! ramp (which stay exact), 1 at white, ½ at a full secondary and l on a grey of luminance
//! fraction l. Fitted on the single-channel patches of seven DisplayCAL files of real
//! monitors and judged on their mixed patches, this spread lowered the mean error on six (by
//! 5–19 %) against plain PLVC and raised it on one (by 15 %, a white 0.9 % darker than the
//! sum whose greys are additive within their noise); a product of the shares (l_r l_g l_b) or
//! the smallest share did less well (`tests/display/ramp_fit.rs`, `print_white_share_study`).
//!
//! The model is stored as the grid LUT of [`super::Lut3d`] over the ramps' own levels, each
//! node the additive sum above: tetrahedral interpolation of a sum of per-axis terms is the
//! sum of their piecewise-linear interpolations, so the table is PLVC exactly, and the LUT's
//! inverse and ICC export serve it unchanged. Interpolation runs in the shaper's domain (the
//! channel's ramp, as for the LUT), where the channel's light is nearly linear.

use super::error::FitError;
use super::plcc::{black_and_primaries, ramp_points, singular};
use super::samples::{SortedSamples, CHANNEL_NAMES};
use super::trc::fit_power_gamma;
use super::{condition_number, Lut3d, ModelKind, Trc, MAX_CONDITION};

/// Most ramp levels per axis the table keeps (a 33³ grid, 36k nodes): a denser ramp is
/// thinned to this many levels spread over its measured ones, 0 and 1 always kept.
pub const MAX_LEVELS: usize = 33;

/// Fits PLVC to the black, the full-on primaries and each channel's ramp.
pub fn fit_plvc(set: &SortedSamples) -> Result<Lut3d, FitError> {
    let kind = ModelKind::Plvc;
    let (black, m) = black_and_primaries(set, kind)?;
    let cond = condition_number(&m);
    if cond > MAX_CONDITION {
        return Err(singular(cond));
    }
    if let Some(c) = (0..3).find(|&c| set.intermediate_levels(c) == 0) {
        return Err(FitError::Missing {
            model: kind,
            what: format!(
                "a {} ramp (patches with only {} on, between 0 and 1) to interpolate its light",
                CHANNEL_NAMES[c], CHANNEL_NAMES[c]
            ),
        });
    }
    // Per channel: (drive, light above black) from 0 to 1.
    let contributions: [Vec<(f64, [f64; 3])>; 3] = std::array::from_fn(|c| {
        let mut v = vec![(0.0, [0.0; 3])];
        v.extend(
            set.ramps[c]
                .iter()
                .map(|(d, xyz)| (*d, std::array::from_fn(|k| xyz[k] - black[k]))),
        );
        thin(v, MAX_LEVELS)
    });
    let levels: [Vec<f64>; 3] =
        std::array::from_fn(|c| contributions[c].iter().map(|p| p.0).collect());
    // The white's departure from the additive sum, and each level's luminance share.
    let departure: [f64; 3] = set.white.map_or([0.0; 3], |w| {
        std::array::from_fn(|k| w[k] - black[k] - (0..3).map(|c| m[k][c]).sum::<f64>())
    });
    let share = |c: usize, light: &[f64; 3]| (light[1] / m[1][c]).clamp(0.0, 1.0);
    let (ng, nb) = (levels[1].len(), levels[2].len());
    let mut nodes = Vec::with_capacity(levels[0].len() * ng * nb);
    for (_, r) in &contributions[0] {
        for (_, g) in &contributions[1] {
            for (_, b) in &contributions[2] {
                let l = [share(0, r), share(1, g), share(2, b)];
                let shared = (l[0] + l[1] + l[2] - l[0].max(l[1]).max(l[2])) / 2.0;
                nodes.push(std::array::from_fn(|k| {
                    black[k] + r[k] + g[k] + b[k] + shared * departure[k]
                }));
            }
        }
    }
    // The ramp through every level shapes the axis; where noise near black makes the
    // monotone table flat between two levels, a power law (always rising) does instead.
    let points: [Vec<(f64, f64)>; 3] = std::array::from_fn(|c| ramp_points(set, black, &m, c));
    let table: [Trc; 3] = std::array::from_fn(|c| Trc::table_from_ramp(&points[c]));
    Lut3d::from_parts(levels.clone(), table, nodes.clone())
        .or_else(|_| {
            let power = std::array::from_fn(|c| Trc::Power {
                gamma: fit_power_gamma(&points[c]),
            });
            Lut3d::from_parts(levels, power, nodes)
        })
        .map_err(|message| FitError::Failed {
            model: kind,
            message,
        })
}

/// At most `max` of the points, evenly spread by index, the first and last always kept.
fn thin<T: Copy>(points: Vec<T>, max: usize) -> Vec<T> {
    let n = points.len();
    if n <= max || max < 2 {
        return points;
    }
    (0..max)
        .map(|i| points[(i * (n - 1) + (max - 1) / 2) / (max - 1)])
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::color::Xyz;
    use crate::display::model::{DisplayModel, Sample};

    /// A display whose red drifts from its primary's chromaticity towards a bluish leak as
    /// it dims, with additive channels: PLVC reproduces every ramp reading and, by hand, a
    /// mixture at measured levels is black plus the three channels' light above black.
    #[test]
    fn reproduces_ramps_and_adds_their_light_in_mixtures() {
        let black = [0.2, 0.21, 0.3];
        let channel = |c: usize, d: f64| -> [f64; 3] {
            let y = d.powf(2.2);
            match c {
                0 => [40.0 * y + 2.0 * d, 20.0 * y, 2.0 * y + 3.0 * d * (1.0 - d)],
                1 => [35.0 * y, 70.0 * y, 12.0 * y],
                _ => [18.0 * y, 7.0 * y, 95.0 * y],
            }
        };
        let mut patches = vec![Sample {
            rgb: [0.0; 3],
            xyz: black.into(),
        }];
        for c in 0..3 {
            for k in 1..=8 {
                let d = k as f64 / 8.0;
                let mut rgb = [0.0; 3];
                rgb[c] = d;
                let l = channel(c, d);
                patches.push(Sample {
                    rgb,
                    xyz: Xyz::from(std::array::from_fn::<f64, 3, _>(|i| black[i] + l[i])),
                });
            }
        }
        let lut = fit_plvc(&SortedSamples::new(&patches)).unwrap();
        for p in &patches {
            let f = lut.forward(p.rgb);
            for k in 0..3 {
                assert!((f[k] - p.xyz[k]).abs() < 1e-9, "{:?}: {f:?}", p.rgb);
            }
        }
        let (r, g, b) = (channel(0, 0.5), channel(1, 0.25), channel(2, 0.75));
        let f = lut.forward([0.5, 0.25, 0.75]);
        for k in 0..3 {
            let hand = black[k] + r[k] + g[k] + b[k];
            assert!((f[k] - hand).abs() < 1e-9, "{f:?}");
        }
        // Without a white the model is additive; this one has none.
        assert!(SortedSamples::new(&patches).white.is_none());
        // The inverse finds the mixture's drive values again.
        let back = lut.inverse(f);
        for (got, want) in back.rgb.iter().zip([0.5, 0.25, 0.75]) {
            assert!((got - want).abs() < 1e-6, "{:?}", back.rgb);
        }
    }

    /// A white 5 % darker than the sum of the channels (in every component): the model
    /// passes through it and the ramps, and at a grey whose channels each give a quarter of
    /// their full light it adds a quarter of the departure. By hand: the share is
    /// (¼ + ¼ + ¼ − ¼)/2 = ¼.
    #[test]
    fn passes_through_the_white_and_spreads_its_departure_by_shared_light() {
        let primaries = [[40.0, 20.0, 2.0], [35.0, 70.0, 12.0], [18.0, 7.0, 95.0]];
        let black = [0.2, 0.2, 0.3];
        let mut patches = vec![Sample {
            rgb: [0.0; 3],
            xyz: black.into(),
        }];
        for (c, p) in primaries.iter().enumerate() {
            for k in 1..=4 {
                let d = k as f64 / 4.0;
                let mut rgb = [0.0; 3];
                rgb[c] = d;
                // Luminance share (d²)… at d = ½ a quarter of the full light.
                let y = d * d;
                patches.push(Sample {
                    rgb,
                    xyz: Xyz::from(std::array::from_fn::<f64, 3, _>(|i| black[i] + y * p[i])),
                });
            }
        }
        let sum: [f64; 3] =
            std::array::from_fn(|i| black[i] + (0..3).map(|c| primaries[c][i]).sum::<f64>());
        let white: [f64; 3] = std::array::from_fn(|i| black[i] + 0.95 * (sum[i] - black[i]));
        patches.push(Sample {
            rgb: [1.0; 3],
            xyz: white.into(),
        });
        let lut = fit_plvc(&SortedSamples::new(&patches)).unwrap();
        for p in &patches {
            let f = lut.forward(p.rgb);
            for k in 0..3 {
                assert!((f[k] - p.xyz[k]).abs() < 1e-9, "{:?}: {f:?}", p.rgb);
            }
        }
        let f = lut.forward([0.5; 3]);
        for k in 0..3 {
            let additive = black[k] + (0..3).map(|c| 0.25 * primaries[c][k]).sum::<f64>();
            let hand = additive + 0.25 * (white[k] - sum[k]);
            assert!((f[k] - hand).abs() < 1e-9, "{f:?} vs {hand}");
        }
    }

    #[test]
    fn thinning_keeps_the_ends_and_spreads_the_rest() {
        let v: Vec<usize> = (0..=100).collect();
        let t = thin(v, 5);
        assert_eq!(t, vec![0, 25, 50, 75, 100]);
        assert_eq!(thin(vec![1, 2, 3], 5), vec![1, 2, 3]);
    }

    #[test]
    fn refuses_a_channel_without_a_ramp() {
        let p = |rgb: [f64; 3], xyz: [f64; 3]| Sample {
            rgb,
            xyz: xyz.into(),
        };
        let patches = vec![
            p([0.0; 3], [0.1; 3]),
            p([1.0, 0.0, 0.0], [40.0, 20.0, 2.0]),
            p([0.5, 0.0, 0.0], [9.0, 4.5, 0.5]),
            p([0.0, 1.0, 0.0], [35.0, 70.0, 12.0]),
            p([0.0, 0.5, 0.0], [8.0, 16.0, 3.0]),
            p([0.0, 0.0, 1.0], [18.0, 7.0, 95.0]),
        ];
        let err = fit_plvc(&SortedSamples::new(&patches)).unwrap_err();
        assert!(err.to_string().contains("blue ramp"), "{err}");
    }
}
