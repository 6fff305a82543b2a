//! The simulated i1Pro's factory data: a plausible calibration built from a few smooth
//! formulas (documented with their reasons in `protocols/i1pro/README.md`, "The simulated
//! unit"), never copied from a real unit. Both revisions share the optics; Rev E adds a
//! stray-light table and the cell → wavelength cubic its bands are built from.

use metamer_protocols::i1pro::calibration::{caps_e, CAPS_AMBIENT};
use metamer_protocols::i1pro::replies::{ClockMode, Misc};
use metamer_protocols::i1pro::{
    eeprom, wavelength, Calibration, Eeprom, Model, RevECalibration, Revision, BANDS, START_NM,
    STEP_NM,
};

use super::error::I1ProError;

/// Firmware revisions the simulated units report: 505 is a Rev D, 629 a Rev E.
pub const FIRMWARE_D: u16 = 505;
pub const FIRMWARE_E: u16 = 629;
/// Serial numbers of the simulated units.
pub const SERIAL_D: i32 = 9_000_001;
pub const SERIAL_E: i32 = 9_000_002;
/// Cell `c` sees `CELL_NM[0] + CELL_NM[1]·c + CELL_NM[2]·c²` nm: 128 cells over
/// 343.5–741.8 nm, a little compressed towards the red as a grating spectrometer is.
pub const CELL_NM: [f64; 4] = [343.5, 3.2, -0.0005, 0.0];
/// Largest positive raw value + 1 that GetMisc reports: the whole u16 range is positive.
pub const MAX_POSITIVE: u16 = 0xFFFF;

fn band_nm(w: usize) -> f64 {
    START_NM + STEP_NM * w as f64
}

fn bands(f: impl Fn(f64) -> f64) -> [f64; BANDS] {
    let mut s = [0.0; BANDS];
    for (w, v) in s.iter_mut().enumerate() {
        *v = f(band_nm(w));
    }
    s
}

/// The relative sensitivity of the simulated sensor: a silicon-like hump at 560 nm that
/// falls to a third at the ends of the range.
pub fn sensitivity(nm: f64) -> f64 {
    0.3 + 0.7 * (-((nm - 560.0) / 150.0).powi(2)).exp()
}

/// The emissive calibration factor at the sensor's most sensitive wavelength,
/// mW·m⁻²·sr⁻¹·nm⁻¹ per count per second.
pub const EMISSIVE_SCALE: f64 = 2.5e-4;

/// The calibration of the simulated unit of `revision`.
pub fn calibration(revision: Revision) -> Calibration {
    let filter = wavelength::filter_from_poly(&CELL_NM).expect("the cells span 380–730 nm");
    let rev_e = (revision == Revision::E).then(|| {
        // Light scattered into the two neighbouring bands, 0.5 % each way.
        let mut stray = [[0i16; BANDS]; BANDS];
        for (i, row) in stray.iter_mut().enumerate() {
            for (j, v) in row.iter_mut().enumerate() {
                if i.abs_diff(j) == 1 {
                    *v = -1638;
                }
            }
        }
        RevECalibration {
            capabilities: caps_e::AMBIENT | caps_e::WAVELENGTH_LED | caps_e::INDICATOR_LEDS,
            stray_light: stray,
            stray_light_scale: 0.1,
            wavelength_poly_emissive: CELL_NM,
            wavelength_poly_reflective: Some(CELL_NM),
        }
    });
    Calibration {
        model: match revision {
            Revision::AToD => Model::I1Pro,
            Revision::E => Model::I1Pro2,
        },
        serial: match revision {
            Revision::AToD => SERIAL_D,
            Revision::E => SERIAL_E,
        },
        manufacture_date: Some(1_062_024),
        cpld_revision: 101,
        capabilities: if revision == Revision::AToD {
            CAPS_AMBIENT
        } else {
            0
        },
        physical_filter: 0x80,
        // Near the identity with a slight bend, as the real polynomials are.
        linearisation_normal: vec![0.0, 1.0, 2e-6, 0.0],
        linearisation_high: vec![0.0, 1.0, 2e-6, 0.0],
        high_gain_factor: 9.5,
        min_integration_s: 0.005,
        max_integration_s: 4.5,
        filter,
        // A white ceramic tile: 0.9 in the red, a little lower in the violet.
        white_reference: Some(bands(|nm| 0.9 - 0.05 * (-(nm - 380.0) / 30.0).exp())),
        // mW·m⁻²·sr⁻¹·nm⁻¹ per count per second, set so that the unit is as sensitive as
        // ArgyllCMS describes a real one: a 2 s reading saturates on about 110 cd/m² of a
        // display's white (here 110 cd/m² of LED-RGB1 puts its largest cell at the 45 000
        // counts of saturation in 2.0 s; 100 cd/m² reaches the 37 000 of the sensor target
        // in about 1.8 s).
        emissive: bands(|nm| EMISSIVE_SCALE / sensitivity(nm)),
        // The diffuser passes about 1/40 of the light into the optics.
        ambient: Some(bands(|_| 40.0)),
        sensor_target: 37_000,
        dark_threshold: 150,
        saturation_normal: 45_000,
        saturation_high: 45_000,
        rev_e,
    }
}

/// The simulated unit's EEPROM image, without the items whose keys are in `missing` (to
/// show what a damaged EEPROM does).
pub fn eeprom_image(revision: Revision, missing: &[u16]) -> Result<Vec<u8>, I1ProError> {
    image_of(&calibration(revision), missing)
}

/// The EEPROM image of a calibration, without the items whose keys are in `missing`.
pub fn image_of(cal: &Calibration, missing: &[u16]) -> Result<Vec<u8>, I1ProError> {
    let revision = cal.revision();
    let mut items: Eeprom = cal.to_eeprom()?;
    for key in missing {
        items.remove(*key);
    }
    let size = match revision {
        Revision::AToD => eeprom::SIZE_A_TO_D,
        Revision::E => eeprom::SIZE_E,
    };
    Ok(items.build(revision, size)?)
}

/// GetMisc's reply of the simulated unit.
pub fn misc(revision: Revision) -> Misc {
    Misc {
        firmware: firmware(revision),
        unknown1: 0,
        max_positive: MAX_POSITIVE,
        unknown3: 1,
        power: 0,
    }
}

/// The firmware revision the simulated unit of `revision` reports.
pub fn firmware(revision: Revision) -> u16 {
    match revision {
        Revision::AToD => FIRMWARE_D,
        Revision::E => FIRMWARE_E,
    }
}

/// The Rev D unit's clock modes as GetClockMode reports each when it is in force (`max`
/// and `current` are filled in by the emulator). Mode 1 is the clock of firmware before
/// 301: 68 µs, 130 to the sub-clock, 8.84 ms shortest. Mode 2 is 36 µs × 131 = 4.716 ms
/// [I]: ArgyllCMS's shortest integration on firmware ≥ 301 is 4.716 ms, reached by
/// stepping the modes until one sub-clock fits, and 4716 µs is 36 µs (Rev E's clock)
/// × 131; the real mode table is not published.
pub const CLOCK_MODES: [ClockMode; 2] = [
    ClockMode {
        max: 2,
        current: 1,
        unknown: 0,
        sub_clock_divider: 130,
        clock_us: 68,
        flags: 0,
    },
    ClockMode {
        max: 2,
        current: 2,
        unknown: 0,
        sub_clock_divider: 131,
        clock_us: 36,
        flags: 0,
    },
];
