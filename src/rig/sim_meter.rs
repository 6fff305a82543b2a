//! The simulated CS-100A served on a pseudo-terminal, for programs other than this one: any
//! serial client (a terminal program, a script, another colour tool) opens the device path
//! and talks to the emulated meter as to one on an RS-232C port. The meter sees a constant
//! light, or whatever the owner of [`PtyMeter::light`] puts in front of it.

use std::sync::Arc;

use metamer_color::Xyz;
use metamer_drivers::cs100a::emulator::{Cs100aEmulator, EmulatorConfig};
use metamer_drivers::cs100a::pty::PtyEmulator;
use metamer_drivers::{DriverError, SharedWorld, DEFAULT_STIMULUS_XYZ};

/// How the served meter behaves.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PtyMeterOptions {
    /// The light in front of the meter, XYZ in cd/m².
    pub xyz: Xyz,
    /// Add the meter's repeatability noise to each reading.
    pub noise: bool,
    /// Seed of the noise; the same seed gives the same readings.
    pub seed: u64,
    /// Multiplies the meter's delays: 1 is the real pace, 0 answers at once.
    pub time_scale: f64,
}

impl Default for PtyMeterOptions {
    fn default() -> Self {
        let meter = EmulatorConfig::default();
        PtyMeterOptions {
            xyz: DEFAULT_STIMULUS_XYZ,
            noise: meter.noise,
            seed: meter.seed,
            time_scale: meter.time_scale,
        }
    }
}

/// The simulated meter could not be served.
#[derive(Debug, thiserror::Error)]
pub enum PtyMeterError {
    #[error("the light X, Y, Z = {xyz:?} is not a light: each must be a finite number ≥ 0")]
    NotALight { xyz: [f64; 3] },
    #[error("the time scale {0:?} is not a number from 0 to {max} (1 = the real meter's pace)", max = metamer_drivers::MAX_TIME_SCALE)]
    BadTimeScale(f64),
    #[error("cannot serve the simulated CS-100A: {0}")]
    Start(#[from] DriverError),
}

/// A simulated CS-100A answering on a pseudo-terminal until dropped.
pub struct PtyMeter {
    light: Arc<SharedWorld>,
    // Dropping it stops the emulator's thread and closes the pty.
    emulator: PtyEmulator,
}

impl PtyMeter {
    /// Starts the meter on a new pseudo-terminal; it answers from another thread.
    ///
    /// # Examples
    ///
    /// `metamer simulate cs100a --pty` as one call: serve the meter, then read it through
    /// its device path as a real CS-100A on a serial port is read.
    ///
    /// ```
    /// use metamer::color::Xyz;
    /// use metamer::rig::sim_meter::{PtyMeter, PtyMeterOptions};
    /// use metamer_drivers::{MeasureMode, Request, Spec};
    ///
    /// let options = PtyMeterOptions {
    ///     xyz: Xyz::new(19.0, 20.0, 21.8),
    ///     noise: false,
    ///     time_scale: 0.0,
    ///     ..Default::default()
    /// };
    /// let meter = PtyMeter::start(&options)?;
    /// let mut cs100a = Spec::new(format!("cs100a:{}", meter.path())).open(None)?;
    /// let reading = cs100a.measure(&Request { mode: MeasureMode::Emissive })?;
    /// assert!((reading.xyz[1] - 20.0).abs() < 0.1, "{:?}", reading.xyz);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn start(options: &PtyMeterOptions) -> Result<PtyMeter, PtyMeterError> {
        check_light(options.xyz)?;
        // The bound every simulated instrument has: beyond it one reading takes days, a
        // typo rather than a pace, and the emulator's delays would overflow.
        if !(0.0..=metamer_drivers::MAX_TIME_SCALE).contains(&options.time_scale) {
            return Err(PtyMeterError::BadTimeScale(options.time_scale));
        }
        let light = Arc::new(SharedWorld::new(options.xyz));
        let config = EmulatorConfig {
            seed: options.seed,
            time_scale: options.time_scale,
            noise: options.noise,
        };
        let emulator = PtyEmulator::start(Cs100aEmulator::new(light.clone(), config))?;
        Ok(PtyMeter { light, emulator })
    }

