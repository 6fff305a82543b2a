//! The pipeline run backwards, for a simulated i1Pro: from a calibrated spectrum to the raw
//! counts whose forward processing gives it back (to within the rounding of counts to
//! integers).
//!
//! Resampling maps 128 cells to 36 bands, so many cell vectors give the same spectrum; the
//! one chosen is the least-norm solution `x = Fᵀ (F Fᵀ)⁻¹ S`, a blend of the filter rows that
//! is as smooth as the filter itself. A spectrum that alternates between neighbouring bands
//! faster than the filter is wide needs negative light in some cells; the sensor cannot
//! report that, so such counts are clipped and do not give the spectrum back.

use super::calibration::Calibration;
use super::linalg::solve;
use super::pipeline::{drift_corrected_dark, scale, AbsRaw, Exposure, PipelineError};
use super::readings::{value_range, RawReading};
use super::{GridSpectrum, Revision, BANDS, CELLS, SHIELDED_CELLS, START_NM, STEP_NM};

fn divide(
    s: &GridSpectrum,
    f: &GridSpectrum,
    what: &'static str,
) -> Result<GridSpectrum, PipelineError> {
    let mut out = [0.0; BANDS];
    for (band, ((o, a), b)) in out.iter_mut().zip(s).zip(f).enumerate() {
        if *b == 0.0 {
            return Err(PipelineError::ZeroFactor {
                what,
                band,
                nm: START_NM + STEP_NM * band as f64,
            });
        }
        *o = a / b;
    }
    Ok(out)
}

/// Spectral radiance → the resampled spectrum the emissive factors turn into it.
pub fn uncalibrate_emissive(
    cal: &Calibration,
    radiance: &GridSpectrum,
) -> Result<GridSpectrum, PipelineError> {
    divide(radiance, &cal.emissive, "the emissive calibration factor")
}

/// Ambient irradiance → the resampled spectrum.
pub fn uncalibrate_ambient(
    cal: &Calibration,
    ambient: &GridSpectrum,
) -> Result<GridSpectrum, PipelineError> {
    let a = cal.ambient.as_ref().ok_or(PipelineError::NoAmbient)?;
    let s = divide(ambient, a, "the ambient calibration factor")?;
    uncalibrate_emissive(cal, &s)
}

/// Reflectance → the resampled spectrum, given the factors of a white calibration.
pub fn uncalibrate_reflective(
    reflectance: &GridSpectrum,
    factors: &GridSpectrum,
) -> Result<GridSpectrum, PipelineError> {
    divide(reflectance, factors, "the reflective calibration factor")
}

