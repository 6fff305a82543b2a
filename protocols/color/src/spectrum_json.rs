//! The JSON form of a [`Spectrum`]: a grid (`start_nm`, `step_nm`) when the samples are
//! evenly spaced, so an instrument's 36-band reading stays short and readable, and explicit
//! wavelengths otherwise. Deserializing validates exactly as [`Spectrum::new`] does.

use serde::{Deserialize, Serialize, Serializer};

use crate::{ColorError, Interpolation, Outside, Quantity, Spectrum};

#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct SpectrumJson {
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        serialize_with = "whole_as_integer"
    )]
    start_nm: Option<f64>,
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        serialize_with = "whole_as_integer"
    )]
    step_nm: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    wavelengths_nm: Option<Vec<f64>>,
    values: Vec<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    quantity: Option<Quantity>,
    #[serde(default, skip_serializing_if = "is_zero")]
    outside: Outside,
    #[serde(default, skip_serializing_if = "is_linear")]
    interpolation: Interpolation,
}

fn is_linear(i: &Interpolation) -> bool {
    *i == Interpolation::Linear
}

fn is_zero(o: &Outside) -> bool {
    *o == Outside::Zero
}

/// 380 rather than 380.0: grids are whole nanometres nearly always, and people read these.
fn whole_as_integer<S: Serializer>(v: &Option<f64>, s: S) -> Result<S::Ok, S::Error> {
    match v {
        Some(x) if x.fract() == 0.0 && x.abs() < 9.0e15 => s.serialize_i64(*x as i64),
        Some(x) => s.serialize_f64(*x),
        None => s.serialize_none(),
    }
}

impl From<Spectrum> for SpectrumJson {
    fn from(s: Spectrum) -> SpectrumJson {
        let (start_nm, step_nm, wavelengths_nm) = match s.grid() {
            Some((start, step)) => (Some(start), Some(step), None),
            None => (None, None, Some(s.wavelengths_nm().to_vec())),
        };
        SpectrumJson {
            start_nm,
            step_nm,
            wavelengths_nm,
            quantity: s.quantity(),
            outside: s.outside(),
            interpolation: s.interpolation(),
            values: s.values().to_vec(),
        }
    }
}

impl TryFrom<SpectrumJson> for Spectrum {
    type Error = ColorError;

    fn try_from(j: SpectrumJson) -> Result<Spectrum, ColorError> {
        let bad = |m: &str| ColorError::InvalidSpectrum(m.into());
        let spectrum = match (j.start_nm, j.step_nm, j.wavelengths_nm) {
            (Some(start), Some(step), None) => {
                if !(step > 0.0 && step.is_finite()) {
                    return Err(bad("step_nm must be a positive number"));
                }
                Spectrum::from_grid(start, step, j.values)?
            }
            (None, None, Some(nm)) => Spectrum::new(nm, j.values)?,
            _ => {
                return Err(bad(
                    "give either start_nm and step_nm, or wavelengths_nm (not both)",
                ))
            }
        };
        let spectrum = spectrum
            .with_outside(j.outside)
            .with_interpolation(j.interpolation);
        Ok(match j.quantity {
            Some(q) => spectrum.with_quantity(q),
            None => spectrum,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_grid_is_written_as_start_and_step() {
        let s = Spectrum::from_grid(380.0, 10.0, vec![0.5, 0.25, 1.0]).unwrap();
        assert_eq!(
            serde_json::to_string(&s).unwrap(),
            r#"{"start_nm":380,"step_nm":10,"values":[0.5,0.25,1.0]}"#
        );
        let r: Spectrum = serde_json::from_str(&serde_json::to_string(&s).unwrap()).unwrap();
        assert_eq!(r, s);
        assert_eq!(r.wavelengths_nm(), &[380.0, 390.0, 400.0]);
    }

    #[test]
    fn irregular_samples_quantity_and_outside_round_trip() {
        let s = Spectrum::new(vec![400.0, 410.5, 700.0], vec![1.0, 2.0, 3.0])
            .unwrap()
            .with_quantity(Quantity::Radiance)
            .with_outside(Outside::HoldEnds);
        let text = serde_json::to_string(&s).unwrap();
        assert_eq!(
            text,
            r#"{"wavelengths_nm":[400.0,410.5,700.0],"values":[1.0,2.0,3.0],"quantity":"radiance","outside":"hold_ends"}"#
        );
        assert_eq!(serde_json::from_str::<Spectrum>(&text).unwrap(), s);
        // A measured spectrum keeps its interpolation.
        let m = Spectrum::measured(380.0, 10.0, vec![1.0; 6]).unwrap();
        let text = serde_json::to_string(&m).unwrap();
        assert_eq!(
            text,
            r#"{"start_nm":380,"step_nm":10,"values":[1.0,1.0,1.0,1.0,1.0,1.0],"outside":"hold_ends","interpolation":"sprague"}"#
        );
        assert_eq!(serde_json::from_str::<Spectrum>(&text).unwrap(), m);
        // A fractional grid keeps its fractions.
        let f = Spectrum::from_grid(380.5, 3.3, vec![0.0; 4]).unwrap();
        let back: Spectrum = serde_json::from_str(&serde_json::to_string(&f).unwrap()).unwrap();
        assert_eq!(back, f);
    }

    #[test]
    fn malformed_json_spectra_are_refused_with_the_reason() {
        let err = |t: &str| serde_json::from_str::<Spectrum>(t).unwrap_err().to_string();
        assert!(err(r#"{"values":[1]}"#).contains("either start_nm"));
        assert!(err(r#"{"start_nm":380,"step_nm":0,"values":[1]}"#).contains("positive"));
        assert!(err(r#"{"wavelengths_nm":[500,400],"values":[1,2]}"#).contains("must increase"));
        assert!(err(r#"{"wavelengths_nm":[400],"values":[1,2]}"#).contains("1 wavelengths"));
        assert!(err(r#"{"start_nm":380,"step_nm":5,"values":[],"x":1}"#).contains("unknown field"));
    }
}
