//! X-Rite i1Pro (Rev A–D) and i1Pro 2 (Rev E) spectrophotometer, USB: the vendor requests
//! and their replies, the EEPROM container and its calibration, the raw readings on the bulk
//! endpoint, and the raw → spectrum pipeline as pure functions (with the inverse a simulated
//! instrument runs). Facts and their sources are in `protocols/i1pro/README.md`.
//!
//! All multi-byte fields on the wire and in the EEPROM are big-endian.

pub mod calibration;
pub mod commands;
pub mod eeprom;
#[cfg(test)]
mod fixture;
pub mod inverse;
mod linalg;
pub mod pipeline;
pub mod readings;
pub mod replies;
#[cfg(test)]
mod session_tests;
pub mod timing;
pub mod wavelength;

pub use calibration::{Calibration, CalibrationError, Filter, Gain, RevECalibration};
pub use commands::{Request, Transfer};
pub use eeprom::{Eeprom, EepromError, Value};
pub use pipeline::{AbsRaw, Exposure, PipelineError};
pub use readings::{RawReading, ReadingError};

/// Output bands of every spectrum: 380–730 nm in 10 nm steps.
pub const BANDS: usize = 36;
/// Wavelength of the first band, nm.
pub const START_NM: f64 = 380.0;
/// Band spacing, nm.
pub const STEP_NM: f64 = 10.0;
/// Spectral sensor cells per reading (both revisions).
pub const CELLS: usize = 128;
/// Shielded (dark reference) cells that precede the spectral cells in a Rev E reading.
pub const SHIELDED_CELLS: usize = 6;

/// A spectrum on the instrument's fixed grid (index `i` is `380 + 10·i` nm).
pub type GridSpectrum = [f64; BANDS];

/// Hardware generation: the two speak different dialects of the same protocol.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Revision {
    /// i1Pro, i1Monitor: 128 cells per reading, high gain, linearisation before scaling.
    AToD,
    /// i1Pro 2: 6 shielded + 128 cells per reading, no high gain, stray-light matrix,
    /// linearisation after dark subtraction.
    E,
}

impl Revision {
    /// Sensor values per reading on the bulk endpoint.
    pub fn values_per_reading(self) -> usize {
        match self {
            Revision::AToD => CELLS,
            Revision::E => SHIELDED_CELLS + CELLS,
        }
    }

    /// Bytes per reading on the bulk endpoint (u16 each).
    pub fn bytes_per_reading(self) -> usize {
        2 * self.values_per_reading()
    }
}

/// Product, as far as the codec must know it: the i1Monitor has no white tile, so its
/// EEPROM lacks the white reference and it cannot measure reflectance.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Model {
    /// i1Pro, Rev A–D (0971:2000, fewer than 5 endpoints).
    I1Pro,
    /// i1Monitor (0971:2001), Rev A–D protocol.
    I1Monitor,
    /// i1Pro 2, Rev E (0971:2000 with 5 endpoints, firmware ≥ 600).
    I1Pro2,
}

/// USB vendor id of the i1Pro family.
pub const VENDOR_ID: u16 = 0x0971;
/// Product id of the i1Pro and i1Pro 2.
pub const PRODUCT_I1PRO: u16 = 0x2000;
/// Product id of the i1Monitor.
pub const PRODUCT_I1MONITOR: u16 = 0x2001;
/// Endpoint descriptors in configuration 1 from which a unit is a Rev E.
const REV_E_ENDPOINTS: usize = 5;
/// Firmware below this is not a Rev E, whatever its endpoints say.
const REV_E_MIN_FIRMWARE: u16 = 600;

impl Model {
    /// The model behind USB ids, the number of endpoint descriptors in configuration 1, and
    /// the firmware revision once GetMisc has answered (`None` before); `None` for ids that
    /// are not an i1Pro.
    pub fn detect(
        vendor: u16,
        product: u16,
        endpoints: usize,
        firmware: Option<u16>,
    ) -> Option<Model> {
        match (vendor, product) {
            (VENDOR_ID, PRODUCT_I1MONITOR) => Some(Model::I1Monitor),
            (VENDOR_ID, PRODUCT_I1PRO) => {
                let rev_e = endpoints >= REV_E_ENDPOINTS
                    && firmware.is_none_or(|f| f >= REV_E_MIN_FIRMWARE);
                Some(if rev_e { Model::I1Pro2 } else { Model::I1Pro })
            }
            _ => None,
        }
    }

    pub fn revision(self) -> Revision {
        match self {
            Model::I1Pro | Model::I1Monitor => Revision::AToD,
            Model::I1Pro2 => Revision::E,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Model::I1Pro => "i1Pro",
            Model::I1Monitor => "i1Monitor",
            Model::I1Pro2 => "i1Pro 2",
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn models_from_usb_ids_endpoints_and_firmware() {
        assert_eq!(Model::detect(0x0971, 0x2000, 4, None), Some(Model::I1Pro));
        assert_eq!(Model::detect(0x0971, 0x2000, 5, None), Some(Model::I1Pro2));
        assert_eq!(
            Model::detect(0x0971, 0x2000, 5, Some(629)),
            Some(Model::I1Pro2)
        );
        // Five endpoints but Rev D firmware: an i1Pro.
        assert_eq!(
            Model::detect(0x0971, 0x2000, 5, Some(505)),
            Some(Model::I1Pro)
        );
        assert_eq!(
            Model::detect(0x0971, 0x2001, 4, None),
            Some(Model::I1Monitor)
        );
        assert_eq!(Model::detect(0x0971, 0x2003, 4, None), None);
        assert_eq!(Model::detect(0x0765, 0x5020, 2, None), None);
        assert_eq!(Revision::E.bytes_per_reading(), 268);
        assert_eq!(Revision::AToD.bytes_per_reading(), 256);
    }
}