/// Dark-subtracted cell values (absraw) whose resampling — and stray-light correction on
/// Rev E — gives `s`. On Rev A–D the junk cells 0 and 127 are copies of cells 1 and 126 by
/// the time the filter sees them, so they are solved for as one with their neighbours.
pub fn cells_for(cal: &Calibration, s: &GridSpectrum) -> Result<[f64; CELLS], PipelineError> {
    let target: Vec<f64> = match &cal.rev_e {
        Some(e) => {
            let m = e.stray_light_matrix();
            solve(m.iter().map(|r| r.to_vec()).collect(), s.to_vec())
                .ok_or(PipelineError::Singular("stray-light"))?
        }
        None => s.to_vec(),
    };
    let mut f = vec![vec![0.0; CELLS]; BANDS];
    for (w, row) in f.iter_mut().enumerate() {
        let (start, c) = cal.filter.band(w);
        row[start..start + c.len()].copy_from_slice(c);
        if cal.revision() == Revision::AToD {
            row[1] += std::mem::take(&mut row[0]);
            row[CELLS - 2] += std::mem::take(&mut row[CELLS - 1]);
        }
    }
    let g: Vec<Vec<f64>> = f
        .iter()
        .map(|a| f.iter().map(|b| dot(a, b)).collect())
        .collect();
    let y = solve(g, target).ok_or(PipelineError::Singular("resampling filter"))?;
    let mut x = [0.0; CELLS];
    for (j, xj) in x.iter_mut().enumerate() {
        *xj = f.iter().zip(&y).map(|(row, yw)| row[j] * yw).sum();
    }
    if cal.revision() == Revision::AToD {
        x[0] = x[1];
        x[CELLS - 1] = x[CELLS - 2];
    }
    Ok(x)
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

/// The `x` with `poly(x) = y`, by Newton's method from `x = y` (the linearisation is close to
/// the identity).
pub fn inverse_linearise(poly: &[f64], y: f64) -> Result<f64, PipelineError> {
    let p = |x: f64| poly.iter().rev().fold(0.0, |acc, c| acc * x + c);
    let dp = |x: f64| {
        poly.iter()
            .enumerate()
            .skip(1)
            .rev()
            .fold(0.0, |acc, (i, c)| acc * x + i as f64 * c)
    };
    let mut x = y;
    for _ in 0..100 {
        let d = dp(x);
        if d == 0.0 || !d.is_finite() {
            break;
        }
        let step = (p(x) - y) / d;
        x -= step;
        if step.abs() <= 1e-12 * x.abs().max(1.0) {
            return Ok(x);
        }
    }
    Err(PipelineError::Singular("linearisation"))
}

/// The counts of one reading whose dark-subtracted absraw is `signal`, with `dark` the
/// absraw of the dark taken at the same exposure. Rev E also needs the reading's shielded
/// cells (the simulator's choice: the dark's own counts mean no drift). Counts are rounded
/// and clipped to what the sensor can send, so an over-bright signal comes back saturated
/// rather than as an error. `max_positive` is the Rev A–D sign limit from GetMisc.
pub fn counts_for(
    cal: &Calibration,
    e: &Exposure,
    signal: &[f64; CELLS],
    dark: &AbsRaw,
    shielded: Option<[u16; SHIELDED_CELLS]>,
    max_positive: u16,
) -> Result<RawReading, PipelineError> {
    let k = scale(cal, e)?;
    let poly = cal.linearisation(e.gain);
    let (low, high) = value_range(cal.revision(), max_positive);
    let clip = |v: f64| v.round().clamp(f64::from(low), f64::from(high)) as i32;
    let mut cells = [0i32; CELLS];
    match (cal.revision(), shielded) {
        (Revision::AToD, None) => {
            for ((c, s), d) in cells.iter_mut().zip(signal).zip(&dark.cells) {
                *c = clip(inverse_linearise(poly, (s + d) / k)?);
            }
        }
        (Revision::E, Some(sh)) => {
            let mean = sh.iter().map(|&v| f64::from(v)).sum::<f64>() / SHIELDED_CELLS as f64;
            let adjusted = drift_corrected_dark(dark, mean * k);
            for ((c, s), d) in cells.iter_mut().zip(signal).zip(&adjusted) {
                *c = clip(inverse_linearise(poly, s / k)? + d / k);
            }
        }
        (revision, Some(_)) => {
            return Err(PipelineError::Shape {
                revision,
                problem: "has no shielded cells",
            })
        }
        (revision, None) => {
            return Err(PipelineError::Shape {
                revision,
                problem: "needs its shielded cells",
            })
        }
    }
    Ok(RawReading { cells, shielded })
}

/// Spectral radiance → one reading's counts: [`uncalibrate_emissive`], [`cells_for`],
/// [`counts_for`].
pub fn emissive_reading(
    cal: &Calibration,
    e: &Exposure,
    radiance: &GridSpectrum,
    dark: &AbsRaw,
    shielded: Option<[u16; SHIELDED_CELLS]>,
    max_positive: u16,
) -> Result<RawReading, PipelineError> {
    let s = uncalibrate_emissive(cal, radiance)?;
    let signal = cells_for(cal, &s)?;
    counts_for(cal, e, &signal, dark, shielded, max_positive)
}

#[cfg(test)]
mod tests;
