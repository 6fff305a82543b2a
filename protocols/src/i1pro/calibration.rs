//! The factory calibration the raw → spectrum pipeline needs, typed, read from the EEPROM's
//! items (a missing or malformed item is an error naming its key) and written back to them,
//! so a simulated instrument serves exactly the calibration it was built from.

use super::eeprom::{key_name, Eeprom, EepromError, Value};
use super::{GridSpectrum, Model, Revision, BANDS, CELLS};

pub mod key;

/// Capability bits of key 0x0BC2 that mean "has the ambient diffuser".
pub const CAPS_AMBIENT: i32 = 0x6000;
/// Physical filter value of a UV-cut unit (0x80: none).
pub const FILTER_UV_CUT: i32 = 0x82;

/// Rev E capability bits (key 0x2EE2).
pub mod caps_e {
    pub const AMBIENT: i32 = 0x01;
    pub const WAVELENGTH_LED: i32 = 0x02;
    pub const UV_LED: i32 = 0x04;
    pub const RULER: i32 = 0x08;
    pub const INDICATOR_LEDS: i32 = 0x10;
    pub const UV_FILTER: i32 = 0x20;
}

mod ambient;
pub use ambient::AmbientTable;

/// A calibration item that is missing or malformed.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum CalibrationError {
    #[error("the EEPROM lacks key {key:#06x} ({name}), which the {model} needs")]
    Missing {
        key: u16,
        name: &'static str,
        model: &'static str,
    },
    #[error("EEPROM key {key:#06x} ({name}) has {found} values, expected {expected}")]
    Length {
        key: u16,
        name: &'static str,
        expected: String,
        found: usize,
    },
    #[error("EEPROM key {key:#06x} ({name}) holds the wrong type of values")]
    Type { key: u16, name: &'static str },
    #[error(
        "resampling filter band {band} reads cells {start}..{end}, outside the sensor's 0..128"
    )]
    FilterRange { band: usize, start: i64, end: i64 },
    #[error("the resampling filter has {found} bands, expected 36")]
    FilterBands { found: usize },
    #[error("the {what} must be a polynomial with at least one coefficient")]
    EmptyPolynomial { what: &'static str },
    #[error("the {model} calibration {problem}")]
    Model {
        model: &'static str,
        problem: &'static str,
    },
    #[error(transparent)]
    Eeprom(#[from] EepromError),
}

/// The factory resampling filter: each output band is a weighted sum of a run of adjacent
/// sensor cells. Built only through [`Filter::new`], which checks every run lies on the
/// sensor, so applying it never indexes out of range.
#[derive(Clone, Debug, PartialEq)]
pub struct Filter {
    starts: Vec<usize>,
    coefficients: Vec<Vec<f64>>,
}

impl Filter {
    /// `starts[w]` is band `w`'s first cell, `coefficients[w]` its weights.
    pub fn new(
        starts: Vec<usize>,
        coefficients: Vec<Vec<f64>>,
    ) -> Result<Filter, CalibrationError> {
        if starts.len() != BANDS || coefficients.len() != BANDS {
            return Err(CalibrationError::FilterBands {
                found: starts.len().max(coefficients.len()),
            });
        }
        for (band, (s, c)) in starts.iter().zip(&coefficients).enumerate() {
            if s + c.len() > CELLS {
                return Err(CalibrationError::FilterRange {
                    band,
                    start: *s as i64,
                    end: (s + c.len()) as i64,
                });
            }
        }
        Ok(Filter {
            starts,
            coefficients,
        })
    }

    /// First cell of each band.
    pub fn starts(&self) -> &[usize] {
        &self.starts
    }

    /// Weights of each band.
    pub fn coefficients(&self) -> &[Vec<f64>] {
        &self.coefficients
    }

    /// First cell and weights of band `w` (< 36).
    pub(super) fn band(&self, w: usize) -> (usize, &[f64]) {
        (self.starts[w], &self.coefficients[w])
    }

    /// `S[w] = Σ_k c_w[k] · cells[start_w + k]`.
    pub fn apply(&self, cells: &[f64; CELLS]) -> GridSpectrum {
        let mut s = [0.0; BANDS];
        for (w, out) in s.iter_mut().enumerate() {
            let (start, c) = self.band(w);
            *out = c.iter().zip(&cells[start..]).map(|(a, b)| a * b).sum();
        }
        s
    }
}

/// What only Rev E stores.
#[derive(Clone, Debug, PartialEq)]
pub struct RevECalibration {
    /// [`caps_e`] bits.
    pub capabilities: i32,
    /// Stray-light table, signed; see [`RevECalibration::stray_light_matrix`].
    pub stray_light: [[i16; BANDS]; BANDS],
    pub stray_light_scale: f64,
    /// Raw cell → wavelength cubic for emissive measurements.
    pub wavelength_poly_emissive: [f64; 4],
    /// The same for reflective; stripped-down units lack it and use the emissive one.
    pub wavelength_poly_reflective: Option<[f64; 4]>,
}

impl RevECalibration {
    /// `M = I + scale · L / 32767`: the matrix that corrects a resampled spectrum.
    pub fn stray_light_matrix(&self) -> [[f64; BANDS]; BANDS] {
        let mut m = [[0.0; BANDS]; BANDS];
        for (i, row) in m.iter_mut().enumerate() {
            for (j, v) in row.iter_mut().enumerate() {
                *v = self.stray_light_scale * f64::from(self.stray_light[i][j]) / 32767.0;
                if i == j {
                    *v += 1.0;
                }
            }
        }
        m
    }
}

/// The gain a reading was taken at (Rev E has only normal gain).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Gain {
    Normal,
    High,
}

