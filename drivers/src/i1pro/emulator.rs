//! A simulated i1Pro on the USB level: it answers the vendor requests and bulk reads the
//! real driver sends, from its synthetic EEPROM and the simulated world, so the driver runs
//! unchanged against it.
//!
//! Counts come from running the codec's pipeline backwards: the spectrum the instrument
//! sees (a light's radiance; under its lamp a surface's or the white tile's reflectance
//! times the lamp) → the resampled values the calibration factors turn into it → the cell
//! values the filter maps to them → plus the dark current → raw counts. Then the sensor's
//! noise (shot noise of the light and of the dark current, √counts, and a read noise of
//! [`READ_NOISE`] counts) and its full well ([`FULL_WELL`], above the EEPROM's saturation
//! threshold so the driver sees the saturation) apply.
//!
//! It refuses (stalls) what a real unit cannot do rather than doing it anyway: an
//! integration shorter than one sub-clock of the clock mode in force, a clock mode it does
//! not have, and clock-mode requests on firmware before 301, which has none.

use std::sync::Arc;
use std::time::Duration;

use metamer_color::{radiance_to_xyz, Illuminant, ObserverKind, Spectrum, Xyz};
use metamer_protocols::i1pro::commands::EP_DATA_IN;
use metamer_protocols::i1pro::inverse;
use metamer_protocols::i1pro::pipeline::{self, AbsRaw, Exposure};
use metamer_protocols::i1pro::replies::MeasChar;
use metamer_protocols::i1pro::{
    commands::{Setup, Transfer},
    readings, Calibration, Gain, GridSpectrum, RawReading, Request, Revision, BANDS, CELLS,
    SHIELDED_CELLS, START_NM, STEP_NM,
};
use metamer_protocols::transcript::TransferKind;

use super::synthetic;
use crate::link::usb::ControlSetup;
use crate::link::usb_pair::{TransferAnswer, UsbDevice};
use crate::world::{Light, View, World};

/// Read noise of the simulated sensor, counts (1σ).
pub const READ_NOISE: f64 = 2.0;
/// Counts at which the simulated sensor's cells clip.
pub const FULL_WELL: f64 = 60_000.0;
/// What the simulated lamp gives on a perfect white, in counts per second of a band: a
/// warm lamp, stronger in the red.
pub fn lamp(nm: f64) -> f64 {
    1.5e6 * (0.25 + 0.75 * (nm - START_NM) / 350.0)
}
/// Repeatability the simulated instrument declares for an emissive reading whose largest
/// cell reaches the sensor target: relative 1σ of Y. Measured 0.12 % on 100 cd/m² of
/// LED-RGB1, one reading of 1.8 s with the shot noise of ~37 000 counts at its peak
/// (`a_noisy_100_cd_white_repeats_within_the_documented_repeatability`).
pub const REPEATABILITY_Y: f64 = 0.0015;
/// Below about this luminance (cd/m²) the driver integrates its longest time (2 s) and the
/// cells collect fewer photons than the target: the relative noise of Y grows as
/// √(this / Y) (shot noise). Where the cap starts depends on the light's spectrum (LED-RGB1
/// about 90 cd/m², the ips-lcd white above 103); this is the upper end.
pub const FULL_SIGNAL_CD_M2: f64 = 100.0;
/// The sensor's own noise at 2 s (read noise, the dark current's shot noise and the
/// subtracted dark's), in cd/m² of Y (1σ): what dominates below about 1 cd/m².
pub const DARK_NOISE_CD_M2: f64 = 0.013;

/// The relative 1σ of Y of one emissive reading of `cd_m2`: [`REPEATABILITY_Y`] down to
/// [`FULL_SIGNAL_CD_M2`], then growing as the shot noise does, with the sensor's own
/// noise in quadrature. Checked against the simulated unit from 0.5 to 400 cd/m²
/// (`the_stated_repeatability_holds_at_every_level`).
pub fn repeatability_y(cd_m2: f64) -> f64 {
    let y = cd_m2.abs().max(f64::MIN_POSITIVE);
    let shot = REPEATABILITY_Y * REPEATABILITY_Y * (FULL_SIGNAL_CD_M2 / y).max(1.0);
    (shot + (DARK_NOISE_CD_M2 / y).powi(2)).sqrt()
}

