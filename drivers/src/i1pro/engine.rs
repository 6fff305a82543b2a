//! From shots to calibrated spectra: the dark and white calibrations, the emissive
//! integration-time search, and each mode's pipeline (the codec's pure functions, run in
//! the order the instrument needs them).

use metamer_protocols::i1pro::pipeline::{self, AbsRaw, Averaged, Exposure};
use metamer_protocols::i1pro::{Calibration, Gain, GridSpectrum, RawReading, Revision, CELLS};

use super::error::I1ProError;
use super::wire::{Shot, Wire};
use crate::link::usb::UsbLink;
use crate::DriverError;

/// The long dark of an emissive calibration and the longest integration the driver uses,
/// seconds (ArgyllCMS's adaptive emissive mode aims at no more than 2 s, and its display
/// mode integrates 2 s): every emissive time lies between the two darks, so its dark is
/// interpolated, never extrapolated.
pub const DARK_LONG_S: f64 = 2.0;
/// Readings in the long dark. With one reading of 2 s in a dim light's measurement, nine
/// in the dark keep its noise at a third of the measurement's (see [`DarkPair::noise`]).
pub const DARK_LONG_READINGS: usize = 9;
/// The short dark integrates this long in all, over readings at the shortest time, seconds
/// (ArgyllCMS: one second of dark at each time it interpolates from).
pub const DARK_SHORT_TOTAL_S: f64 = 1.0;
/// Reflective readings integrate this long with the lamp lit, seconds [I: the lamp and the
/// white tile give counts near the sensor target in about this time].
pub const REFLECTIVE_S: f64 = 0.02;
/// Readings averaged in a reflective shot (dark, white tile or sample).
pub const REFLECTIVE_READINGS: usize = 8;
/// The first emissive shot of an automatic integration, seconds.
pub const TRIAL_S: f64 = 0.1;
/// An emissive measurement integrates about this long in all, over several readings,
/// seconds.
pub const EMISSIVE_TOTAL_S: f64 = 0.8;
/// At most this many readings in one emissive shot.
pub const MAX_READINGS: usize = 16;
/// A light is too dark when its counts summed over the cells stay within this many
/// standard deviations of the sensor's noise at the longest time.
pub const TOO_DARK_SIGMAS: f64 = 5.0;
/// A light too dim for one reading at the longest time is read this many times at it in
/// all (12 s), so that a display's black and near-black patches are readings with their
/// larger uncertainty rather than errors: the floor falls to √(1/6 + 1/9) / √(1 + 1/9) =
/// 0.53 of one reading's, which puts the ideal-crt preset's black (0.05 cd/m², 4.3σ of one
/// reading) 3.4σ above it; four readings would leave it 2.5σ above, and fail one black in
/// 160. ArgyllCMS reads a dim patch longer too (its
/// adaptive emissive mode integrates past 2 s up to the unit's maximum when the light is
/// far below the sensor target [C2 `i1pro_optimise_sensor`]); more readings at 2 s need no
/// other dark than the calibration's, whose noise then limits what further readings gain.
pub const DARK_PATCH_READINGS: usize = 6;
/// No reading is more precise than its rounding to whole counts: 1/√12 count.
const QUANTISATION_COUNTS: f64 = 0.288_675_134_594_812_9;

/// A dark reference: its mean, its integration time, how many readings it averages, and
/// the spread of one reading (counts, root mean square over the cells).
#[derive(Clone, Debug)]
pub struct Dark {
    pub mean: AbsRaw,
    pub integration_s: f64,
    pub readings: usize,
    pub sigma_counts: f64,
}

/// The two darks an emissive calibration takes, from which any integration time's dark is
/// interpolated.
#[derive(Clone, Debug)]
pub struct DarkPair {
    pub short: Dark,
    pub long: Dark,
}

/// The noise of one cell of an emissive measurement in the dark, counts (1σ).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CellNoise {
    /// Of the measurement's mean of readings: what the light has to rise above.
    pub floor: f64,
    /// Of the interpolated dark subtracted from it: the same offset in every measurement
    /// until the next calibration.
    pub dark: f64,
}

impl DarkPair {
    pub fn at(&self, t: f64) -> Result<AbsRaw, I1ProError> {
        Ok(pipeline::interpolate_dark(
            &self.short.mean,
            self.short.integration_s,
            &self.long.mean,
            self.long.integration_s,
            t,
        )?)
    }