/// Everything the raw → spectrum pipeline reads from the EEPROM.
#[derive(Clone, Debug, PartialEq)]
pub struct Calibration {
    pub model: Model,
    pub serial: i32,
    /// Probably DDMMYYYY as a decimal number.
    pub manufacture_date: Option<i32>,
    pub cpld_revision: i32,
    /// Capability bits; ambient diffuser if `& CAPS_AMBIENT`.
    pub capabilities: i32,
    /// 0x80 none, [`FILTER_UV_CUT`] UV cut.
    pub physical_filter: i32,
    /// Linearisation polynomial `c0 + c1·v + c2·v² + …` for normal / high gain.
    pub linearisation_normal: Vec<f64>,
    pub linearisation_high: Vec<f64>,
    /// Sensitivity of high gain relative to normal.
    pub high_gain_factor: f64,
    pub min_integration_s: f64,
    pub max_integration_s: f64,
    pub filter: Filter,
    /// Reflectance of the white tile (absent on the i1Monitor).
    pub white_reference: Option<GridSpectrum>,
    /// Multiplies a resampled spectrum into radiance.
    pub emissive: GridSpectrum,
    /// Multiplies the emissive factors for an ambient (diffuser) reading.
    pub ambient: Option<GridSpectrum>,
    /// Counts the integration time is optimised for.
    pub sensor_target: i32,
    /// Dark threshold in counts (before the integration-time term).
    pub dark_threshold: i32,
    pub saturation_normal: i32,
    pub saturation_high: i32,
    /// Present exactly when the model is Rev E.
    pub rev_e: Option<RevECalibration>,
}

impl Calibration {
    pub fn revision(&self) -> Revision {
        self.model.revision()
    }

    pub fn linearisation(&self, gain: Gain) -> &[f64] {
        match gain {
            Gain::Normal => &self.linearisation_normal,
            Gain::High => &self.linearisation_high,
        }
    }

    pub fn gain_factor(&self, gain: Gain) -> f64 {
        match gain {
            Gain::Normal => 1.0,
            Gain::High => self.high_gain_factor,
        }
    }

    pub fn saturation(&self, gain: Gain) -> i32 {
        match gain {
            Gain::Normal => self.saturation_normal,
            Gain::High => self.saturation_high,
        }
    }

    /// Whether the EEPROM's capability bits say the unit has the ambient diffuser (0x0BC2 &
    /// 0x6000, or Rev E 0x2EE2 & 0x01), whatever its ambient table holds.
    pub fn claims_ambient(&self) -> bool {
        self.capabilities & CAPS_AMBIENT != 0
            || self
                .rev_e
                .as_ref()
                .is_some_and(|e| e.capabilities & caps_e::AMBIENT != 0)
    }

    /// Whether the unit has the ambient diffuser and a usable calibration for it.
    pub fn has_ambient(&self) -> bool {
        self.claims_ambient() && self.ambient.is_some()
    }

