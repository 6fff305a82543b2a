//! Sampled spectra: a function of wavelength given at increasing sample points, linearly
//! interpolated between them (the convention of the validation-box contract, and how the CIE
//! defines its illuminants between their 5 nm samples), zero outside unless the caller asks to
//! hold the end values. A spectrometer's reading at 5 or 10 nm is instead interpolated as
//! CIE 167:2005 recommends for evenly spaced data (Sprague, see [`Interpolation`]) and held
//! at its end values beyond its range ([`Spectrum::measured`]). A spectrum may say what it
//! measures ([`Quantity`]), so a reading's spectrum carries its unit with it.

use serde::{Deserialize, Serialize};

use crate::ColorError;

/// What a spectrum's values are.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Quantity {
    /// Spectral radiance in W·sr⁻¹·m⁻²·nm⁻¹ → absolute XYZ in cd/m².
    Radiance,
    /// Spectral irradiance in W·m⁻²·nm⁻¹ → illuminance XYZ in lux.
    Irradiance,
    /// Reflectance factor 0–1 under an illuminant → relative XYZ, Y = 100 for white.
    Reflectance,
}

impl Quantity {
    /// The unit of the values, for messages and file headers.
    pub fn unit(self) -> &'static str {
        match self {
            Quantity::Radiance => "W·sr⁻¹·m⁻²·nm⁻¹",
            Quantity::Irradiance => "W·m⁻²·nm⁻¹",
            Quantity::Reflectance => "1",
        }
    }
}

/// What a spectrum is worth outside its first and last sample.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Outside {
    /// Zero outside the table (the default for emission and observer tables).
    #[default]
    Zero,
    /// The first value below the table, the last above it (used for reflectances measured
    /// over a shorter range, e.g. the ColorChecker's 380–730 nm).
    HoldEnds,
}

/// What a spectrum is worth between its samples.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Interpolation {
    /// Straight lines between samples (tables at 1 nm, the CIE illuminants, the renderer's
    /// spectra).
    #[default]
    Linear,
    /// Sprague's (1880) fifth-order interpolation, which CIE 167:2005 recommends for
    /// evenly spaced spectral data and CIE 15 for data coarser than the 1 nm of its
    /// colour-matching functions. It needs an even grid of at least 6 samples; a spectrum
    /// without one is interpolated linearly whatever this says. Colorimetry sums such a
    /// spectrum over 360–830 nm, the range of the CIE's standard method (see
    /// [`radiance_to_xyz`](crate::radiance_to_xyz)).
    Sprague,
}

/// A sampled spectrum with strictly increasing wavelengths in nm.
///
/// In JSON a spectrum on an even grid is `{"start_nm":380,"step_nm":10,"values":[…]}`, any
/// other `{"wavelengths_nm":[…],"values":[…]}`; `quantity` and `outside` follow when set.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(try_from = "crate::spectrum_json::SpectrumJson")]
#[serde(into = "crate::spectrum_json::SpectrumJson")]
pub struct Spectrum {
    wavelengths_nm: Vec<f64>,
    values: Vec<f64>,
    outside: Outside,
    interpolation: Interpolation,
    quantity: Option<Quantity>,
}

impl Spectrum {
    /// Builds a spectrum; wavelengths must be finite and strictly increasing, values finite.
    pub fn new(wavelengths_nm: Vec<f64>, values: Vec<f64>) -> Result<Self, ColorError> {
        if wavelengths_nm.is_empty() {
            return Err(ColorError::InvalidSpectrum("no samples".into()));
        }
        if wavelengths_nm.len() != values.len() {
            return Err(ColorError::InvalidSpectrum(format!(
                "{} wavelengths but {} values",
                wavelengths_nm.len(),
                values.len()
            )));
        }
        if let Some(i) = wavelengths_nm
            .windows(2)
            .position(|w| w[1] <= w[0] || !w[0].is_finite() || !w[1].is_finite())
        {
            return Err(ColorError::InvalidSpectrum(format!(
                "wavelengths must increase: {} nm follows {} nm",
                wavelengths_nm[i + 1],
                wavelengths_nm[i]
            )));
        }
        if let Some(v) = values.iter().find(|v| !v.is_finite()) {
            return Err(ColorError::InvalidSpectrum(format!(
                "value {v} is not finite"
            )));
        }
        Ok(Spectrum {
            wavelengths_nm,
            values,
            outside: Outside::Zero,
            interpolation: Interpolation::Linear,
            quantity: None,
        })
    }