    /// The noise budget at integration time `t` with `readings` readings: the noise of one
    /// reading grows linearly in variance from the short dark's to the long one's (read
    /// noise plus the dark current's shot noise), and the interpolated dark
    /// `(1 − w)·d₁ + w·d₂`, `w = (t − t₁)/(t₂ − t₁)`, carries `(1 − w)²σ₁²/n₁ + w²σ₂²/n₂`.
    pub fn noise(&self, t: f64, readings: usize) -> CellNoise {
        let (s, l) = (&self.short, &self.long);
        let w = ((t - s.integration_s) / (l.integration_s - s.integration_s)).clamp(0.0, 1.0);
        let (v1, v2) = (s.sigma_counts.powi(2), l.sigma_counts.powi(2));
        let one = (v1 + (v2 - v1) * w).max(QUANTISATION_COUNTS.powi(2));
        let dark = (1.0 - w).powi(2) * v1 / s.readings as f64 + w.powi(2) * v2 / l.readings as f64;
        CellNoise {
            floor: (one / readings.max(1) as f64).sqrt(),
            dark: dark.sqrt(),
        }
    }
}

/// A finished emissive or reflective shot: the resampled spectrum and what averaging saw.
pub struct Processed {
    /// The raw readings, so that more readings of the same exposure can join them.
    pub raw: Vec<RawReading>,
    pub spectrum: GridSpectrum,
    pub averaged: Averaged,
    pub integration_s: f64,
    pub readings: usize,
    /// The largest dark-subtracted count of any cell.
    pub peak_counts: f64,
    /// The dark-subtracted counts of the mean reading summed over the cells that carry
    /// light (1–126 on Rev A–D, all 128 on Rev E).
    pub signal_counts: f64,
}

fn exposure(t: f64) -> Exposure {
    Exposure {
        integration_s: t,
        gain: Gain::Normal,
    }
}

fn used_cells(revision: Revision) -> std::ops::Range<usize> {
    match revision {
        Revision::AToD => 1..CELLS - 1,
        Revision::E => 0..CELLS,
    }
}

/// The integration time the instrument really uses for `t`: a whole number of clocks of
/// the clock mode that runs it.
pub fn quantize<L: UsbLink>(wire: &Wire<L>, t: f64) -> Result<f64, I1ProError> {
    Ok(wire.plan(t)?.integration_s)
}

/// The shortest integration time: one sub-clock of the unit's finest clock mode. As
/// ArgyllCMS, the driver goes by the clock, not by the EEPROM's minimum (key 0x04C5).
pub fn shortest<L: UsbLink>(wire: &Wire<L>) -> Result<f64, I1ProError> {
    quantize(wire, wire.shortest_s())
}

/// The longest integration time: [`DARK_LONG_S`], or the EEPROM's maximum if that is
/// shorter.
pub fn longest<L: UsbLink>(wire: &Wire<L>, cal: &Calibration) -> Result<f64, I1ProError> {
    quantize(wire, DARK_LONG_S.min(cal.max_integration_s))
}

/// Takes a dark of `readings` at `t` and checks it saw no light.
pub fn dark<L: UsbLink>(
    wire: &mut Wire<L>,
    cal: &Calibration,
    t: f64,
    readings: usize,
) -> Result<Dark, DriverError> {
    let t = quantize(wire, t)?;
    let raw = wire.shot(Shot {
        integration_s: t,
        readings,
        lamp: false,
    })?;
    let e = exposure(t);
    let avg = pipeline::dark(cal, &raw, &e).map_err(I1ProError::from)?;
    let (_, threshold) = pipeline::thresholds(cal, &e, &raw).map_err(I1ProError::from)?;
    if avg.too_bright_for_dark(threshold) {
        let m = &avg.mean.cells[1..avg.mean.cells.len() - 1];
        return Err(I1ProError::DarkNotDark {
            mean: m.iter().sum::<f64>() / m.len() as f64,
            limit: 2.0 * threshold,
        }
        .into());
    }
    let sigma_counts = spread_counts(cal, &raw, &e, &avg.mean)?;
    Ok(Dark {
        mean: avg.mean,
        integration_s: t,
        readings,
        sigma_counts,
    })
}

