//! Raw readings → calibrated spectrum, step by step as pure functions, in the order a driver
//! runs them:
//!
//! 1. [`to_absraw`]: counts → "absolute raw" values (counts per second at unit gain). Rev A–D
//!    linearise the signed count first and replace the junk cells 0 and 127 by their
//!    neighbours; Rev E only scales (and keeps the mean of its shielded cells).
//! 2. [`subtract_dark`]: minus a dark reading of the same exposure. Rev E first corrects the
//!    dark for temperature drift with the shielded cells, then linearises.
//! 3. [`average`]: the mean of several readings with saturation and consistency flags.
//! 4. [`Filter::apply`](super::Filter::apply): resample 128 cells to 36 bands.
//! 5. [`stray_light`] (Rev E).
//! 6. [`emissive`], [`ambient`], [`reflective`] / [`transmissive`] with their factors.

use super::calibration::{Calibration, Gain, RevECalibration};
use super::readings::RawReading;
use super::{GridSpectrum, Revision, BANDS, CELLS};

/// How a reading was taken.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Exposure {
    pub integration_s: f64,
    pub gain: Gain,
}

/// One reading in counts per second at unit gain.
#[derive(Clone, Debug, PartialEq)]
pub struct AbsRaw {
    pub cells: [f64; CELLS],
    /// Mean of Rev E's shielded cells on the same scale; 0 on Rev A–D.
    pub shielded: f64,
}

/// Bad input to a pipeline step.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum PipelineError {
    #[error("integration time {0} s is not a positive number")]
    IntegrationTime(f64),
    #[error("the i1Pro 2 has no high gain")]
    NoHighGainOnRevE,
    #[error("a Rev {revision:?} reading {problem}")]
    Shape {
        revision: Revision,
        problem: &'static str,
    },
    #[error("two darks at the same integration time {0} s cannot be interpolated")]
    SameDarkTimes(f64),
    #[error("nothing to average: no readings")]
    NoReadings,
    #[error("this unit has no ambient calibration (no diffuser)")]
    NoAmbient,
    #[error("this unit has no white reference (an i1Monitor cannot measure reflectance)")]
    NoWhiteReference,
    #[error("{what} is zero in band {band} ({nm} nm): the spectrum cannot be recovered")]
    ZeroFactor {
        what: &'static str,
        band: usize,
        nm: f64,
    },
    #[error("the {0} matrix is singular")]
    Singular(&'static str),
}

/// Horner evaluation of `c0 + c1·v + c2·v² + …`.
pub fn linearise(poly: &[f64], v: f64) -> f64 {
    poly.iter().rev().fold(0.0, |acc, c| acc * v + c)
}

/// `1 / (t · g)`: multiplies counts into counts per second at unit gain.
pub fn scale(cal: &Calibration, e: &Exposure) -> Result<f64, PipelineError> {
    if !(e.integration_s.is_finite() && e.integration_s > 0.0) {
        return Err(PipelineError::IntegrationTime(e.integration_s));
    }
    if cal.revision() == Revision::E && e.gain == Gain::High {
        return Err(PipelineError::NoHighGainOnRevE);
    }
    Ok(1.0 / (e.integration_s * cal.gain_factor(e.gain)))
}

/// Step 1 for one reading.
pub fn to_absraw(cal: &Calibration, r: &RawReading, e: &Exposure) -> Result<AbsRaw, PipelineError> {
    let k = scale(cal, e)?;
    let mut cells = [0.0; CELLS];
    match (cal.revision(), &r.shielded) {
        (Revision::AToD, None) => {
            let poly = cal.linearisation(e.gain);
            for (a, &c) in cells.iter_mut().zip(&r.cells) {
                *a = linearise(poly, f64::from(c)) * k;
            }
            cells[0] = cells[1];
            cells[CELLS - 1] = cells[CELLS - 2];
            Ok(AbsRaw {
                cells,
                shielded: 0.0,
            })
        }
        (Revision::E, Some(s)) => {
            for (a, &c) in cells.iter_mut().zip(&r.cells) {
                *a = f64::from(c) * k;
            }
            let mean = s.iter().map(|&v| f64::from(v)).sum::<f64>() / s.len() as f64;
            Ok(AbsRaw {
                cells,
                shielded: mean * k,
            })
        }
        (revision, Some(_)) => Err(PipelineError::Shape {
            revision,
            problem: "has no shielded cells",
        }),
        (revision, None) => Err(PipelineError::Shape {
            revision,
            problem: "needs its shielded cells",
        }),
    }
}

