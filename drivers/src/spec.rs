//! Choosing an instrument by one string (architecture note: "device selection by one
//! string"):
//!
//! - `cs100a:PORT` — a CS-100A on a serial port (`cs100a:/dev/ttyUSB0`, `cs100a:COM3`);
//! - `replay:FILE.jsonl` — a transcript played through the real driver;
//! - `sim:cs100a` — the emulated CS-100A, answering from a world. Options after `?`,
//!   separated by `&`: `time_scale=F` (1 = the real meter's ≈100/400 ms per reading,
//!   0.01 a hundred times faster, 0 instant; default 1, or the environment variable
//!   `METAMER_SIM_TIME_SCALE`), `seed=N` (noise seed, default 1), `noise=off`;
//! - `sim:i1pro` — the emulated i1Pro on the in-process USB pair, with the same options and
//!   its own (`rev=d|e`, `diffuser=on`), listed in its registry row;
//! - `i1pro[:SERIAL]` — an i1Pro on USB (`i1pro` alone: the first one found).
//!
//! Which models exist and how each is opened is the driver registry's; this file only reads
//! the spec.

use std::path::Path;
use std::sync::Arc;

use crate::instrument::Instrument;
use crate::link::replay::Transcript;
use crate::open::{OpenOptions, SimSettings, TIME_SCALE_ENV};
use crate::registry::{self, Model, REPLAY_PREFIX, SIM_PREFIX};
use crate::world::World;
use crate::DriverError;

/// Opens the instrument `spec` names; `stimulus` is what a simulated one sees.
pub fn open_instrument(
    spec: &str,
    stimulus: Option<Arc<dyn World>>,
) -> Result<Box<dyn Instrument>, DriverError> {
    open_instrument_with(
        spec,
        &OpenOptions {
            stimulus,
            record: None,
        },
    )
}

/// [`open_instrument`] with recording and other options.
pub fn open_instrument_with(
    spec: &str,
    options: &OpenOptions,
) -> Result<Box<dyn Instrument>, DriverError> {
    open_in(registry::MODELS, spec, options)
}

/// Whether `spec` names an instrument that could be opened, without opening it: the form,
/// the model and a simulation's options. A command that opens its instruments only after
/// minutes of other work checks them first, so a typo fails at once. A real instrument's
/// port and a transcript's content are only looked at when opened.
pub fn check_spec(spec: &str) -> Result<(), DriverError> {
    check_in(registry::MODELS, spec)
}

/// Whether `spec` names a physical instrument (`cs100a:PORT`, `i1pro[:SERIAL]`): not a
/// simulation and not a replayed transcript, so something real is measured and somebody
/// has to place, aim or calibrate it. A spec naming no model is not (opening it fails).
pub fn is_physical(spec: &str) -> bool {
    is_physical_in(registry::MODELS, spec)
}

fn is_physical_in(models: &[Model], spec: &str) -> bool {
    let (kind, _) = spec.split_once(':').unwrap_or((spec, ""));
    kind != REPLAY_PREFIX
        && kind != SIM_PREFIX
        && models
            .iter()
            .any(|m| m.spec_prefixes.contains(&kind) && m.real.is_some())
}

fn check_in(models: &[Model], spec: &str) -> Result<(), DriverError> {
    let unknown = || DriverError::UnknownSpec {
        spec: spec.to_string(),
        expected: registry::spec_forms(),
    };
    let (kind, rest) = spec.split_once(':').unwrap_or((spec, ""));
    match kind {
        REPLAY_PREFIX if !rest.is_empty() => Ok(()),
        SIM_PREFIX => {
            let (model, query) = rest.split_once('?').unwrap_or((rest, ""));
            let row = models
                .iter()
                .find(|m| m.name == model && m.sim.is_some())
                .ok_or_else(unknown)?;
            sim_settings(spec, query, row.sim_options).map(drop)
        }
        prefix => match models
            .iter()
            .find(|m| m.spec_prefixes.contains(&prefix))
            .and_then(|m| m.real)
        {
            Some(real) if !rest.is_empty() || !real.address_required => Ok(()),
            _ => Err(unknown()),
        },
    }
}