/// The 1σ of x and of y of one emissive reading, relative to that of Y
/// ([`repeatability_y`]): the same photons' noise, spread over the bands that make X
/// and Z. Measured 0.19–0.27 from 1 to 400 cd/m² in the check above (0.33 at 0.5 cd/m²,
/// where chromaticity means little); stated above the upper end.
pub const REPEATABILITY_XY_PER_Y: f64 = 0.3;
/// Repeatability of a reflectance band, absolute 1σ (both the white and the sample shot are
/// noisy).
pub const REPEATABILITY_REFLECTANCE: f64 = 0.002;

/// A fault to inject, for transcripts of what the driver does when things go wrong.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Fault {
    /// The `n`th measurement's bulk read (from 1) returns half its bytes.
    ShortRead(u32),
    /// The device goes away during the `n`th measurement's bulk read.
    DisconnectMidRead(u32),
    /// The device stalls the `n`th measurement's trigger.
    StallTrigger(u32),
    /// The device never answers the `n`th measurement's bulk read.
    SilentRead(u32),
}

/// How the simulated unit behaves.
#[derive(Clone, Debug)]
pub struct EmulatorConfig {
    pub revision: Revision,
    pub seed: u64,
    pub noise: bool,
    /// Multiplies the integration delays (0 answers at once).
    pub time_scale: f64,
    /// The diffuser is over the optics: the instrument sees irradiance, π × the radiance of
    /// a light filling its view.
    pub diffuser: bool,
    /// EEPROM keys left out of the image.
    pub missing_keys: Vec<u16>,
    pub fault: Option<Fault>,
    /// The unit starts in low power and still answers this many GetMisc in low power after
    /// the power-up reset.
    pub low_power_polls: u32,
    /// Rev A–D: how many of the clock modes in [`synthetic::CLOCK_MODES`] the unit has (1:
    /// only the 8.84 ms one).
    pub clock_modes: u8,
    /// The firmware revision GetMisc reports, if not the revision's usual one (Rev A–D
    /// below 301 has no clock modes).
    pub firmware: Option<u16>,
    /// The capability bits claim the diffuser, but the ambient table is the "no ambient"
    /// marker (−1 in every band).
    pub no_ambient_table: bool,
}

impl Default for EmulatorConfig {
    fn default() -> Self {
        EmulatorConfig {
            revision: Revision::AToD,
            seed: 1,
            noise: true,
            time_scale: 1.0,
            diffuser: false,
            missing_keys: Vec::new(),
            fault: None,
            low_power_polls: 0,
            clock_modes: 2,
            firmware: None,
            no_ambient_table: false,
        }
    }
}

impl EmulatorConfig {
    fn firmware(&self) -> u16 {
        self.firmware
            .unwrap_or_else(|| synthetic::firmware(self.revision))
    }

    fn has_clock_modes(&self) -> bool {
        self.revision == Revision::AToD && self.firmware() >= 301
    }
}

/// The emulator's state between transfers.
pub struct I1ProEmulator {
    config: EmulatorConfig,
    world: Arc<dyn World>,
    cal: Calibration,
    image: Vec<u8>,
    /// Integration time, readings and lamp of the last SetMeasParams.
    params: (f64, u64, bool),
    /// The clock mode in force (Rev A–D), from 1.
    mode: u8,
    pending: Option<(Duration, Vec<u8>)>,
    measurements: u32,
    rng: u64,
    noise: crate::noise::NoiseCursor,
    /// In low power; after the power-up reset, the GetMisc answers still to come in it.
    low_power: Option<(bool, u32)>,
    /// The instrument's own time at the real unit's pace, whatever the time scale: every
    /// measurement's integration (and lamp warm-up) adds to it.
    real_pace: super::ManualClock,
}