/// The spread of one reading about the mean, counts: the root of the cells' mean sample
/// variance (0 for a single reading, which shows none).
fn spread_counts(
    cal: &Calibration,
    raw: &[RawReading],
    e: &Exposure,
    mean: &AbsRaw,
) -> Result<f64, I1ProError> {
    if raw.len() < 2 {
        return Ok(0.0);
    }
    let cells = used_cells(cal.revision());
    let mut sum = 0.0;
    for r in raw {
        let a = pipeline::to_absraw(cal, r, e)?;
        for j in cells.clone() {
            sum += ((a.cells[j] - mean.cells[j]) * e.integration_s).powi(2);
        }
    }
    Ok((sum / ((raw.len() - 1) * cells.len()) as f64).sqrt())
}

/// The emissive (and ambient) dark calibration: [`DARK_SHORT_TOTAL_S`] of readings at the
/// shortest time and [`DARK_LONG_READINGS`] at the longest.
pub fn dark_pair<L: UsbLink>(
    wire: &mut Wire<L>,
    cal: &Calibration,
) -> Result<DarkPair, DriverError> {
    let t1 = shortest(wire)?;
    let t2 = longest(wire, cal)?;
    let n1 = ((DARK_SHORT_TOTAL_S / t1).round() as usize).clamp(1, usize::from(u16::MAX));
    let short = dark(wire, cal, t1, n1)?;
    let long = dark(wire, cal, t2, DARK_LONG_READINGS)?;
    Ok(DarkPair { short, long })
}

/// One shot through steps 1–5 of the pipeline.
pub fn process<L: UsbLink>(
    wire: &mut Wire<L>,
    cal: &Calibration,
    t: f64,
    readings: usize,
    lamp: bool,
    dark: &AbsRaw,
) -> Result<Processed, DriverError> {
    let raw: Vec<RawReading> = wire.shot(Shot {
        integration_s: t,
        readings,
        lamp,
    })?;
    processed(cal, raw, t, dark)
}

/// Steps 1–5 of the pipeline on the readings of one exposure at `t`.
fn processed(
    cal: &Calibration,
    raw: Vec<RawReading>,
    t: f64,
    dark: &AbsRaw,
) -> Result<Processed, DriverError> {
    let readings = raw.len();
    let e = exposure(t);
    let (spectrum, averaged) = pipeline::measure(cal, &raw, dark, &e).map_err(I1ProError::from)?;
    let signal_counts = averaged.mean.cells[used_cells(cal.revision())]
        .iter()
        .sum::<f64>()
        * t;
    Ok(Processed {
        raw,
        spectrum,
        peak_counts: averaged.highest * t,
        signal_counts,
        averaged,
        integration_s: t,
        readings,
    })
}

/// Readings for an emissive shot at `t`: about [`EMISSIVE_TOTAL_S`] in all.
pub fn readings_for(t: f64) -> usize {
    ((EMISSIVE_TOTAL_S / t).floor() as usize).clamp(1, MAX_READINGS)
}

/// An emissive (or ambient) shot, the integration time either fixed or found.
///
/// The search: a trial reading at [`TRIAL_S`] (at the shortest time if that saturates)
/// gives the peak count per second, and the time that puts the peak at the EEPROM's sensor
/// target follows by proportion, within the shortest and the longest time. The light may
/// be too bright (saturating at the shortest time) or too dark (at the longest time, its
/// counts summed over the cells within [`TOO_DARK_SIGMAS`] of the sensor's noise, as
/// the dark calibration measured it): both are errors that say what to do, never a wrong
/// spectrum. A dim light above that floor is measured, noisy as it is: a display's black
/// is a reading, not an error.
pub fn emissive_shot<L: UsbLink>(
    wire: &mut Wire<L>,
    cal: &Calibration,
    darks: &DarkPair,
    fixed: Option<f64>,
) -> Result<Processed, DriverError> {
    let min = shortest(wire)?;
    let max = longest(wire, cal)?;
    let one_mode = wire.modes.len() == 1;
    let too_bright = || I1ProError::TooBright {
        min_s: min,
        one_mode,
    };
    if let Some(t) = fixed {
        let t = quantize(wire, t.clamp(min, max))?;
        let p = process(wire, cal, t, readings_for(t), false, &darks.at(t)?)?;
        if p.averaged.saturated {
            return Err(I1ProError::SaturatedAtFixedTime { integration_s: t }.into());
        }
        return check(p);
    }
    let mut t = quantize(wire, TRIAL_S.clamp(min, max))?;
    let mut trial = process(wire, cal, t, 1, false, &darks.at(t)?)?;
    if trial.averaged.saturated && t > min {
        t = min;
        trial = process(wire, cal, t, 1, false, &darks.at(t)?)?;
    }
    if trial.averaged.saturated {
        return Err(too_bright().into());
    }
    let rate = trial.peak_counts.max(0.0) / t;
    let want = if rate > 0.0 {
        f64::from(cal.sensor_target) / rate
    } else {
        max
    };
    let t = quantize(wire, want.clamp(min, max))?;
    let p = process(wire, cal, t, readings_for(t), false, &darks.at(t)?)?;
    if p.averaged.saturated {
        // The light grew between the trial and the measurement.
        return Err(too_bright().into());
    }
    if t >= max * 0.999 {
        return check(dim(wire, cal, darks, p, max)?);
    }
    check(p)
}