    /// A spectrometer's reading on an even grid: see [`Spectrum::as_measured`].
    pub fn measured(start_nm: f64, step_nm: f64, values: Vec<f64>) -> Result<Self, ColorError> {
        Ok(Spectrum::from_grid(start_nm, step_nm, values)?.as_measured())
    }

    /// A spectrum on an even grid `start, start+step, …`.
    pub fn from_grid(start_nm: f64, step_nm: f64, values: Vec<f64>) -> Result<Self, ColorError> {
        let nm = (0..values.len())
            .map(|i| start_nm + step_nm * i as f64)
            .collect();
        Spectrum::new(nm, values)
    }

    /// A constant value over `[start, end]` sampled at 1 nm.
    pub fn constant(start_nm: f64, end_nm: f64, value: f64) -> Self {
        let n = (end_nm - start_nm).round() as usize + 1;
        Spectrum::from_grid(start_nm, 1.0, vec![value; n]).expect("a constant grid is valid")
    }

    /// The same samples with another rule outside the table.
    pub fn with_outside(mut self, outside: Outside) -> Self {
        self.outside = outside;
        self
    }

    pub fn outside(&self) -> Outside {
        self.outside
    }

    /// These samples read as the CIE treats measured data coarser than its 1 nm tables:
    /// Sprague interpolation between samples (CIE 167:2005 §9.2.4) and the nearest measured
    /// value beyond the measured range (the CIE's rule for data measured over a shorter range
    /// than its tables, CIE 15 and CIE 167:2005; ArgyllCMS and colour-science do the same).
    /// A spectrum at 1 nm or finer, on an uneven grid or with fewer than 6 samples is
    /// returned unchanged: it is summed as given.
    pub fn as_measured(self) -> Spectrum {
        let coarse = self.grid().is_some_and(|(_, step)| step > 1.0)
            && self.values.len() >= crate::sprague::MIN_SAMPLES;
        if coarse {
            self.with_interpolation(Interpolation::Sprague)
                .with_outside(Outside::HoldEnds)
        } else {
            self
        }
    }

    /// The same samples with another rule between them.
    pub fn with_interpolation(mut self, interpolation: Interpolation) -> Self {
        self.interpolation = interpolation;
        self
    }

    /// The rule between samples as set (see [`Spectrum::sprague`] for the one in force).
    pub fn interpolation(&self) -> Interpolation {
        self.interpolation
    }

    /// Whether values between samples follow Sprague's interpolation: asked for, on an even
    /// grid of at least 6 samples.
    pub fn sprague(&self) -> bool {
        self.interpolation == Interpolation::Sprague
            && self.values.len() >= crate::sprague::MIN_SAMPLES
            && self.grid().is_some()
    }

    /// Other values on the same wavelengths, keeping every rule (outside, interpolation,
    /// quantity): for averages and clamps of readings.
    pub fn with_values(&self, values: Vec<f64>) -> Result<Spectrum, ColorError> {
        Ok(Spectrum {
            interpolation: self.interpolation,
            outside: self.outside,
            quantity: self.quantity,
            ..Spectrum::new(self.wavelengths_nm.clone(), values)?
        })
    }

    /// The same samples marked as measuring `quantity`.
    pub fn with_quantity(mut self, quantity: Quantity) -> Self {
        self.quantity = Some(quantity);
        self
    }

    /// What the values are, when the spectrum says.
    pub fn quantity(&self) -> Option<Quantity> {
        self.quantity
    }