/// The light a world gives as the instrument's 36 bands, mW·m⁻²·sr⁻¹·nm⁻¹.
fn light_bands(light: &Light) -> GridSpectrum {
    let s = match light {
        Light::Radiance(s) => s.clone(),
        Light::Xyz(xyz) => metamer_for(*xyz),
    };
    let mut b = [0.0; BANDS];
    for (w, v) in b.iter_mut().enumerate() {
        *v = 1000.0 * s.value_at(START_NM + STEP_NM * w as f64);
    }
    b
}

/// A smooth spectrum of this XYZ (cd/m²), for worlds that know only the colour: a blend of
/// three broad bands at 450, 540 and 610 nm.
pub fn metamer_for(xyz: Xyz) -> Spectrum {
    let basis: Vec<Spectrum> = [450.0, 540.0, 610.0]
        .iter()
        .map(|c| {
            let nm: Vec<f64> = (380..=780).map(f64::from).collect();
            let v = nm
                .iter()
                .map(|l| (-((l - c) / 30.0f64).powi(2)).exp())
                .collect();
            Spectrum::new(nm, v).expect("an even grid")
        })
        .collect();
    let m: Vec<Xyz> = basis
        .iter()
        .map(|b| radiance_to_xyz(b, ObserverKind::Cie1931))
        .collect();
    // Solve Σ_k a_k m_k = xyz (3×3, Cramer's rule).
    let det = |a: Xyz, b: Xyz, c: Xyz| {
        a[0] * (b[1] * c[2] - b[2] * c[1]) - b[0] * (a[1] * c[2] - a[2] * c[1])
            + c[0] * (a[1] * b[2] - a[2] * b[1])
    };
    let d = det(m[0], m[1], m[2]);
    let a = [
        det(xyz, m[1], m[2]) / d,
        det(m[0], xyz, m[2]) / d,
        det(m[0], m[1], xyz) / d,
    ];
    let nm: Vec<f64> = (380..=780).map(f64::from).collect();
    let values = (0..nm.len())
        .map(|i| (0..3).map(|k| a[k] * basis[k].values()[i]).sum())
        .collect();
    Spectrum::new(nm, values).expect("an even grid")
}

/// The light of the simulated world when none is given: 100 cd/m² of CIE LED-RGB1, the
/// same light [`DEFAULT_STIMULUS_XYZ`](crate::world::DEFAULT_STIMULUS_XYZ) is the colour of.
pub fn default_light() -> Spectrum {
    let s = Illuminant::LedRgb1.spectrum();
    let y = radiance_to_xyz(&s, ObserverKind::Cie1931).y;
    s.scaled(100.0 / y)
}

impl I1ProEmulator {
    pub fn new(world: Arc<dyn World>, config: EmulatorConfig) -> Result<I1ProEmulator, String> {
        if !(1..=synthetic::CLOCK_MODES.len() as u8).contains(&config.clock_modes) {
            return Err(format!(
                "clock_modes={}: the simulated unit has 1 or 2",
                config.clock_modes
            ));
        }
        let mut unit = synthetic::calibration(config.revision);
        if config.no_ambient_table {
            unit.ambient = None;
        }
        let image = synthetic::image_of(&unit, &config.missing_keys).map_err(|e| e.to_string())?;
        // The emulator computes with what the driver will read: the full image, parsed.
        let full = synthetic::image_of(&unit, &[]).map_err(|e| e.to_string())?;
        let cal = super::unit_calibration(&full, config.revision).map_err(|e| e.to_string())?;
        Ok(I1ProEmulator {
            low_power: (config.low_power_polls > 0).then_some((false, config.low_power_polls)),
            rng: config.seed,
            noise: crate::noise::NoiseCursor::default(),
            config,
            world,
            cal,
            image,
            params: (0.0, 0, false),
            mode: 1,
            pending: None,
            measurements: 0,
            real_pace: super::ManualClock::new(),
        })
    }