/// Opens `spec` from the rows of `models` (the registry's, or a test's own).
fn open_in(
    models: &[Model],
    spec: &str,
    options: &OpenOptions,
) -> Result<Box<dyn Instrument>, DriverError> {
    let unknown = || DriverError::UnknownSpec {
        spec: spec.to_string(),
        expected: registry::spec_forms(),
    };
    let by_name = |name: &str| models.iter().find(|m| m.name == name);
    // A bare prefix (`i1pro`) opens a model whose address may be left out.
    let (kind, rest) = spec.split_once(':').unwrap_or((spec, ""));
    match kind {
        REPLAY_PREFIX if !rest.is_empty() => {
            let transcript = Transcript::load(Path::new(rest))?;
            let instrument = transcript.header.instrument.clone();
            let open = by_name(&instrument).and_then(|m| m.replay).ok_or_else(|| {
                DriverError::Transcript {
                    file: rest.to_string(),
                    line: 1,
                    message: format!(
                        "the transcript is of instrument '{instrument}', which has no driver yet \
                         (known: {})",
                        registry::replayable().join(", ")
                    ),
                }
            })?;
            open(transcript, options)
        }
        SIM_PREFIX => {
            let (model, query) = rest.split_once('?').unwrap_or((rest, ""));
            let row = by_name(model)
                .filter(|m| m.sim.is_some())
                .ok_or_else(unknown)?;
            let open = row.sim.ok_or_else(unknown)?;
            open(&sim_settings(spec, query, row.sim_options)?, options)
        }
        prefix => match models
            .iter()
            .find(|m| m.spec_prefixes.contains(&prefix))
            .and_then(|m| m.real)
        {
            Some(real) if !rest.is_empty() || !real.address_required => (real.open)(rest, options),
            _ => Err(unknown()),
        },
    }
}

/// Parses `time_scale=…&seed=…&noise=off`.
fn sim_settings(
    spec: &str,
    query: &str,
    model_options: &[&str],
) -> Result<SimSettings, DriverError> {
    let bad = |message: String| DriverError::BadSpecOption {
        spec: spec.to_string(),
        message,
    };
    let mut config = SimSettings::default();
    if let Ok(v) = std::env::var(TIME_SCALE_ENV) {
        config.time_scale =
            parse_scale(&v).ok_or_else(|| bad(format!("{TIME_SCALE_ENV}={v:?} {SCALE_RANGE}")))?;
    }
    for option in query.split('&').filter(|o| !o.is_empty()) {
        let (key, value) = option.split_once('=').unwrap_or((option, ""));
        match key {
            "time_scale" => {
                config.time_scale = parse_scale(value)
                    .ok_or_else(|| bad(format!("time_scale={value:?} {SCALE_RANGE}")))?
            }
            "seed" => {
                config.seed = value
                    .parse()
                    .map_err(|_| bad(format!("seed={value:?} is not a whole number")))?
            }
            "noise" => {
                config.noise = match value {
                    "on" => true,
                    "off" => false,
                    _ => return Err(bad(format!("noise={value:?}: expected on or off"))),
                }
            }
            key if model_options.contains(&key) => {
                config.extra.push((key.to_string(), value.to_string()))
            }
            _ => {
                let mut known = vec!["time_scale", "seed", "noise"];
                known.extend(model_options);
                return Err(bad(format!(
                    "unknown option '{key}' (known: {})",
                    known.join(", ")
                )));
            }
        }
    }
    Ok(config)
}

/// Slowest simulated pace: 1000 times the real instrument's already makes one CS-100A
/// reading take minutes; beyond it a scale can only be a typo, and the emulator's delays
/// would overflow.
const MAX_TIME_SCALE: f64 = 1000.0;
const SCALE_RANGE: &str = "is not a number from 0 to 1000 (1 = the real instrument's pace)";