    /// `(start, step)` when the samples lie exactly on `start + step·i` (two samples or
    /// more); the exact test keeps a spectrum built with [`Spectrum::from_grid`] on its grid
    /// through a JSON round trip.
    pub fn grid(&self) -> Option<(f64, f64)> {
        let w = &self.wavelengths_nm;
        if w.len() < 2 {
            return None;
        }
        let (start, step) = (w[0], w[1] - w[0]);
        w.iter()
            .enumerate()
            .all(|(i, &nm)| nm == start + step * i as f64)
            .then_some((start, step))
    }

    pub fn wavelengths_nm(&self) -> &[f64] {
        &self.wavelengths_nm
    }

    pub fn values(&self) -> &[f64] {
        &self.values
    }

    /// First and last sampled wavelength.
    pub fn range_nm(&self) -> (f64, f64) {
        (
            self.wavelengths_nm[0],
            *self.wavelengths_nm.last().expect("never empty"),
        )
    }

    /// The value at `nm`, interpolated between samples by the spectrum's [`Interpolation`].
    pub fn value_at(&self, nm: f64) -> f64 {
        let w = &self.wavelengths_nm;
        let (first, last) = self.range_nm();
        if nm < first || nm > last {
            return match self.outside {
                Outside::Zero => 0.0,
                Outside::HoldEnds if nm < first => self.values[0],
                Outside::HoldEnds => *self.values.last().expect("never empty"),
            };
        }
        if self.sprague() {
            let (start, step) = (w[0], w[1] - w[0]);
            return crate::sprague::value_at(&self.values, (nm - start) / step);
        }
        // Index of the first sample strictly above nm; nm lies in [w[i-1], w[i]].
        let i = w.partition_point(|&s| s <= nm);
        if i == 0 {
            return self.values[0];
        }
        if i == w.len() {
            return self.values[w.len() - 1];
        }
        let t = (nm - w[i - 1]) / (w[i] - w[i - 1]);
        self.values[i - 1] + t * (self.values[i] - self.values[i - 1])
    }

    /// The values at `start, start+step, …` (`n` of them) as a flat array, for code that
    /// works on a fixed grid (the path tracer's 1 nm bins).
    pub fn on_grid(&self, start_nm: f64, step_nm: f64, n: usize) -> Vec<f64> {
        (0..n)
            .map(|i| self.value_at(start_nm + step_nm * i as f64))
            .collect()
    }

    /// Samples this spectrum on `start, start+step, …, end` (inclusive).
    pub fn resample(&self, start_nm: f64, end_nm: f64, step_nm: f64) -> Spectrum {
        assert!(step_nm > 0.0 && end_nm >= start_nm, "bad resampling grid");
        let n = ((end_nm - start_nm) / step_nm).round() as usize + 1;
        let nm: Vec<f64> = (0..n).map(|i| start_nm + step_nm * i as f64).collect();
        let values = nm.iter().map(|&l| self.value_at(l)).collect();
        Spectrum {
            wavelengths_nm: nm,
            values,
            outside: self.outside,
            interpolation: self.interpolation,
            quantity: self.quantity,
        }
    }

    /// Every value multiplied by `k`.
    pub fn scaled(&self, k: f64) -> Spectrum {
        Spectrum {
            wavelengths_nm: self.wavelengths_nm.clone(),
            values: self.values.iter().map(|v| v * k).collect(),
            outside: self.outside,
            interpolation: self.interpolation,
            quantity: self.quantity,
        }
    }