    /// The clock the simulated unit's measurements advance at the real unit's pace (a
    /// session's instrument time, also when it runs at `time_scale` 0).
    pub fn real_pace_clock(&self) -> super::ManualClock {
        self.real_pace.clone()
    }

    /// The handle a session moves the noise stream with (see
    /// [`NoiseCursor`](crate::noise::NoiseCursor)).
    pub fn noise_cursor(&self) -> crate::noise::NoiseCursor {
        self.noise.clone()
    }

    /// The clock mode in force as GetClockMode reports it.
    fn clock_mode(&self) -> metamer_protocols::i1pro::replies::ClockMode {
        let mut c = synthetic::CLOCK_MODES[usize::from(self.mode) - 1];
        c.max = self.config.clock_modes;
        c.current = self.mode;
        c
    }

    /// The integration clock and sub-clock divider in force.
    fn clock(&self) -> (f64, u64) {
        match self.config.revision {
            Revision::AToD => {
                let c = self.clock_mode();
                (c.clock_s(), u64::from(c.sub_clock_divider))
            }
            Revision::E => (
                MeasChar::KNOWN.clock_s(),
                u64::from(MeasChar::KNOWN.divider),
            ),
        }
    }

    /// The integration time of `int_clocks` clocks, or None where the unit refuses it:
    /// less than one sub-clock of the mode in force.
    fn integration(&self, int_clocks: u64) -> Option<f64> {
        let (clock_s, divider) = self.clock();
        (int_clocks >= divider).then_some(int_clocks as f64 * clock_s)
    }

    /// Dark counts of cell `j` after `t` seconds: the converter's bias, a whole number of
    /// counts, and a dark current of 25–35 counts per second, both varying from cell to
    /// cell. (A fractional bias would put up to half a count of rounding into the short
    /// dark, which the driver's interpolation carries to every integration time.)
    pub fn dark_count(j: usize, t: f64) -> f64 {
        let j = j as f64;
        (120.0 + 10.0 * (0.37 * j).sin()).round() + (30.0 + 5.0 * (0.11 * j).cos()) * t
    }

    fn gauss(&mut self) -> f64 {
        // Box–Muller on two SplitMix64 uniforms.
        let mut u = || {
            self.rng = self.rng.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = self.rng;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            z ^= z >> 31;
            ((z >> 11) as f64 + 0.5) / (1u64 << 53) as f64
        };
        let (a, b) = (u(), u());
        (-2.0 * a.ln()).sqrt() * (std::f64::consts::TAU * b).cos()
    }

    /// The resampled, uncalibrated values the instrument sees now.
    fn seen(&self, lamp_on: bool) -> Result<GridSpectrum, String> {
        let cal = &self.cal;
        let err = |e: pipeline::PipelineError| e.to_string();
        let zero = [0.0; BANDS];
        Ok(match (self.world.view(), lamp_on) {
            (View::Emissive(light), false) if self.config.diffuser => {
                let mut e = light_bands(&light);
                e.iter_mut().for_each(|v| *v *= std::f64::consts::PI);
                inverse::uncalibrate_ambient(cal, &e).map_err(err)?
            }
            (View::Emissive(light), false) => {
                inverse::uncalibrate_emissive(cal, &light_bands(&light)).map_err(err)?
            }
            (View::Emissive(_), true) | (View::Capped, _) => zero,
            (_, false) => zero,
            (View::WhiteTile, true) => {
                let r = cal.white_reference.unwrap_or([0.9; BANDS]);
                std::array::from_fn(|w| r[w] * lamp(START_NM + STEP_NM * w as f64))
            }
            (View::Surface(s), true) => std::array::from_fn(|w| {
                let nm = START_NM + STEP_NM * w as f64;
                s.value_at(nm) * lamp(nm)
            }),
        })
    }