/// Rev E's dark corrected for the sensor's drift since it was taken: with `s` the shielded
/// mean of the readings now and `s0` the dark's, a zero point `z = 1.144·(s + s0)/2` (raised
/// to at least 1.01 × each of `s`, `s0` and the largest dark cell) and
/// `dark'_j = z − (z − dark_j)·(z − s)/(z − s0)`. When `s == s0` it is the dark unchanged.
pub fn drift_corrected_dark(dark: &AbsRaw, shielded_now: f64) -> [f64; CELLS] {
    let dark_max = dark.cells.iter().copied().fold(f64::MIN, f64::max);
    let (s, s0) = (shielded_now, dark.shielded);
    let z = (1.144 * 0.5 * (s + s0))
        .max(1.01 * s)
        .max(1.01 * s0)
        .max(1.01 * dark_max);
    let mut out = [0.0; CELLS];
    for (o, &d) in out.iter_mut().zip(&dark.cells) {
        *o = z - (z - d) * (z - s) / (z - s0);
    }
    out
}

/// Step 2 for several readings of one exposure, in place.
pub fn subtract_dark(
    cal: &Calibration,
    readings: &mut [AbsRaw],
    dark: &AbsRaw,
    e: &Exposure,
) -> Result<(), PipelineError> {
    let k = scale(cal, e)?;
    match cal.revision() {
        Revision::AToD => {
            for r in readings.iter_mut() {
                for (c, d) in r.cells.iter_mut().zip(&dark.cells) {
                    *c -= d;
                }
            }
        }
        Revision::E => {
            if readings.is_empty() {
                return Ok(());
            }
            let s = readings.iter().map(|r| r.shielded).sum::<f64>() / readings.len() as f64;
            let adjusted = drift_corrected_dark(dark, s);
            let poly = cal.linearisation(e.gain);
            for r in readings.iter_mut() {
                for (c, d) in r.cells.iter_mut().zip(&adjusted) {
                    *c = linearise(poly, (*c - d) / k) * k;
                }
            }
        }
    }
    Ok(())
}

/// The dark for any integration time `t` from darks taken at two, `t1` and `t2` (emissive
/// spot measurements take them at the shortest time and at 4 s): per cell the dark count
/// grows linearly with time, `count(t) = a + b·t`, through the two measured points, and the
/// dark absraw at `t` is `count(t) / t` (gain cancels: all three share it).
pub fn interpolate_dark(
    d1: &AbsRaw,
    t1: f64,
    d2: &AbsRaw,
    t2: f64,
    t: f64,
) -> Result<AbsRaw, PipelineError> {
    for x in [t1, t2, t] {
        if !(x.is_finite() && x > 0.0) {
            return Err(PipelineError::IntegrationTime(x));
        }
    }
    if t1 == t2 {
        return Err(PipelineError::SameDarkTimes(t1));
    }
    let at = |v1: f64, v2: f64| {
        let (c1, c2) = (v1 * t1, v2 * t2);
        let b = (c2 - c1) / (t2 - t1);
        (c1 + b * (t - t1)) / t
    };
    let mut cells = [0.0; CELLS];
    for ((o, a), b) in cells.iter_mut().zip(&d1.cells).zip(&d2.cells) {
        *o = at(*a, *b);
    }
    Ok(AbsRaw {
        cells,
        shielded: at(d1.shielded, d2.shielded),
    })
}

