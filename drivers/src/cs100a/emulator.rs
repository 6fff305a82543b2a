//! A simulated CS-100A: answers the protocol from a light model (the [`World`] in front
//! of it), with the meter's repeatability as seeded noise, its range codes and its
//! measuring time. It serves any [`SerialLink`]: an in-process pair, or the master side of a
//! pseudo-terminal so the real `serialport` backend is exercised (see `pty`).
//!
//! The light model, ours and only as good as the unconfirmed figures it rests on (fact
//! sheet §5: repeatability ±0.2 % in Y and ±0.001 in x, y; range 0.01–299,000 cd/m²):
//! - the meter has no lamp: it sees emitted light (XYZ, or computed from a spectral
//!   radiance) and nothing from a surface, its tile or a cap (0 cd/m²);
//! - Y < 0.01 cd/m² → OK13 (low light), values still sent;
//! - 299,000 < Y ≤ 598,000 → OK12 with the `-999999` placeholder (MC2 template);
//! - Y > 598,000 (twice the range) → ER10;
//! - no defined chromaticity (X+Y+Z ≤ 0 or y ≤ 0) → OK11 with x, y sent as .0000.
//! - ±0.2 % and ±0.001 are taken as 2σ of Gaussian noise.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

use metamer_color::Xyz;
use metamer_protocols::cs100a::{self, Command, Mode, Status, Yxy};

use super::Speed;
use crate::i1pro::ManualClock;
use crate::link::{LineSettings, LinkError, SerialLink};
use crate::noise::NoiseCursor;
use crate::world::World;

/// Upper end of the display range, cd/m² (protocols/cs100a/README.md, "Measurement facts": unconfirmed).
pub const MAX_LUMINANCE: f64 = 299_000.0;
/// Below this the meter flags low light, cd/m² (protocols/cs100a/README.md, "Measurement facts": unconfirmed).
pub const MIN_LUMINANCE: f64 = 0.01;
/// Relative 1σ noise of Y: half the ±0.2 % repeatability.
pub const SIGMA_Y_REL: f64 = 0.001;
/// 1σ noise of x and y: half the ±0.001 repeatability.
pub const SIGMA_XY: f64 = 0.0005;
/// A command left without its CR LF is answered with ER00 after this long (LS-100, KM-LS
/// p.13 [C]; the CS-100A is assumed to behave alike [I]).
pub const COMMAND_TIMEOUT: Duration = Duration::from_secs(5);

/// How the emulator behaves besides its light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EmulatorConfig {
    /// Seed of the noise; the same seed gives the same readings.
    pub seed: u64,
    /// Multiplies every delay (measuring time, wire time, command timeout): 1.0 is the real
    /// meter's pace, 0.01 a hundred times faster for tests, 0 no delay at all.
    pub time_scale: f64,
    /// Add the repeatability noise (off for exact checks of the range logic).
    pub noise: bool,
}

impl Default for EmulatorConfig {
    fn default() -> Self {
        EmulatorConfig {
            seed: 1,
            time_scale: 1.0,
            noise: true,
        }
    }
}

/// The simulated meter's state.
pub struct Cs100aEmulator {
    world: Arc<dyn World>,
    config: EmulatorConfig,
    noise: NoiseCursor,
    speed: Speed,
    /// The meter's own time at the real pace, whatever the time scale: every measurement's
    /// measuring time and its command and reply on the wire add to it.
    real_pace: ManualClock,
}

impl Cs100aEmulator {
    pub fn new(world: Arc<dyn World>, config: EmulatorConfig) -> Cs100aEmulator {
        Cs100aEmulator {
            world,
            noise: NoiseCursor::default(),
            config,
            // The power-on speed is not documented; FAST is assumed [I].
            speed: Speed::Fast,
            real_pace: ManualClock::new(),
        }
    }

    /// The handle a session moves the noise stream with (see [`NoiseCursor`]).
    pub fn noise_cursor(&self) -> NoiseCursor {
        self.noise.clone()
    }

    /// The clock the meter's measurements advance at the real meter's pace (a session's
    /// instrument time, also when it runs at `time_scale` 0).
    pub fn real_pace_clock(&self) -> ManualClock {
        self.real_pace.clone()
    }