    fn readings(&mut self, t: f64, n: u64, lamp_on: bool) -> Result<Vec<u8>, String> {
        let e = Exposure {
            integration_s: t,
            gain: Gain::Normal,
        };
        let err = |e: pipeline::PipelineError| e.to_string();
        let revision = self.config.revision;
        let dark_counts: Vec<f64> = (0..CELLS).map(|j| Self::dark_count(j, t)).collect();
        let shielded_count = (0..SHIELDED_CELLS)
            .map(|j| Self::dark_count(CELLS + j, t).round() as u16)
            .collect::<Vec<_>>();
        let shielded: Option<[u16; SHIELDED_CELLS]> =
            (revision == Revision::E).then(|| std::array::from_fn(|j| shielded_count[j]));
        let dark_raw = RawReading {
            cells: std::array::from_fn(|j| dark_counts[j].round() as i32),
            shielded,
        };
        let dark: AbsRaw = pipeline::to_absraw(&self.cal, &dark_raw, &e).map_err(err)?;
        let seen = self.seen(lamp_on)?;
        let signal = inverse::cells_for(&self.cal, &seen).map_err(err)?;
        let clean =
            inverse::counts_for(&self.cal, &e, &signal, &dark, shielded, u16::MAX).map_err(err)?;
        // Each measurement's noise from its own stream (see NoiseCursor).
        self.rng = self.noise.next_stream(self.config.seed).next_u64();
        let mut out = Vec::new();
        for _ in 0..n {
            let mut r = clean.clone();
            for (j, c) in r.cells.iter_mut().enumerate() {
                let mut v = f64::from(*c);
                if self.config.noise {
                    // Shot noise of everything the cell collected (the light and the dark
                    // current, not the converter's bias), and the read noise.
                    let collected = (v - Self::dark_count(j, 0.0)).max(0.0);
                    v += (collected + READ_NOISE * READ_NOISE).sqrt() * self.gauss();
                }
                *c = v.round().clamp(0.0, FULL_WELL) as i32;
            }
            out.push(r);
        }
        readings::encode(&out, revision, synthetic::MAX_POSITIVE).map_err(|e| e.to_string())
    }

    fn start(&mut self, t: f64, n: u64, lamp_on: bool) -> TransferAnswer<()> {
        match self.readings(t, n, lamp_on) {
            Ok(bytes) => {
                let t = t * n as f64
                    + if lamp_on {
                        super::wire::LAMP_WARMUP_S
                    } else {
                        0.0
                    };
                self.real_pace.advance(t);
                let delay = crate::link::duration_s(t * self.config.time_scale);
                self.measurements += 1;
                self.pending = Some((delay, bytes));
                TransferAnswer::Done(())
            }
            Err(_) => TransferAnswer::Stall,
        }
    }
}

fn transfer_in(setup: ControlSetup, len: usize) -> Transfer {
    Transfer::In {
        setup: Setup {
            request_type: setup.request_type,
            request: setup.request,
            value: setup.value,
            index: setup.index,
        },
        length: len as u16,
    }
}

impl UsbDevice for I1ProEmulator {
    fn control_in(&mut self, setup: ControlSetup, len: usize) -> TransferAnswer<Vec<u8>> {
        let revision = self.config.revision;
        match Request::decode(&transfer_in(setup, len), revision) {
            Ok(Request::GetMisc) => {
                let mut misc = synthetic::misc(revision);
                misc.firmware = self.config.firmware();
                if let Some((reset, left)) = self.low_power {
                    misc.power = metamer_protocols::i1pro::replies::POWER_LOW;
                    if reset {
                        self.low_power = left.checked_sub(1).filter(|n| *n > 0).map(|n| (true, n));
                    }
                }
                TransferAnswer::Done(misc.encode().to_vec())
            }
            Ok(Request::GetClockMode) if self.config.has_clock_modes() => {
                TransferAnswer::Done(self.clock_mode().encode().to_vec())
            }
            Ok(Request::GetMeasChar) => TransferAnswer::Done(MeasChar::KNOWN.encode().to_vec()),
            Ok(Request::GetEepromSize) => {
                TransferAnswer::Done((self.image.len() as u32).to_be_bytes().to_vec())
            }
            Ok(Request::GetChipId) => TransferAnswer::Done(vec![0; 8]),
            _ => TransferAnswer::Stall,
        }
    }