/// The light's noise floor at `t` over `readings`: [`TOO_DARK_SIGMAS`] standard deviations
/// of the sum over the cells of the readings' mean, the subtracted dark's noise included.
fn too_dark_floor(darks: &DarkPair, cal: &Calibration, t: f64, readings: usize) -> f64 {
    let noise = darks.noise(t, readings);
    let cells = used_cells(cal.revision()).len() as f64;
    TOO_DARK_SIGMAS * (noise.floor.powi(2) + noise.dark.powi(2)).sqrt() * cells.sqrt()
}

/// A reading at the longest time `t`: kept when its light stands above the noise floor;
/// otherwise, when more readings could lift it above theirs, read [`DARK_PATCH_READINGS`]
/// times in all (a display's black); "too dark" when it still does not stand out. Where
/// even a first reading one standard deviation higher could not reach the lower floor of
/// the longer measurement, nothing is gained by it (a capped sensor, a meter facing away).
fn dim<L: UsbLink>(
    wire: &mut Wire<L>,
    cal: &Calibration,
    darks: &DarkPair,
    p: Processed,
    t: f64,
) -> Result<Processed, DriverError> {
    let floor = too_dark_floor(darks, cal, t, p.readings);
    if p.signal_counts >= floor {
        return Ok(p);
    }
    let sigma = floor / TOO_DARK_SIGMAS;
    let longer = too_dark_floor(darks, cal, t, DARK_PATCH_READINGS.max(p.readings));
    let p = if p.readings < DARK_PATCH_READINGS && p.signal_counts + sigma >= longer {
        let more = wire.shot(Shot {
            integration_s: t,
            readings: DARK_PATCH_READINGS - p.readings,
            lamp: false,
        })?;
        let mut raw = p.raw;
        raw.extend(more);
        processed(cal, raw, t, &darks.at(t)?)?
    } else {
        p
    };
    let floor = too_dark_floor(darks, cal, t, p.readings);
    if p.signal_counts < floor {
        return Err(I1ProError::TooDark {
            max_s: t,
            readings: p.readings,
            signal: p.signal_counts,
            floor,
        }
        .into());
    }
    Ok(p)
}

fn check(p: Processed) -> Result<Processed, DriverError> {
    if p.averaged.inconsistent {
        return Err(I1ProError::Inconsistent.into());
    }
    Ok(p)
}

/// The white calibration: a lamp-lit shot of the tile, turned into reflective factors.
pub fn white<L: UsbLink>(
    wire: &mut Wire<L>,
    cal: &Calibration,
    dark: &AbsRaw,
) -> Result<GridSpectrum, DriverError> {
    let t = quantize(wire, REFLECTIVE_S)?;
    let p = process(wire, cal, t, REFLECTIVE_READINGS, true, dark)?;
    if p.averaged.saturated {
        return Err(I1ProError::BadWhite {
            problem: "saturated",
        }
        .into());
    }
    let mean = p.spectrum.iter().sum::<f64>() / p.spectrum.len() as f64;
    if mean < pipeline::MIN_WHITE_READING {
        return Err(I1ProError::BadWhite {
            problem: "too dim (the lamp seems not to light it)",
        }
        .into());
    }
    let p = check(p)?;
    Ok(pipeline::reflective_factors(cal, &p.spectrum).map_err(I1ProError::from)?)
}

/// A reflective shot of a sample: its reflectance, with the saturation flag.
pub fn reflective<L: UsbLink>(
    wire: &mut Wire<L>,
    cal: &Calibration,
    dark: &AbsRaw,
    factors: &GridSpectrum,
) -> Result<(GridSpectrum, Processed), DriverError> {
    let t = quantize(wire, REFLECTIVE_S)?;
    let p = check(process(wire, cal, t, REFLECTIVE_READINGS, true, dark)?)?;
    Ok((pipeline::reflective(&p.spectrum, factors), p))
}