    /// The device path a client opens (`/dev/pts/N`).
    pub fn path(&self) -> &str {
        self.emulator.path()
    }

    /// What the meter sees; setting it changes the next reading.
    pub fn light(&self) -> &Arc<SharedWorld> {
        &self.light
    }
}

fn check_light(xyz: Xyz) -> Result<(), PtyMeterError> {
    let xyz = xyz.to_array();
    if xyz.iter().all(|v| v.is_finite() && *v >= 0.0) {
        Ok(())
    } else {
        Err(PtyMeterError::NotALight { xyz })
    }
}

#[cfg(test)]
mod tests {
    use std::io::{BufRead, BufReader, Write};

    use super::*;

    #[test]
    fn bad_lights_and_time_scales_are_errors() {
        for xyz in [
            [-1.0, 1.0, 1.0],
            [1.0, f64::NAN, 1.0],
            [1.0, 1.0, f64::INFINITY],
        ] {
            let options = PtyMeterOptions {
                xyz: xyz.into(),
                ..PtyMeterOptions::default()
            };
            let e = PtyMeter::start(&options).err().unwrap();
            assert!(e.to_string().contains("is not a light"), "{e}");
        }
        for (scale, shown) in [(-0.5, "-0.5"), (1e308, "1e308"), (f64::NAN, "NaN")] {
            let options = PtyMeterOptions {
                time_scale: scale,
                ..PtyMeterOptions::default()
            };
            let e = PtyMeter::start(&options).err().unwrap().to_string();
            assert!(
                e.contains(&format!(
                    "time scale {shown} is not a number from 0 to 1000"
                )),
                "{e}"
            );
        }
    }

    /// A stop asked for while the meter takes a slow reading (1000 times the real pace:
    /// minutes) ends the emulator at once: dropping the meter joins its thread.
    #[test]
    fn dropping_the_meter_mid_reading_returns_at_once() {
        let options = PtyMeterOptions {
            noise: false,
            time_scale: 1000.0,
            ..PtyMeterOptions::default()
        };
        let meter = PtyMeter::start(&options).unwrap();
        let port = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .open(meter.path())
            .unwrap();
        (&port).write_all(b"MES\r\n").unwrap();
        // Let the emulator take the command and start its delay.
        std::thread::sleep(std::time::Duration::from_millis(300));
        let start = std::time::Instant::now();
        drop(meter);
        assert!(
            start.elapsed() < std::time::Duration::from_secs(2),
            "{:?}",
            start.elapsed()
        );
    }

    /// Raw reads and writes on the device path, as any program would make them: a light of
    /// chromaticity (0.3127, 0.3290) at 50 cd/m² reads back as those numbers.
    #[test]
    fn a_plain_file_client_reads_the_light() {
        let (x, y, lum) = (0.3127, 0.3290, 50.0);
        let options = PtyMeterOptions {
            xyz: Xyz::new(x / y * lum, lum, (1.0 - x - y) / y * lum),
            noise: false,
            seed: 1,
            time_scale: 0.0,
        };
        let meter = PtyMeter::start(&options).unwrap();
        let port = std::fs::OpenOptions::new()
            .read(true)
            .write(true)
            .open(meter.path())
            .unwrap();
        let mut reader = BufReader::new(port.try_clone().unwrap());
        let mut ask = |command: &str| {
            (&port).write_all(command.as_bytes()).unwrap();
            let mut reply = String::new();
            reader.read_line(&mut reply).unwrap();
            reply
        };
        assert_eq!(ask("MDS,04\r\n"), "OK00\r\n");
        // The meter pads Y to seven characters and sends x, y without the leading zero.
        assert_eq!(ask("MES\r\n"), "OK00,  50.00, .3127, .3290\r\n");
        meter.light().set([0.0, 0.0, 0.0]);
        assert_eq!(ask("MES\r\n").get(..5), Some("OK11,"));
    }
}