    fn control_out(&mut self, setup: ControlSetup, data: &[u8]) -> TransferAnswer<()> {
        let transfer = Transfer::Out {
            setup: Setup {
                request_type: setup.request_type,
                request: setup.request,
                value: setup.value,
                index: setup.index,
            },
            data: data.to_vec(),
        };
        match Request::decode(&transfer, self.config.revision) {
            Ok(Request::Reset { mask }) => {
                self.pending = None;
                if mask == metamer_protocols::i1pro::commands::RESET_POWER {
                    self.low_power = self.low_power.map(|(_, n)| (true, n));
                }
                TransferAnswer::Done(())
            }
            Ok(Request::ReadEeprom { address, length }) => {
                let (a, l) = (address as usize, usize::from(length));
                match self.image.get(a..a + l) {
                    Some(bytes) => {
                        self.pending = Some((Duration::ZERO, bytes.to_vec()));
                        TransferAnswer::Done(())
                    }
                    None => TransferAnswer::Stall,
                }
            }
            Ok(Request::SetClockMode(m))
                if self.config.has_clock_modes() && (1..=self.config.clock_modes).contains(&m) =>
            {
                self.mode = m;
                TransferAnswer::Done(())
            }
            Ok(Request::SetClockMode(_)) => TransferAnswer::Stall,
            Ok(Request::SetMeasParams(p)) => match self.integration(u64::from(p.int_clocks)) {
                Some(t) => {
                    self.params = (
                        t,
                        u64::from(p.readings),
                        p.flags & metamer_protocols::i1pro::commands::flags::LAMP_OFF == 0,
                    );
                    TransferAnswer::Done(())
                }
                None => TransferAnswer::Stall,
            },
            Ok(Request::Trigger)
                if self.config.fault == Some(Fault::StallTrigger(self.measurements + 1)) =>
            {
                TransferAnswer::Stall
            }
            Ok(Request::Trigger) if self.params.1 == 0 => TransferAnswer::Stall,
            Ok(Request::Trigger) => {
                let (t, n, lamp_on) = self.params;
                self.start(t, n, lamp_on)
            }
            Ok(Request::MeasureE(p)) => match self.integration(u64::from(p.int_clocks)) {
                Some(t) => {
                    let lamp_on = p.flags & metamer_protocols::i1pro::commands::flags_e::LAMP != 0;
                    self.start(t, u64::from(p.readings), lamp_on)
                }
                None => TransferAnswer::Stall,
            },
            Ok(_) => TransferAnswer::Done(()),
            Err(_) => TransferAnswer::Stall,
        }
    }

    fn read(&mut self, kind: TransferKind, endpoint: u8, len: usize) -> TransferAnswer<Vec<u8>> {
        if kind != TransferKind::Bulk || endpoint != EP_DATA_IN {
            return TransferAnswer::Silent;
        }
        let Some((delay, mut bytes)) = self.pending.take() else {
            return TransferAnswer::Silent;
        };
        let scaled = |d: Duration| d;
        match self.config.fault {
            Some(Fault::ShortRead(n)) if n == self.measurements && !bytes.is_empty() => {
                bytes.truncate(bytes.len() / 2);
            }
            Some(Fault::DisconnectMidRead(n)) if n == self.measurements => {
                return TransferAnswer::Disconnect
            }
            Some(Fault::SilentRead(n)) if n == self.measurements => return TransferAnswer::Silent,
            _ => {}
        }
        bytes.truncate(len);
        TransferAnswer::After(scaled(delay), bytes)
    }

    fn write(&mut self, _kind: TransferKind, _endpoint: u8, _data: &[u8]) -> TransferAnswer<()> {
        TransferAnswer::Stall
    }
}