    /// The product of two spectra, sampled on the union of both grids so no sample of
    /// either is lost, and at every whole nanometre between where a factor is interpolated
    /// by Sprague (the product itself is linear between its samples). Outside both tables
    /// the product follows each factor's own rule. A reflectance times anything is what the
    /// other factor is (light reflected is light).
    pub fn product(&self, other: &Spectrum) -> Spectrum {
        let mut nm: Vec<f64> = self
            .wavelengths_nm
            .iter()
            .chain(other.wavelengths_nm.iter())
            .copied()
            .collect();
        for s in [self, other].into_iter().filter(|s| s.sprague()) {
            let (first, last) = s.range_nm();
            nm.extend((first.ceil() as i64..=last.floor() as i64).map(|l| l as f64));
        }
        nm.sort_by(f64::total_cmp);
        nm.dedup();
        let values = nm
            .iter()
            .map(|&l| self.value_at(l) * other.value_at(l))
            .collect();
        let outside = if self.outside == Outside::HoldEnds && other.outside == Outside::HoldEnds {
            Outside::HoldEnds
        } else {
            Outside::Zero
        };
        let quantity = match (self.quantity, other.quantity) {
            (Some(Quantity::Reflectance), q) | (q, Some(Quantity::Reflectance)) => q,
            _ => None,
        };
        Spectrum {
            wavelengths_nm: nm,
            values,
            outside,
            interpolation: Interpolation::Linear,
            quantity,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ramp() -> Spectrum {
        Spectrum::new(vec![400.0, 500.0, 600.0], vec![0.0, 1.0, 3.0]).unwrap()
    }

    #[test]
    fn interpolates_linearly_between_samples() {
        let s = ramp();
        assert_eq!(s.value_at(400.0), 0.0);
        assert_eq!(s.value_at(450.0), 0.5);
        assert_eq!(s.value_at(500.0), 1.0);
        assert!((s.value_at(575.0) - 2.5).abs() < 1e-12);
        assert_eq!(s.value_at(600.0), 3.0);
    }

    #[test]
    fn zero_or_held_outside() {
        let s = ramp();
        assert_eq!(s.value_at(399.0), 0.0);
        assert_eq!(s.value_at(700.0), 0.0);
        let h = s.with_outside(Outside::HoldEnds);
        assert_eq!(h.value_at(380.0), 0.0);
        assert_eq!(h.value_at(780.0), 3.0);
    }

    #[test]
    fn resample_and_product() {
        let s = ramp().resample(400.0, 600.0, 50.0);
        assert_eq!(s.values(), &[0.0, 0.5, 1.0, 2.0, 3.0]);
        let p = ramp().product(&Spectrum::constant(380.0, 780.0, 2.0));
        assert_eq!(p.value_at(500.0), 2.0);
        assert_eq!(p.value_at(390.0), 0.0);
        assert_eq!(ramp().scaled(2.0).value_at(600.0), 6.0);
        assert_eq!(
            ramp().on_grid(400.0, 25.0, 5),
            vec![0.0, 0.25, 0.5, 0.75, 1.0]
        );
        assert_eq!(ramp().on_grid(350.0, 300.0, 2), vec![0.0, 0.0]);
    }

    #[test]
    fn quantity_follows_scaling_resampling_and_reflection() {
        let light = ramp().with_quantity(Quantity::Radiance);
        let surface = Spectrum::constant(380.0, 780.0, 0.5).with_quantity(Quantity::Reflectance);
        assert_eq!(light.scaled(2.0).quantity(), Some(Quantity::Radiance));
        assert_eq!(
            light.resample(400.0, 600.0, 10.0).quantity(),
            Some(Quantity::Radiance)
        );
        assert_eq!(surface.product(&light).quantity(), Some(Quantity::Radiance));
        assert_eq!(light.product(&light).quantity(), None);
        assert_eq!(ramp().quantity(), None);
    }

    #[test]
    fn grid_is_found_only_when_every_sample_is_on_it() {
        assert_eq!(ramp().grid(), Some((400.0, 100.0)));
        let odd = Spectrum::new(vec![400.0, 500.0, 650.0], vec![0.0; 3]).unwrap();
        assert_eq!(odd.grid(), None);
        assert_eq!(Spectrum::new(vec![500.0], vec![1.0]).unwrap().grid(), None);
    }

    #[test]
    fn rejects_malformed() {
        assert!(Spectrum::new(vec![], vec![]).is_err());
        assert!(Spectrum::new(vec![500.0, 500.0], vec![1.0, 1.0]).is_err());
        assert!(Spectrum::new(vec![500.0], vec![f64::NAN]).is_err());
        assert!(Spectrum::new(vec![500.0, 510.0], vec![1.0]).is_err());
    }
}