/// The dark threshold in counts. Rev A–D: the EEPROM value plus 900 counts per second of
/// integration, times the gain factor in high gain (so on the absraw scale it does not
/// depend on the gain). Rev E: the mean raw count of the readings' shielded cells, which sit
/// in the dark whatever the light.
pub fn dark_threshold_counts(cal: &Calibration, e: &Exposure, readings: &[RawReading]) -> f64 {
    let shielded: Vec<f64> = readings
        .iter()
        .filter_map(|r| r.shielded)
        .flat_map(|s| s.map(f64::from))
        .collect();
    if cal.revision() == Revision::E && !shielded.is_empty() {
        return shielded.iter().sum::<f64>() / shielded.len() as f64;
    }
    (f64::from(cal.dark_threshold) + 900.0 * e.integration_s) * cal.gain_factor(e.gain)
}

/// The averaged readings and what was seen while averaging.
#[derive(Clone, Debug, PartialEq)]
pub struct Averaged {
    pub mean: AbsRaw,
    /// Largest single cell value (junk cells excluded on Rev A–D).
    pub highest: f64,
    /// Some cell of some reading exceeded the saturation threshold.
    pub saturated: bool,
    /// The readings' means spread by more than 10 % of their level.
    pub inconsistent: bool,
}

/// How far the readings' means may spread, relative to their level, before they are
/// inconsistent.
pub const CONSISTENCY_LIMIT: f64 = 0.1;

/// Step 3. Thresholds are on the absraw scale (counts × [`scale`]); `saturation` of `None`
/// checks nothing. The consistency check compares the spread of the per-reading means (over
/// cells 1–126 on Rev A–D, all on Rev E) with half the sum of the largest and smallest mean,
/// but with no less than twice the dark threshold so that dark readings are not judged by
/// their noise.
pub fn average(
    revision: Revision,
    readings: &[AbsRaw],
    saturation: Option<f64>,
    dark_threshold: f64,
) -> Result<Averaged, PipelineError> {
    if readings.is_empty() {
        return Err(PipelineError::NoReadings);
    }
    let used = match revision {
        Revision::AToD => 1..CELLS - 1,
        Revision::E => 0..CELLS,
    };
    let n = readings.len() as f64;
    let mut mean = AbsRaw {
        cells: [0.0; CELLS],
        shielded: 0.0,
    };
    let (mut highest, mut saturated) = (f64::MIN, false);
    let (mut lo, mut hi) = (f64::MAX, f64::MIN);
    for r in readings {
        for (m, v) in mean.cells.iter_mut().zip(&r.cells) {
            *m += v / n;
        }
        mean.shielded += r.shielded / n;
        let cells = &r.cells[used.clone()];
        let m = cells.iter().sum::<f64>() / cells.len() as f64;
        lo = lo.min(m);
        hi = hi.max(m);
        for &v in cells {
            highest = highest.max(v);
            if saturation.is_some_and(|s| v > s) {
                saturated = true;
            }
        }
    }
    let norm = (0.5 * (hi + lo)).abs().max(2.0 * dark_threshold);
    Ok(Averaged {
        mean,
        highest,
        saturated,
        inconsistent: (hi - lo) / norm > CONSISTENCY_LIMIT,
    })
}

impl Averaged {
    /// A dark reading brighter than twice the dark threshold was not taken in the dark.
    pub fn too_bright_for_dark(&self, dark_threshold: f64) -> bool {
        let m = &self.mean.cells[1..CELLS - 1];
        m.iter().sum::<f64>() / m.len() as f64 > 2.0 * dark_threshold
    }
}

/// Saturation and dark thresholds on the absraw scale of an exposure, for its `readings`.
pub fn thresholds(
    cal: &Calibration,
    e: &Exposure,
    readings: &[RawReading],
) -> Result<(f64, f64), PipelineError> {
    let k = scale(cal, e)?;
    Ok((
        f64::from(cal.saturation(e.gain)) * k,
        dark_threshold_counts(cal, e, readings) * k,
    ))
}

/// Step 5: `S' = M·S` with Rev E's stray-light matrix.
pub fn stray_light(e: &RevECalibration, s: &GridSpectrum) -> GridSpectrum {
    let m = e.stray_light_matrix();
    let mut out = [0.0; BANDS];
    for (o, row) in out.iter_mut().zip(&m) {
        *o = row.iter().zip(s).map(|(a, b)| a * b).sum();
    }
    out
}