    /// The reply to one command line and how long the meter takes before sending it.
    pub fn respond(&mut self, line: &[u8]) -> (Vec<u8>, Duration) {
        let wire = |n: usize| LineSettings::CS100A.char_time() * n as u32;
        match cs100a::parse_command(line) {
            Ok(Command::Measure) => {
                let (status, value) = self.measure();
                let reply = match value {
                    Some(v) => cs100a::encode_measurement(status, &v),
                    None => cs100a::encode_code(status),
                };
                let t = Duration::from_secs_f64(crate::cs100a::response_time_s(self.speed))
                    + wire(reply.len());
                // The host's command on the wire is the meter's time too, though it is not
                // the emulator's to wait out.
                let command = wire(Command::Measure.encode().len());
                self.real_pace.advance((t + command).as_secs_f64());
                (reply, self.scaled(t))
            }
            Ok(Command::SetMode(mode)) => {
                let status = match mode {
                    Mode::Fast => {
                        self.speed = Speed::Fast;
                        Status::Ok00
                    }
                    Mode::Slow => {
                        self.speed = Speed::Slow;
                        Status::Ok00
                    }
                    // The emulator has one calibration and always reports absolute Yxy.
                    Mode::Absolute | Mode::Preset | Mode::Variable => Status::Ok00,
                    // DIFF needs a stored target (TDW), which the emulator does not model: it
                    // refuses the mode rather than send numbers a real meter would not.
                    Mode::Difference => Status::Er00,
                };
                let reply = cs100a::encode_code(status);
                let t = wire(reply.len());
                (reply, self.scaled(t))
            }
            Ok(Command::Clear) => {
                let reply = cs100a::encode_code(Status::Ok00);
                let t = wire(reply.len());
                (reply, self.scaled(t))
            }
            Err(_) => (cs100a::encode_code(Status::Er00), Duration::ZERO),
        }
    }

    /// One measurement of what the meter sees now, by the light model in the module doc.
    pub fn measure(&mut self) -> (Status, Option<Yxy>) {
        let Xyz {
            x: x_,
            y: y_,
            z: z_,
        } = self
            .world
            .view()
            .light()
            .map_or(Xyz::default(), |l| l.xyz());
        let lum = if y_.is_finite() { y_.max(0.0) } else { 0.0 };
        if lum > 2.0 * MAX_LUMINANCE {
            return (Status::Er10, None);
        }
        let sum = x_ + y_ + z_;
        let chroma = (sum.is_finite() && sum > 0.0 && y_ > 0.0).then(|| (x_ / sum, y_ / sum));
        let mut rng = self.noise.next_stream(self.config.seed);
        let noisy_lum = if self.config.noise {
            lum * (1.0 + SIGMA_Y_REL * rng.normal())
        } else {
            lum
        };
        let noisy_chroma = chroma.map(|(x, y)| {
            if self.config.noise {
                (x + SIGMA_XY * rng.normal(), y + SIGMA_XY * rng.normal())
            } else {
                (x, y)
            }
        });
        let (x, y) = match noisy_chroma {
            Some((x, y)) => (Some(x), Some(y)),
            None => (None, None),
        };
        let (status, luminance) = if lum > MAX_LUMINANCE {
            (Status::Ok12, None)
        } else if chroma.is_none() {
            (Status::Ok11, Some(noisy_lum))
        } else if lum < MIN_LUMINANCE {
            (Status::Ok13, Some(noisy_lum))
        } else {
            (Status::Ok00, Some(noisy_lum))
        };
        (status, Some(Yxy { luminance, x, y }))
    }

    fn scaled(&self, t: Duration) -> Duration {
        crate::link::duration_s(t.as_secs_f64() * self.config.time_scale)
    }

    /// Answers commands on `link` until the host disconnects or `stop` is set.
    pub fn serve<L: SerialLink>(mut self, mut link: L, stop: &AtomicBool) {
        // Poll in short slices so `stop` is seen promptly.
        let slice = Duration::from_millis(20);
        let command_timeout = self.scaled(COMMAND_TIMEOUT).max(slice);
        let mut pending: Vec<u8> = Vec::new();
        let mut pending_since = Instant::now();
        while !stop.load(Ordering::Relaxed) {
            match link.read_until(cs100a::TERMINATOR, slice) {
                Ok(line) => {
                    let mut full = std::mem::take(&mut pending);
                    full.extend_from_slice(&line);
                    let (reply, delay) = self.respond(&full);
                    // The meter's delay, in slices: a stop asked for while it "measures"
                    // ends the thread now, not when a slow scale's reading would be done.
                    let until = Instant::now() + delay.min(Duration::from_secs(86_400 * 365));
                    while Instant::now() < until {
                        if stop.load(Ordering::Relaxed) {
                            return;
                        }
                        std::thread::sleep(
                            slice.min(until.saturating_duration_since(Instant::now())),
                        );
                    }
                    // The meter ignores requests that arrive while it measures (LS-100 manual
                    // p.13 [C]; the CS-100A is assumed alike [I]).
                    pending.clear();
                    if link.discard_input().is_err() || link.write_all(&reply).is_err() {
                        return;
                    }
                }
                Err(LinkError::Timeout { received, .. }) => {
                    if !received.is_empty() {
                        if pending.is_empty() {
                            pending_since = Instant::now();
                        }
                        pending.extend_from_slice(&received);
                    }
                    if !pending.is_empty() && pending_since.elapsed() >= command_timeout {
                        pending.clear();
                        if link.write_all(&cs100a::encode_code(Status::Er00)).is_err() {
                            return;
                        }
                    }
                }
                Err(_) => return,
            }
        }
    }

