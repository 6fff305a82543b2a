//! The fit input: measured samples (drive values and the XYZ they gave), and their sorting
//! into what the models need: black, full-on primaries, white, single-channel ramps.
//! Repeated samples are averaged; everything else stays available for fitting and residuals.

use serde::{Deserialize, Serialize};

use crate::color::Xyz;

/// One measurement of a display: drive values 0–1 per channel and the XYZ measured, cd/m².
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Sample {
    pub rgb: [f64; 3],
    pub xyz: Xyz,
}

impl Sample {
    /// A sample of 8-bit drive values (each code c is the drive c/255) and the XYZ read
    /// with them shown: how every reading of a characterization becomes a sample.
    pub fn from_rgb8(rgb8: [u8; 3], xyz: Xyz) -> Sample {
        Sample {
            rgb: rgb8.map(|c| f64::from(c) / 255.0),
            xyz,
        }
    }
}

/// Drive values closer than this count as equal (finer than a 16-bit step).
pub const SAME_DRIVE: f64 = 1e-6;

/// Black, white, primaries and ramps of a set of samples, each averaged over repeats.
#[derive(Clone, Debug, Default)]
pub struct SortedSamples {
    pub black: Option<Xyz>,
    pub white: Option<Xyz>,
    /// Full-on red, green, blue alone.
    pub primaries: [Option<Xyz>; 3],
    /// Per channel: (drive, XYZ) with only that channel on, drive in (0, 1], sorted, averaged.
    pub ramps: [Vec<(f64, Xyz)>; 3],
    /// Readings averaged into each ramp entry (the last, at drive 1, is the primary).
    pub ramp_readings: [Vec<usize>; 3],
    /// Readings averaged into the white.
    pub white_readings: usize,
    /// Readings averaged into the black.
    pub black_readings: usize,
}

fn is(v: f64, target: f64) -> bool {
    (v - target).abs() < SAME_DRIVE
}

fn mean(xs: &[Xyz]) -> Option<Xyz> {
    if xs.is_empty() {
        return None;
    }
    let n = xs.len() as f64;
    let component = |c: usize| xs.iter().map(|x| x[c]).sum::<f64>() / n;
    Some(Xyz::new(component(0), component(1), component(2)))
}

impl SortedSamples {
    pub fn new(patches: &[Sample]) -> SortedSamples {
        let pick = |f: &dyn Fn(&Sample) -> bool| -> Vec<Xyz> {
            patches.iter().filter(|p| f(p)).map(|p| p.xyz).collect()
        };
        let blacks = pick(&|p| p.rgb.iter().all(|&d| is(d, 0.0)));
        let black = mean(&blacks);
        let whites = pick(&|p| p.rgb.iter().all(|&d| is(d, 1.0)));
        let white = mean(&whites);
        let mut ramps: [Vec<(f64, Xyz)>; 3] = Default::default();
        let mut ramp_readings: [Vec<usize>; 3] = Default::default();
        for (c, ramp) in ramps.iter_mut().enumerate() {
            let mut pts: Vec<(f64, Xyz)> = patches
                .iter()
                .filter(|p| {
                    p.rgb[c] > SAME_DRIVE && (0..3).filter(|&o| o != c).all(|o| is(p.rgb[o], 0.0))
                })
                .map(|p| (p.rgb[c], p.xyz))
                .collect();
            pts.sort_by(|a, b| a.0.total_cmp(&b.0));
            let mut i = 0;
            while i < pts.len() {
                let mut j = i;
                while j < pts.len() && is(pts[j].0, pts[i].0) {
                    j += 1;
                }
                let xyz: Vec<Xyz> = pts[i..j].iter().map(|p| p.1).collect();
                ramp.push((pts[i].0, mean(&xyz).expect("non-empty group")));
                ramp_readings[c].push(j - i);
                i = j;
            }
        }
        let primaries = std::array::from_fn(|c| {
            ramps[c]
                .last()
                .filter(|(d, _)| is(*d, 1.0))
                .map(|(_, xyz)| *xyz)
        });
        SortedSamples {
            black,
            white,
            primaries,
            ramps,
            ramp_readings,
            white_readings: whites.len(),
            black_readings: blacks.len(),
        }
    }

    /// Ramp levels strictly between 0 and 1 for a channel.
    pub fn intermediate_levels(&self, channel: usize) -> usize {
        self.ramps[channel]
            .iter()
            .filter(|(d, _)| *d < 1.0 - SAME_DRIVE)
            .count()
    }
}

pub const CHANNEL_NAMES: [&str; 3] = ["red", "green", "blue"];

/// A seeded scramble of patch indices, so folds do not follow the file's order (files
/// list ramps and greys in blocks).
pub fn fold_of(i: usize) -> usize {
    let mut x = (i as u64).wrapping_add(0x9E37_79B9_7F4A_7C15);
    x = (x ^ (x >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    (x ^ (x >> 31)) as usize
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sorts_and_averages() {
        let p = |rgb: [f64; 3], y: f64| Sample {
            rgb,
            xyz: Xyz::new(y, y, y),
        };
        let set = SortedSamples::new(&[
            p([0.0, 0.0, 0.0], 1.0),
            p([0.0, 0.0, 0.0], 3.0),
            p([1.0, 1.0, 1.0], 100.0),
            p([1.0, 0.0, 0.0], 20.0),
            p([0.5, 0.0, 0.0], 5.0),
            p([0.5, 0.0, 0.0], 7.0),
            p([0.5, 0.5, 0.0], 9.0),
        ]);
        assert_eq!(set.black, Some(Xyz::new(2.0, 2.0, 2.0)));
        assert_eq!(set.white, Some(Xyz::new(100.0, 100.0, 100.0)));
        assert_eq!(
            set.primaries,
            [Some(Xyz::new(20.0, 20.0, 20.0)), None, None]
        );
        assert_eq!(
            set.ramps[0],
            vec![
                (0.5, Xyz::new(6.0, 6.0, 6.0)),
                (1.0, Xyz::new(20.0, 20.0, 20.0))
            ]
        );
        assert_eq!(set.ramp_readings[0], vec![2, 1]);
        assert_eq!(set.white_readings, 1);
        assert_eq!(set.intermediate_levels(0), 1);
        assert!(set.ramps[1].is_empty());
    }
}