    /// Whether a UV-cut filter is fitted.
    pub fn uv_cut(&self) -> bool {
        self.physical_filter == FILTER_UV_CUT
            || self
                .rev_e
                .as_ref()
                .is_some_and(|e| e.capabilities & caps_e::UV_FILTER != 0)
    }

    /// Reads the calibration of a `model` from its parsed EEPROM.
    pub fn from_eeprom(e: &Eeprom, model: Model) -> Result<Calibration, CalibrationError> {
        let r = Reader { e, model };
        let starts = r.ints(key::FILTER_START, Some(BANDS))?;
        let counts = r.ints(key::FILTER_COUNT, Some(BANDS))?;
        let total: i64 = counts.iter().map(|&c| i64::from(c.max(0))).sum();
        let coef = r.floats(key::FILTER_COEF, Some(total as usize))?;
        let mut at = 0usize;
        let mut start_cells = Vec::with_capacity(BANDS);
        let mut coefficients = Vec::with_capacity(BANDS);
        for (band, (&s, &n)) in starts.iter().zip(&counts).enumerate() {
            let end = i64::from(s) + i64::from(n);
            if s < 0 || n < 0 || end > CELLS as i64 {
                return Err(CalibrationError::FilterRange {
                    band,
                    start: i64::from(s),
                    end,
                });
            }
            start_cells.push(s as usize);
            coefficients.push(coef[at..at + n as usize].to_vec());
            at += n as usize;
        }
        let filter = Filter::new(start_cells, coefficients)?;

        let capabilities = r.int(key::CAPABILITIES)?;
        let white_reference = match model {
            Model::I1Monitor => r.optional_spectrum(key::WHITE_REF)?,
            _ => Some(r.spectrum(key::WHITE_REF)?),
        };
        let caps_e_ambient =
            model.revision() == Revision::E && r.int(key::CAPABILITIES_E)? & caps_e::AMBIENT != 0;
        // A unit that claims the diffuser must carry the table (ArgyllCMS refuses one that
        // does not); whether it claims it or not, a table that is the "no ambient" marker
        // (−1 in every band) or holds a factor that is not a positive number calibrates
        // nothing: the unit has no ambient mode (see `ambient_table`).
        let table = if capabilities & CAPS_AMBIENT != 0 || caps_e_ambient {
            Some(r.spectrum(key::AMBIENT)?)
        } else {
            r.optional_spectrum(key::AMBIENT)?
        };
        let ambient = table.filter(|a| AmbientTable::of(Some(a)) == AmbientTable::Usable);
        let rev_e = match model.revision() {
            Revision::AToD => None,
            Revision::E => {
                let emissive = r.poly4(key::WAVELENGTH_POLY_EMISSIVE)?;
                let reflective = match e.get(key::WAVELENGTH_POLY_REFLECTIVE) {
                    None => None,
                    Some(_) => Some(r.poly4(key::WAVELENGTH_POLY_REFLECTIVE)?),
                };
                Some(RevECalibration {
                    capabilities: r.int(key::CAPABILITIES_E)?,
                    stray_light: r.square(key::STRAY_LIGHT)?,
                    stray_light_scale: r.float(key::STRAY_LIGHT_SCALE)?,
                    wavelength_poly_emissive: emissive,
                    wavelength_poly_reflective: reflective,
                })
            }
        };
        let cal = Calibration {
            model,
            serial: r.int(key::SERIAL)?,
            manufacture_date: match e.get(key::MANUFACTURE_DATE) {
                None => None,
                Some(_) => Some(r.int(key::MANUFACTURE_DATE)?),
            },
            cpld_revision: r.int(key::CPLD_REVISION)?,
            capabilities,
            physical_filter: r.int(key::PHYSICAL_FILTER)?,
            linearisation_normal: r.floats(key::LIN_NORMAL, None)?,
            linearisation_high: r.floats(key::LIN_HIGH, None)?,
            high_gain_factor: r.float(key::HIGH_GAIN_FACTOR)?,
            min_integration_s: r.float(key::MIN_INTEGRATION)?,
            max_integration_s: r.float(key::MAX_INTEGRATION)?,
            filter,
            white_reference,
            emissive: r.spectrum(key::EMISSIVE)?,
            ambient,
            sensor_target: r.int(key::SENSOR_TARGET)?,
            dark_threshold: r.int(key::DARK_THRESHOLD)?,
            saturation_normal: r.int(key::SATURATION_NORMAL)?,
            saturation_high: r.int(key::SATURATION_HIGH)?,
            rev_e,
        };
        cal.check()?;
        Ok(cal)
    }