    /// Serves `link` on a new thread until the host end disconnects. A panic while serving
    /// is handed to the link before it is dropped, so the host reports a failed simulation
    /// rather than a disconnected cable.
    pub fn spawn<L: SerialLink + 'static>(self, link: L) -> std::thread::JoinHandle<()> {
        std::thread::Builder::new()
            .name("cs100a-emulator".into())
            .spawn(move || {
                let mut link = link;
                let served = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                    self.serve(&mut link, &AtomicBool::new(false))
                }));
                if let Err(payload) = served {
                    let message = crate::link::panic_message(payload.as_ref());
                    link.report_panic(&format!("CS-100A emulator: {message}"));
                }
            })
            .expect("spawning the emulator thread")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::world::SharedWorld;

    fn emu(xyz: [f64; 3], noise: bool, seed: u64) -> Cs100aEmulator {
        Cs100aEmulator::new(
            Arc::new(SharedWorld::new(xyz)),
            EmulatorConfig {
                seed,
                time_scale: 0.0,
                noise,
            },
        )
    }

    /// XYZ of luminance `lum` at D65's chromaticity (x, y) = (0.3127, 0.3290).
    fn d65(lum: f64) -> [f64; 3] {
        let (x, y) = (0.3127, 0.3290);
        [x / y * lum, lum, (1.0 - x - y) / y * lum]
    }

    #[test]
    fn the_meter_sees_spectral_light_and_nothing_from_surfaces_or_a_cap() {
        use crate::world::View;
        use metamer_color::{Quantity, Spectrum};
        let world = Arc::new(SharedWorld::new(View::Capped));
        let config = EmulatorConfig {
            seed: 1,
            time_scale: 0.0,
            noise: false,
        };
        let mut e = Cs100aEmulator::new(world.clone(), config);
        // 0.1 W·sr⁻¹·m⁻²·nm⁻¹ in a 1 nm line at 555 nm (ȳ = 1): Y = 68.3 cd/m², and the
        // chromaticity of 555 nm from the CIE 1931 table, x̄ 0.512050, ȳ 1, z̄ 0.005750:
        // x = 0.512050 / 1.517800 = 0.33736, y = 1 / 1.517800 = 0.65885.
        let line = Spectrum::new(vec![554.0, 555.0, 556.0], vec![0.0, 0.1, 0.0]).unwrap();
        world.set(View::radiance(line).unwrap());
        let (status, v) = e.measure();
        assert_eq!(status, Status::Ok00);
        let v = v.unwrap();
        assert!((v.luminance.unwrap() - 68.3).abs() < 1e-9, "{v:?}");
        assert!((v.x.unwrap() - 0.33736).abs() < 1e-5, "{v:?}");
        assert!((v.y.unwrap() - 0.65885).abs() < 1e-5, "{v:?}");
        let white = Spectrum::constant(380.0, 780.0, 1.0).with_quantity(Quantity::Reflectance);
        for dark in [View::Capped, View::WhiteTile, View::surface(white).unwrap()] {
            world.set(dark.clone());
            let (status, v) = e.measure();
            assert_eq!(
                (status, v.unwrap().luminance),
                (Status::Ok11, Some(0.0)),
                "{dark:?}"
            );
        }
    }

    #[test]
    fn noiseless_reading_reports_the_stimulus() {
        let (status, v) = emu(d65(123.4), false, 1).measure();
        assert_eq!(status, Status::Ok00);
        let v = v.unwrap();
        assert!((v.luminance.unwrap() - 123.4).abs() < 1e-9);
        assert!((v.x.unwrap() - 0.3127).abs() < 1e-12);
        assert!((v.y.unwrap() - 0.3290).abs() < 1e-12);
        let (reply, _) = emu(d65(123.4), false, 1).respond(b"MES\r\n");
        assert_eq!(reply, b"OK00,  123.4, .3127, .3290\r\n");
    }

    #[test]
    fn range_ends_give_the_documented_codes() {
        assert_eq!(emu(d65(0.005), false, 1).measure().0, Status::Ok13);
        assert_eq!(emu(d65(0.01), false, 1).measure().0, Status::Ok00);
        assert_eq!(emu(d65(299_000.0), false, 1).measure().0, Status::Ok00);
        let (s, v) = emu(d65(300_000.0), false, 1).measure();
        assert_eq!((s, v.unwrap().luminance), (Status::Ok12, None));
        assert_eq!(
            emu(d65(700_000.0), false, 1).measure(),
            (Status::Er10, None)
        );
        let (s, v) = emu([0.0, 0.0, 0.0], false, 1).measure();
        assert_eq!(s, Status::Ok11);
        assert_eq!(v.unwrap().x, None);
        let (reply, _) = emu(d65(700_000.0), false, 1).respond(b"MES\r\n");
        assert_eq!(reply, b"ER10\r\n");
    }

    #[test]
    fn noise_matches_the_stated_repeatability() {
        let mut e = emu(d65(100.0), true, 42);
        let n = 4000;
        let (mut sy, mut syy, mut sx, mut sxx) = (0.0, 0.0, 0.0, 0.0);
        for _ in 0..n {
            let v = e.measure().1.unwrap();
            let l = v.luminance.unwrap();
            sy += l;
            syy += l * l;
            let x = v.x.unwrap();
            sx += x;
            sxx += x * x;
        }
        let n = n as f64;
        let (my, mx) = (sy / n, sx / n);
        let sd_y = (syy / n - my * my).sqrt();
        let sd_x = (sxx / n - mx * mx).sqrt();
        // Standard error of a standard deviation over 4000 samples is ≈1.1 %; allow 5 %.
        assert!((sd_y / 0.1 - 1.0).abs() < 0.05, "σ_Y = {sd_y}");
        assert!((sd_x / SIGMA_XY - 1.0).abs() < 0.05, "σ_x = {sd_x}");
        assert!((my - 100.0).abs() < 0.01 && (mx - 0.3127).abs() < 5e-5);
        // Same seed, same readings.
        let a: Vec<_> = (0..3).map(|_| emu(d65(50.0), true, 7).measure()).collect();
        let mut e7 = emu(d65(50.0), true, 7);
        assert_eq!(a[0], e7.measure());
    }

    #[test]
    fn modes_and_bad_commands() {
        let mut e = emu(d65(1.0), false, 1);
        assert_eq!(e.respond(b"MDS,07\r\n").0, b"OK00\r\n");
        assert_eq!(e.speed, Speed::Slow);
        assert_eq!(e.respond(b"MDS,08\r\n").0, b"ER00\r\n");
        assert_eq!(e.respond(b"FOO\r\n").0, b"ER00\r\n");
        assert_eq!(e.respond(b"CLE\r\n").0, b"OK00\r\n");
    }

    #[test]
    fn commands_sent_while_measuring_are_ignored() {
        use crate::link::pair::pair;
        let (mut host, device) = pair(LineSettings::CS100A, "test");
        let config = EmulatorConfig {
            seed: 1,
            time_scale: 1.0,
            noise: false,
        };
        let light = Arc::new(SharedWorld::new(d65(123.4)));
        Cs100aEmulator::new(light, config).spawn(device);
        host.write_all(b"MES\r\n").unwrap();
        std::thread::sleep(Duration::from_millis(5));
        host.write_all(b"MES\r\n").unwrap();
        let t = Duration::from_millis(600);
        assert_eq!(
            host.read_until(b"\r\n", t).unwrap(),
            b"OK00,  123.4, .3127, .3290\r\n"
        );
        assert!(matches!(
            host.read_until(b"\r\n", Duration::from_millis(300)),
            Err(LinkError::Timeout { .. })
        ));
    }

    #[test]
    fn measuring_time_follows_speed_and_scale() {
        let mut e = Cs100aEmulator::new(
            Arc::new(SharedWorld::new(d65(10.0))),
            EmulatorConfig {
                seed: 1,
                time_scale: 1.0,
                noise: false,
            },
        );
        let wire = 28.0 * 11.0 / 4800.0;
        let (_, t) = e.respond(b"MES\r\n");
        assert!((t.as_secs_f64() - (0.1 + wire)).abs() < 1e-6, "{t:?}");
        e.respond(b"MDS,07\r\n");
        let (_, t) = e.respond(b"MES\r\n");
        assert!((t.as_secs_f64() - (0.4 + wire)).abs() < 1e-6, "{t:?}");
        e.config.time_scale = 0.01;
        let (_, t) = e.respond(b"MES\r\n");
        assert!(
            (t.as_secs_f64() - (0.4 + wire) * 0.01).abs() < 1e-6,
            "{t:?}"
        );
    }
}
