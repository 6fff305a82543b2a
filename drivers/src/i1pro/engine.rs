//! From shots to calibrated spectra: the dark and white calibrations, the emissive
//! integration-time search, and each mode's pipeline (the codec's pure functions, run in
//! the order the instrument needs them).

use metamer_protocols::i1pro::pipeline::{self, AbsRaw, Averaged, Exposure};
use metamer_protocols::i1pro::{Calibration, Gain, RawReading, Spectrum};

use super::error::I1ProError;
use super::wire::{Shot, Wire};
use crate::link::usb::UsbLink;
use crate::DriverError;

/// The long dark of an emissive calibration, seconds: with the one at the shortest
/// integration time it gives the dark at any time by the codec's linear interpolation.
pub const DARK_LONG_S: f64 = 2.0;
/// Readings averaged in a dark at the shortest integration time.
pub const DARK_READINGS: usize = 8;
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

/// The two darks an emissive calibration takes, from which any integration time's dark is
/// interpolated.
#[derive(Clone, Debug)]
pub struct DarkPair {
    pub short: (AbsRaw, f64),
    pub long: (AbsRaw, f64),
}

impl DarkPair {
    pub fn at(&self, t: f64) -> Result<AbsRaw, I1ProError> {
        Ok(pipeline::interpolate_dark(
            &self.short.0,
            self.short.1,
            &self.long.0,
            self.long.1,
            t,
        )?)
    }
}

/// A finished emissive or reflective shot: the resampled spectrum and what averaging saw.
pub struct Processed {
    pub spectrum: Spectrum,
    pub averaged: Averaged,
    pub integration_s: f64,
    /// The largest dark-subtracted count of any cell.
    pub peak_counts: f64,
}

fn exposure(t: f64) -> Exposure {
    Exposure {
        integration_s: t,
        gain: Gain::Normal,
    }
}

/// The integration time the instrument really uses for `t`: a whole number of clocks.
pub fn quantize<L: UsbLink>(wire: &Wire<L>, t: f64) -> f64 {
    (t / wire.clock_s).round().max(1.0) * wire.clock_s
}

/// The longest integration time: the EEPROM's, or less where the request cannot carry it
/// (65535 clocks on Rev A–D).
pub fn longest<L: UsbLink>(wire: &Wire<L>, cal: &Calibration) -> f64 {
    let clocks = (cal.max_integration_s / wire.clock_s).floor();
    let limit = match wire.revision {
        metamer_protocols::i1pro::Revision::AToD => f64::from(u16::MAX),
        metamer_protocols::i1pro::Revision::E => f64::from(u32::MAX),
    };
    clocks.min(limit) * wire.clock_s
}

/// Takes a dark of `readings` at `t` and checks it saw no light.
pub fn dark<L: UsbLink>(
    wire: &mut Wire<L>,
    cal: &Calibration,
    t: f64,
    readings: usize,
) -> Result<AbsRaw, DriverError> {
    let t = quantize(wire, t);
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
    Ok(avg.mean)
}

/// The emissive (and ambient) dark calibration.
pub fn dark_pair<L: UsbLink>(
    wire: &mut Wire<L>,
    cal: &Calibration,
) -> Result<DarkPair, DriverError> {
    let t1 = quantize(wire, cal.min_integration_s);
    let t2 = quantize(wire, DARK_LONG_S.min(longest(wire, cal)));
    let short = dark(wire, cal, t1, DARK_READINGS)?;
    let long = dark(wire, cal, t2, 1)?;
    Ok(DarkPair {
        short: (short, t1),
        long: (long, t2),
    })
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
    let e = exposure(t);
    let (spectrum, averaged) = pipeline::measure(cal, &raw, dark, &e).map_err(I1ProError::from)?;
    Ok(Processed {
        spectrum,
        peak_counts: averaged.highest * t,
        averaged,
        integration_s: t,
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
/// target follows by proportion. The light may be too bright (saturating at the shortest
/// time) or too dark (the peak at the longest time below the dark threshold, the sensor's
/// noise floor): both are errors that say what to do, never a wrong spectrum.
pub fn emissive_shot<L: UsbLink>(
    wire: &mut Wire<L>,
    cal: &Calibration,
    darks: &DarkPair,
    fixed: Option<f64>,
) -> Result<Processed, DriverError> {
    let min = quantize(wire, cal.min_integration_s);
    let max = longest(wire, cal);
    let floor = |t: f64| f64::from(cal.dark_threshold) + 900.0 * t;
    if let Some(t) = fixed {
        let t = quantize(wire, t);
        let p = process(wire, cal, t, readings_for(t), false, &darks.at(t)?)?;
        if p.averaged.saturated {
            return Err(I1ProError::SaturatedAtFixedTime { integration_s: t }.into());
        }
        return check(p);
    }
    let mut t = quantize(wire, TRIAL_S.clamp(min, max));
    let mut trial = process(wire, cal, t, 1, false, &darks.at(t)?)?;
    if trial.averaged.saturated && t > min {
        t = min;
        trial = process(wire, cal, t, 1, false, &darks.at(t)?)?;
    }
    if trial.averaged.saturated {
        return Err(I1ProError::TooBright { min_s: min }.into());
    }
    let rate = trial.peak_counts.max(0.0) / t;
    let want = if rate > 0.0 {
        f64::from(cal.sensor_target) / rate
    } else {
        max
    };
    let t = quantize(wire, want.clamp(min, max)).min(max);
    let p = process(wire, cal, t, readings_for(t), false, &darks.at(t)?)?;
    if p.averaged.saturated {
        // The light grew between the trial and the measurement.
        return Err(I1ProError::TooBright { min_s: min }.into());
    }
    if p.peak_counts < floor(t) && t >= max * 0.999 {
        return Err(I1ProError::TooDark {
            max_s: max,
            signal: p.peak_counts,
            floor: floor(t),
        }
        .into());
    }
    check(p)
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
) -> Result<Spectrum, DriverError> {
    let t = quantize(wire, REFLECTIVE_S);
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
    factors: &Spectrum,
) -> Result<(Spectrum, Processed), DriverError> {
    let t = quantize(wire, REFLECTIVE_S);
    let p = check(process(wire, cal, t, REFLECTIVE_READINGS, true, dark)?)?;
    Ok((pipeline::reflective(&p.spectrum, factors), p))
}