/// Steps 4 and 5: resampling, then stray light on Rev E.
pub fn resample(cal: &Calibration, cells: &[f64; CELLS]) -> GridSpectrum {
    let s = cal.filter.apply(cells);
    match &cal.rev_e {
        Some(e) => stray_light(e, &s),
        None => s,
    }
}

fn times(s: &GridSpectrum, f: &GridSpectrum) -> GridSpectrum {
    let mut out = [0.0; BANDS];
    for ((o, a), b) in out.iter_mut().zip(s).zip(f) {
        *o = a * b;
    }
    out
}

/// Step 6, emissive: spectral radiance in mW·m⁻²·sr⁻¹·nm⁻¹, `S · emissive factor`.
pub fn emissive(cal: &Calibration, s: &GridSpectrum) -> GridSpectrum {
    times(s, &cal.emissive)
}

/// Step 6, ambient (diffuser): `S · emissive factor · ambient factor`.
pub fn ambient(cal: &Calibration, s: &GridSpectrum) -> Result<GridSpectrum, PipelineError> {
    let a = cal.ambient.as_ref().ok_or(PipelineError::NoAmbient)?;
    Ok(times(&times(s, &cal.emissive), a))
}

/// Below this a white-tile reading is taken as this (a dim band would otherwise blow up).
pub const MIN_WHITE_READING: f64 = 1000.0;

/// Reflective calibration factors from a white-tile reading: `white reference / white
/// reading`, the reading clamped to at least [`MIN_WHITE_READING`].
pub fn reflective_factors(
    cal: &Calibration,
    white: &GridSpectrum,
) -> Result<GridSpectrum, PipelineError> {
    let r = cal
        .white_reference
        .as_ref()
        .ok_or(PipelineError::NoWhiteReference)?;
    let mut f = [0.0; BANDS];
    for ((f, r), w) in f.iter_mut().zip(r).zip(white) {
        *f = r / w.max(MIN_WHITE_READING);
    }
    Ok(f)
}

/// Transmissive calibration factors from an open-aperture reading: `1 / reading`, the reading
/// clamped to at least 0.4 % of its mean.
pub fn transmissive_factors(white: &GridSpectrum) -> GridSpectrum {
    let floor = 0.004 * white.iter().sum::<f64>() / BANDS as f64;
    let mut f = [0.0; BANDS];
    for (f, w) in f.iter_mut().zip(white) {
        *f = 1.0 / w.max(floor);
    }
    f
}

/// Step 6, reflective or transmissive: `S · factors`.
pub fn reflective(s: &GridSpectrum, factors: &GridSpectrum) -> GridSpectrum {
    times(s, factors)
}

/// Alias of [`reflective`] for transmissive factors.
pub fn transmissive(s: &GridSpectrum, factors: &GridSpectrum) -> GridSpectrum {
    times(s, factors)
}

/// Steps 1–5 for the readings of one exposure: the resampled (uncalibrated) spectrum of their
/// average, with the averaging flags.
pub fn measure(
    cal: &Calibration,
    readings: &[RawReading],
    dark: &AbsRaw,
    e: &Exposure,
) -> Result<(GridSpectrum, Averaged), PipelineError> {
    let mut abs = readings
        .iter()
        .map(|r| to_absraw(cal, r, e))
        .collect::<Result<Vec<_>, _>>()?;
    subtract_dark(cal, &mut abs, dark, e)?;
    let (sat, dark_t) = thresholds(cal, e, readings)?;
    let avg = average(cal.revision(), &abs, Some(sat), dark_t)?;
    Ok((resample(cal, &avg.mean.cells), avg))
}

/// Steps 1 and 3 for dark readings: their averaged absraw and flags.
pub fn dark(
    cal: &Calibration,
    readings: &[RawReading],
    e: &Exposure,
) -> Result<Averaged, PipelineError> {
    let abs = readings
        .iter()
        .map(|r| to_absraw(cal, r, e))
        .collect::<Result<Vec<_>, _>>()?;
    let (sat, dark_t) = thresholds(cal, e, readings)?;
    average(cal.revision(), &abs, Some(sat), dark_t)
}

#[cfg(test)]
mod tests;
