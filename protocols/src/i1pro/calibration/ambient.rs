//! What an EEPROM's ambient table holds: usable factors, the "no ambient" marker that units
//! without the diffuser store, or values that calibrate nothing.

use super::key;
use crate::i1pro::eeprom::{Eeprom, Value};
use crate::i1pro::{GridSpectrum, BANDS};

/// What an EEPROM's ambient table (key 0x044E) holds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AmbientTable {
    /// No such key.
    Missing,
    /// −1 in every band: what units without the diffuser store.
    NoAmbientMarker,
    /// A factor that is zero, negative or not a number, in `band` (from 0, 380 nm).
    Unusable { band: usize, value: f64 },
    /// Every factor a positive number.
    Usable,
}

impl AmbientTable {
    /// Judges a table (None: the key is missing).
    pub fn of(table: Option<&GridSpectrum>) -> AmbientTable {
        let Some(t) = table else {
            return AmbientTable::Missing;
        };
        if t.iter().all(|&v| v == -1.0) {
            return AmbientTable::NoAmbientMarker;
        }
        match t.iter().position(|v| !(v.is_finite() && *v > 0.0)) {
            Some(band) => AmbientTable::Unusable {
                band,
                value: t[band],
            },
            None => AmbientTable::Usable,
        }
    }

    /// Judges the table of a parsed EEPROM; a table of the wrong length or type counts as
    /// unusable in its first band.
    pub fn in_eeprom(e: &Eeprom) -> AmbientTable {
        match e.get(key::AMBIENT) {
            None => AmbientTable::Missing,
            Some(Value::Floats(v)) if v.len() == BANDS => {
                let mut s = [0.0; BANDS];
                for (o, &x) in s.iter_mut().zip(v) {
                    *o = f64::from(x);
                }
                AmbientTable::of(Some(&s))
            }
            Some(_) => AmbientTable::Unusable {
                band: 0,
                value: f64::NAN,
            },
        }
    }
}