fn parse_scale(v: &str) -> Option<f64> {
    v.trim()
        .parse::<f64>()
        .ok()
        .filter(|s| (0.0..=MAX_TIME_SCALE).contains(s))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::instrument::{MeasureMode, Request};
    use crate::world::SharedWorld;

    #[test]
    fn sim_measures_the_given_stimulus() {
        let light = Arc::new(SharedWorld::new([0.0; 3]));
        let mut m = open_instrument(
            "sim:cs100a?time_scale=0&noise=off",
            Some(light.clone() as Arc<dyn World>),
        )
        .unwrap();
        light.set([95.047, 100.0, 108.883]);
        let r = m.measure(&Request::default()).unwrap();
        // D65 white: x = 0.31272, y = 0.32903; the meter rounds to 4 decimals.
        assert!((r.xyy[0] - 0.3127).abs() < 1e-9 && (r.xyy[1] - 0.3290).abs() < 1e-9);
        assert_eq!(r.xyy[2], 100.0);
        assert!(r.flags.is_empty());
        assert_eq!(r.instrument, "cs100a");
        light.set([0.3, 0.3, 0.3]);
        let r = m.measure(&Request::default()).unwrap();
        assert!((r.xyy[2] - 0.3).abs() < 1e-9);
    }

    #[test]
    fn info_capabilities_and_unsupported_requests() {
        let mut m = open_instrument("sim:cs100a?time_scale=0", None).unwrap();
        assert_eq!(m.info().model, "cs100a");
        assert_eq!(m.info().connection, "sim:cs100a");
        let caps = serde_json::to_value(m.capabilities()).unwrap();
        assert_eq!(
            caps["options"][0]["values"]["choice"],
            serde_json::json!(["fast", "slow"])
        );
        assert_eq!(caps["modes"][0]["mode"], "emissive");
        assert_eq!(m.calibration_needed(MeasureMode::Emissive).unwrap(), None);
        let e = m
            .measure(&Request {
                mode: crate::MeasureMode::Reflective,
            })
            .unwrap_err();
        assert!(
            e.to_string().starts_with("the cs100a cannot do reflective"),
            "{e}"
        );
    }

    #[test]
    fn only_a_device_spec_is_physical() {
        for spec in [
            "cs100a:/dev/ttyUSB0",
            "cs100a:COM3",
            "i1pro",
            "i1pro:1234567",
        ] {
            assert!(is_physical(spec), "{spec}");
        }
        for spec in [
            "sim:cs100a",
            "sim:i1pro?time_scale=0",
            "replay:session.jsonl",
            "replay:cs100a:odd-name.jsonl",
            "i1d3:1",
            "",
        ] {
            assert!(!is_physical(spec), "{spec}");
        }
    }

    #[test]
    fn a_spec_is_checked_as_opening_would_check_it() {
        for good in [
            "sim:cs100a?time_scale=0&seed=3",
            "sim:i1pro?rev=e",
            "replay:x.jsonl",
        ] {
            check_spec(good).unwrap_or_else(|e| panic!("{good}: {e}"));
        }
        for bad in [
            "sim:cs100a?time_scale=1e308",
            "sim:cs100a?noise=maybe",
            "sim:cs100a?rev=e",
            "sim:nothing",
            "cs100a",
            "nonsense:x",
        ] {
            let checked = check_spec(bad).err().map(|e| e.to_string());
            let opened = open_instrument(bad, None).err().map(|e| e.to_string());
            assert!(checked.is_some(), "{bad} passed the check");
            assert_eq!(checked, opened, "{bad}");
        }
    }

    #[test]
    fn default_stimulus_and_bad_specs() {
        let mut m = open_instrument("sim:cs100a?time_scale=0&noise=off", None).unwrap();
        let r = m.measure(&Request::default()).unwrap();
        assert_eq!(r.xyy[2], 100.0);
        assert!((r.xyy[0] - 0.4558).abs() < 1e-9, "{:?}", r.xyy);
        assert!((r.xyy[1] - 0.4211).abs() < 1e-9, "{:?}", r.xyy);
        for spec in ["nothing", "sim:i1d3", "cs100a:", "replay:"] {
            let e = open_instrument(spec, None).err().unwrap();
            assert!(
                e.to_string().contains("expected cs100a:PORT"),
                "{spec}: {e}"
            );
        }
        let e = open_instrument("sim:cs100a?speed=9", None).err().unwrap();
        assert!(e.to_string().contains("unknown option 'speed'"), "{e}");
        // A model's own options are known to it alone.
        let e = open_instrument("sim:cs100a?rev=e", None).err().unwrap();
        assert!(
            e.to_string()
                .ends_with("unknown option 'rev' (known: time_scale, seed, noise)"),
            "{e}"
        );
        let e = open_instrument("sim:i1pro?time_scale=0&rev=x", None)
            .err()
            .unwrap();
        assert!(e.to_string().contains("rev=\"x\": expected d or e"), "{e}");
        let e = open_instrument("sim:i1pro?colour=red", None).err().unwrap();
        assert!(
            e.to_string()
                .ends_with("(known: time_scale, seed, noise, rev, diffuser)"),
            "{e}"
        );
        let e = open_instrument("sim:cs100a?time_scale=-1", None)
            .err()
            .unwrap();
        assert!(e.to_string().contains("time_scale=\"-1\""), "{e}");
        // A scale whose delays no Duration can hold is refused when the spec is read,
        // not by a panic in the emulator thread later.
        for scale in ["1e308", "inf", "NaN", "1000.5"] {
            let e = open_instrument(&format!("sim:cs100a?time_scale={scale}"), None)
                .err()
                .unwrap_or_else(|| panic!("{scale} was accepted"));
            assert!(e.to_string().contains("from 0 to 1000"), "{e}");
        }
    }

    #[test]
    fn a_transcript_of_a_model_without_a_driver_names_those_with_one() {
        let dir = std::env::temp_dir().join(format!("metamer-spec-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("i1d3.jsonl");
        std::fs::write(
            &path,
            "{\"format\":\"metamer-transcript/1\",\"instrument\":\"i1d3\",\"transport\":\"hid\",\
             \"origin\":\"synthesized from the protocol documentation\"}\n",
        )
        .unwrap();
        let e = open_instrument(&format!("replay:{}", path.display()), None)
            .err()
            .unwrap()
            .to_string();
        assert!(
            e.ends_with("line 1: the transcript is of instrument 'i1d3', which has no driver yet (known: cs100a, i1pro)"),
            "{e}"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_world_given_as_a_spectrum_is_read_through_the_colour_core() {
        use crate::world::View;
        use metamer_color::Spectrum;
        // 0.1 W·sr⁻¹·m⁻²·nm⁻¹ flat over 380–780 nm: Y = 68.3 · Σȳ. Summed with awk over
        // the 380–780 nm rows of data/cie1931_2deg_cmf_1nm.csv: Σx̄ 106.855085, Σȳ 106.856426,
        // Σz̄ 106.846082, so Y = 7298.294 cd/m² and (x, y) = (0.333341, 0.333345); the meter
        // sends four significant digits of Y here and four decimals of x, y.
        let flat = Spectrum::constant(380.0, 780.0, 0.1);
        let light = Arc::new(SharedWorld::new(View::radiance(flat).unwrap()));
        let mut m = open_instrument(
            "sim:cs100a?time_scale=0&noise=off",
            Some(light as Arc<dyn World>),
        )
        .unwrap();
        let r = m.measure(&Request::default()).unwrap();
        assert_eq!(r.xyy[2], 7298.0, "{:?}", r.xyy);
        assert!(
            (r.xyy[0] - 0.3333).abs() < 1e-9 && (r.xyy[1] - 0.3333).abs() < 1e-9,
            "{:?}",
            r.xyy
        );
    }

    fn fake_open(address: &str, _: &OpenOptions) -> Result<Box<dyn Instrument>, DriverError> {
        Err(DriverError::Simulation(format!("opened at '{address}'")))
    }

    /// A USB-like model whose address (a serial number) may be left out.
    const FAKE: &[Model] = &[Model {
        name: "fake",
        title: "Fake",
        usb: &[],
        spec_prefixes: &["fake", "fk"],
        real: Some(registry::Real {
            address: "SERIAL",
            address_required: false,
            open: fake_open,
        }),
        replay: None,
        sim: None,
        sim_options: &[],
    }];

    #[test]
    fn a_row_is_opened_by_any_of_its_prefixes_with_or_without_its_optional_address() {
        let opened = |spec: &str| {
            open_in(FAKE, spec, &OpenOptions::default())
                .err()
                .unwrap()
                .to_string()
        };
        assert_eq!(opened("fake"), "simulated instrument: opened at ''");
        assert_eq!(opened("fake:"), "simulated instrument: opened at ''");
        assert_eq!(opened("fk:A123"), "simulated instrument: opened at 'A123'");
        // What the table does not offer is an unknown spec, never another row's opener.
        for spec in ["sim:fake", "cs100a:/dev/ttyS0", "fak"] {
            assert!(opened(spec).starts_with("unknown instrument"), "{spec}");
        }
        // The CS-100A's port is required.
        let e = open_instrument("cs100a", None).err().unwrap().to_string();
        assert!(e.starts_with("unknown instrument 'cs100a'"), "{e}");
    }
}