    /// Parses a whole EEPROM image of a `model`.
    pub fn from_image(image: &[u8], model: Model) -> Result<Calibration, CalibrationError> {
        Calibration::from_eeprom(&Eeprom::parse(image, model.revision())?, model)
    }

    /// What a parsed or hand-made calibration must satisfy for the pipeline to run on it.
    pub fn check(&self) -> Result<(), CalibrationError> {
        let model = self.model.name();
        if self.linearisation_normal.is_empty() {
            return Err(CalibrationError::EmptyPolynomial {
                what: "normal-gain linearisation",
            });
        }
        if self.linearisation_high.is_empty() {
            return Err(CalibrationError::EmptyPolynomial {
                what: "high-gain linearisation",
            });
        }
        if self.rev_e.is_some() != (self.revision() == Revision::E) {
            return Err(CalibrationError::Model {
                model,
                problem: "must carry Rev E data (stray light, wavelength polynomials) exactly when the model is the i1Pro 2",
            });
        }
        if self.white_reference.is_none() && self.model != Model::I1Monitor {
            return Err(CalibrationError::Missing {
                key: key::WHITE_REF,
                name: key_name(key::WHITE_REF),
                model,
            });
        }
        Ok(())
    }

    /// The EEPROM items of this calibration (floats rounded to float32, as stored).
    pub fn to_eeprom(&self) -> Result<Eeprom, CalibrationError> {
        self.check()?;
        let mut e = Eeprom::new();
        let floats = |v: &[f64]| Value::Floats(v.iter().map(|&x| x as f32).collect());
        let int = |v: i32| Value::Ints(vec![v]);
        let starts = (0..BANDS).map(|w| self.filter.band(w).0 as i32).collect();
        let counts = (0..BANDS)
            .map(|w| self.filter.band(w).1.len() as i32)
            .collect();
        let coef: Vec<f64> = (0..BANDS)
            .flat_map(|w| self.filter.band(w).1.to_vec())
            .collect();
        e.insert(key::FILTER_START, Value::Ints(starts))?;
        e.insert(key::FILTER_COUNT, Value::Ints(counts))?;
        e.insert(key::FILTER_COEF, floats(&coef))?;
        e.insert(key::LIN_NORMAL, floats(&self.linearisation_normal))?;
        e.insert(key::LIN_HIGH, floats(&self.linearisation_high))?;
        if let Some(w) = &self.white_reference {
            e.insert(key::WHITE_REF, floats(w))?;
        }
        e.insert(key::EMISSIVE, floats(&self.emissive))?;
        let no_ambient = [-1.0; BANDS];
        e.insert(
            key::AMBIENT,
            floats(self.ambient.as_ref().unwrap_or(&no_ambient)),
        )?;
        e.insert(key::SENSOR_TARGET, int(self.sensor_target))?;
        e.insert(key::DARK_THRESHOLD, int(self.dark_threshold))?;
        e.insert(key::SATURATION_NORMAL, int(self.saturation_normal))?;
        e.insert(key::SATURATION_HIGH, int(self.saturation_high))?;
        e.insert(key::SERIAL, int(self.serial))?;
        if let Some(d) = self.manufacture_date {
            e.insert(key::MANUFACTURE_DATE, int(d))?;
        }
        e.insert(key::HIGH_GAIN_FACTOR, floats(&[self.high_gain_factor]))?;
        e.insert(key::MIN_INTEGRATION, floats(&[self.min_integration_s]))?;
        e.insert(key::MAX_INTEGRATION, floats(&[self.max_integration_s]))?;
        e.insert(key::CPLD_REVISION, int(self.cpld_revision))?;
        e.insert(key::CAPABILITIES, int(self.capabilities))?;
        e.insert(key::PHYSICAL_FILTER, int(self.physical_filter))?;
        if let Some(r) = &self.rev_e {
            e.insert(key::CAPABILITIES_E, int(r.capabilities))?;
            let table = r.stray_light.iter().flatten().copied().collect();
            e.insert(key::STRAY_LIGHT, Value::Shorts(table))?;
            e.insert(key::STRAY_LIGHT_SCALE, floats(&[r.stray_light_scale]))?;
            e.insert(
                key::WAVELENGTH_POLY_EMISSIVE,
                floats(&r.wavelength_poly_emissive),
            )?;
            if let Some(p) = &r.wavelength_poly_reflective {
                e.insert(key::WAVELENGTH_POLY_REFLECTIVE, floats(p))?;
            }
        }
        Ok(e)
    }

