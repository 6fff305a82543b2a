//! A whole exchange through the codec with a simulated instrument on the other side: the host
//! encodes requests, the "device" decodes them and answers from a calibration and a light
//! spectrum using only the codec's device-side functions, and the host turns the bytes back
//! into the spectrum. This is how the driver and the simulated i1Pro are meant to use it.

use super::calibration::Gain;
use super::commands::{flags, MeasParams, MeasParamsE, Request, Transfer};
use super::pipeline::{self, Exposure};
use super::readings::{self, RawReading};
use super::replies::Misc;
use super::timing::clocks;
use super::{fixture, inverse, Calibration, GridSpectrum, Model, Revision, BANDS, CELLS};

/// The simulated instrument: answers each transfer from its EEPROM image and the light.
struct Device {
    rev: Revision,
    cal: Calibration,
    image: Vec<u8>,
    light: GridSpectrum,
    dark_counts: i32,
    shielded: [u16; 6],
    pending: Option<(u32, u32)>,
}

const MAX_POSITIVE: u16 = 0xFFFF;
const CLOCK_S: f64 = 68e-6;

impl Device {
    /// The reply of an IN transfer, or the bulk data an OUT transfer starts.
    fn handle(&mut self, t: &Transfer) -> Vec<u8> {
        match Request::decode(t, self.rev).unwrap() {
            Request::GetMisc => Misc {
                firmware: if self.rev == Revision::E { 629 } else { 302 },
                unknown1: 0,
                max_positive: MAX_POSITIVE,
                unknown3: 1,
                power: 0,
            }
            .encode()
            .to_vec(),
            Request::ReadEeprom { address, length } => {
                let a = address as usize;
                self.image[a..a + usize::from(length)].to_vec()
            }
            Request::SetMeasParams(p) => {
                self.pending = Some((u32::from(p.int_clocks), u32::from(p.readings)));
                vec![]
            }
            Request::Trigger => self.readings(),
            Request::MeasureE(p) => {
                self.pending = Some((p.int_clocks, p.readings));
                self.readings()
            }
            other => panic!("the simulated device does not expect {other:?}"),
        }
    }

    fn exposure(&self, int_clocks: u32) -> Exposure {
        let clock = if self.rev == Revision::E {
            36e-6
        } else {
            CLOCK_S
        };
        Exposure {
            integration_s: f64::from(int_clocks) * clock,
            gain: Gain::Normal,
        }
    }

    fn dark_reading(&self) -> RawReading {
        RawReading {
            cells: [self.dark_counts; CELLS],
            shielded: (self.rev == Revision::E).then_some(self.shielded),
        }
    }

    /// Readings of the light as the pipeline run backwards gives them.
    fn readings(&mut self) -> Vec<u8> {
        let (int_clocks, n) = self.pending.take().unwrap();
        let e = self.exposure(int_clocks);
        let dark = pipeline::dark(&self.cal, &[self.dark_reading()], &e).unwrap();
        let shielded = (self.rev == Revision::E).then_some(self.shielded);
        let r = inverse::emissive_reading(
            &self.cal,
            &e,
            &self.light,
            &dark.mean,
            shielded,
            MAX_POSITIVE,
        )
        .unwrap();
        let all = vec![r; n as usize];
        readings::encode(&all, self.rev, MAX_POSITIVE).unwrap()
    }
}

fn session(model: Model, cal: Calibration) {
    let rev = model.revision();
    let light = fixture::spectrum(|w| 5.0 + 0.25 * w);
    let mut dev = Device {
        rev,
        image: cal.to_image().unwrap(),
        cal,
        light,
        dark_counts: 300,
        shielded: [280, 290, 300, 310, 320, 300],
        pending: None,
    };

    // Identify, then read and parse the whole EEPROM.
    let misc = Misc::parse(&dev.handle(&Request::GetMisc.encode(rev).unwrap())).unwrap();
    assert!(misc.high_power());
    let len = dev.image.len() as u16;
    let read = Request::ReadEeprom {
        address: 0,
        length: len,
    };
    let image = dev.handle(&read.encode(rev).unwrap());
    let cal = Calibration::from_image(&image, model).unwrap();
    assert_eq!(cal, dev.cal);

    // One emissive measurement of 3 readings at ~0.5 s, lamp off.
    let (t_clock, max) = if rev == Revision::E {
        (36e-6, u64::from(u32::MAX))
    } else {
        (CLOCK_S, 0xFFFF)
    };
    let int_clocks = clocks("integration time", 0.5, t_clock, max).unwrap();
    let bytes = match rev {
        Revision::AToD => {
            let p = MeasParams {
                int_clocks: int_clocks as u16,
                lamp_clocks: 0,
                readings: 3,
                flags: flags::LAMP_OFF | flags::NORMAL_GAIN,
            };
            assert!(dev
                .handle(&Request::SetMeasParams(p).encode(rev).unwrap())
                .is_empty());
            dev.handle(&Request::Trigger.encode(rev).unwrap())
        }
        Revision::E => {
            let p = MeasParamsE {
                int_clocks: int_clocks as u32,
                lamp_clocks: 0,
                readings: 3,
                flags: 0,
            };
            dev.handle(&Request::MeasureE(p).encode(rev).unwrap())
        }
    };
    let readings = readings::parse(&bytes, rev, 3, misc.max_positive).unwrap();
    let e = dev.exposure(int_clocks as u32);
    // The host's own dark: what the device shows with the light off.
    let dark = pipeline::dark(&cal, &[dev.dark_reading()], &e).unwrap();
    let (s, avg) = pipeline::measure(&cal, &readings, &dark.mean, &e).unwrap();
    assert!(!avg.saturated && !avg.inconsistent);
    let radiance = pipeline::emissive(&cal, &s);
    for w in 0..BANDS {
        // Count rounding: 0.5 count × slope < 1.3 / t × emissive factor × stray-light ≤ 1.1.
        let bound = 0.5 * 1.3 / e.integration_s * cal.emissive[w] * 1.1;
        assert!(
            (radiance[w] - light[w]).abs() <= bound,
            "{model:?} band {w}"
        );
    }
}

#[test]
fn rev_a_to_d_session_reads_the_light_back() {
    session(Model::I1Pro, fixture::calibration_a_to_d());
}

#[test]
fn rev_e_session_reads_the_light_back() {
    session(Model::I1Pro2, fixture::calibration_e());
}