    /// A whole EEPROM image (8 KiB on Rev A–D, 16 KiB on Rev E) holding this calibration.
    pub fn to_image(&self) -> Result<Vec<u8>, CalibrationError> {
        let size = match self.revision() {
            Revision::AToD => super::eeprom::SIZE_A_TO_D,
            Revision::E => super::eeprom::SIZE_E,
        };
        Ok(self.to_eeprom()?.build(self.revision(), size)?)
    }
}

/// Typed access to the items, with errors that name the key.
struct Reader<'a> {
    e: &'a Eeprom,
    model: Model,
}

impl Reader<'_> {
    fn value(&self, key: u16) -> Result<&Value, CalibrationError> {
        self.e.get(key).ok_or(CalibrationError::Missing {
            key,
            name: key_name(key),
            model: self.model.name(),
        })
    }

    fn length<T: Clone>(
        &self,
        key: u16,
        v: &[T],
        n: Option<usize>,
    ) -> Result<Vec<T>, CalibrationError> {
        match n {
            Some(n) if v.len() != n => Err(CalibrationError::Length {
                key,
                name: key_name(key),
                expected: n.to_string(),
                found: v.len(),
            }),
            None if v.is_empty() => Err(CalibrationError::Length {
                key,
                name: key_name(key),
                expected: "at least 1".to_string(),
                found: 0,
            }),
            _ => Ok(v.to_vec()),
        }
    }

    fn type_error(key: u16) -> CalibrationError {
        CalibrationError::Type {
            key,
            name: key_name(key),
        }
    }

    fn ints(&self, key: u16, n: Option<usize>) -> Result<Vec<i32>, CalibrationError> {
        match self.value(key)? {
            Value::Ints(v) => self.length(key, v, n),
            _ => Err(Self::type_error(key)),
        }
    }

    fn floats(&self, key: u16, n: Option<usize>) -> Result<Vec<f64>, CalibrationError> {
        match self.value(key)? {
            Value::Floats(v) => {
                let v: Vec<f64> = v.iter().map(|&x| f64::from(x)).collect();
                self.length(key, &v, n)
            }
            _ => Err(Self::type_error(key)),
        }
    }

    fn shorts(&self, key: u16, n: usize) -> Result<Vec<i16>, CalibrationError> {
        match self.value(key)? {
            Value::Shorts(v) => self.length(key, v, Some(n)),
            _ => Err(Self::type_error(key)),
        }
    }

    fn square(&self, key: u16) -> Result<[[i16; BANDS]; BANDS], CalibrationError> {
        let v = self.shorts(key, BANDS * BANDS)?;
        let mut m = [[0i16; BANDS]; BANDS];
        for (row, chunk) in m.iter_mut().zip(v.chunks_exact(BANDS)) {
            row.copy_from_slice(chunk);
        }
        Ok(m)
    }

    fn int(&self, key: u16) -> Result<i32, CalibrationError> {
        Ok(self.ints(key, Some(1))?[0])
    }

    fn float(&self, key: u16) -> Result<f64, CalibrationError> {
        Ok(self.floats(key, Some(1))?[0])
    }

    fn spectrum(&self, key: u16) -> Result<GridSpectrum, CalibrationError> {
        let v = self.floats(key, Some(BANDS))?;
        let mut s = [0.0; BANDS];
        s.copy_from_slice(&v);
        Ok(s)
    }

    fn optional_spectrum(&self, key: u16) -> Result<Option<GridSpectrum>, CalibrationError> {
        match self.e.get(key) {
            None => Ok(None),
            Some(_) => self.spectrum(key).map(Some),
        }
    }

    fn poly4(&self, key: u16) -> Result<[f64; 4], CalibrationError> {
        let v = self.floats(key, Some(4))?;
        Ok([v[0], v[1], v[2], v[3]])
    }
}

#[cfg(test)]
mod tests;
