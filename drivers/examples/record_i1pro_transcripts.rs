//! Records the i1Pro transcripts in `protocols/i1pro/transcripts/` from the simulated i1Pro
//! through the USB record backend, and writes each header's `origin`, `description` and
//! `expect` (the steps `drivers/tests/i1pro_transcripts.rs` replays, with the readings the
//! live driver got). Run from the repository root:
//!
//! ```sh
//! cargo run --release -p metamer-drivers --example record_i1pro_transcripts
//! cargo run --release -p metamer-drivers --example record_i1pro_transcripts -- dark_patches
//! ```
//!
//! The second form records only the transcript it names (of those recorded by a function
//! of their own: `dark_patches`), leaving the others as they are.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use metamer_color::{colorchecker, radiance_to_xyz, ColorCheckerSet, ObserverKind, Spectrum};
use metamer_drivers::i1pro::emulator::{default_light, EmulatorConfig, Fault};
use metamer_drivers::i1pro::open::sim_with;
use metamer_drivers::i1pro::ManualClock;
use metamer_drivers::{
    CalibrationCondition, Instrument, MeasureMode, OpenOptions, Request, SharedWorld, View, World,
};
use metamer_protocols::i1pro::calibration::key;
use metamer_protocols::i1pro::Revision;
use serde_json::{json, Value};

/// One scenario's live run: the steps and their outcomes, in the harness's format.
struct Run {
    world: Arc<SharedWorld>,
    clock: ManualClock,
    m: Option<Box<dyn Instrument>>,
    steps: Vec<Value>,
}

impl Run {
    fn open(path: &Path, config: EmulatorConfig, view: View) -> Run {
        let world = Arc::new(SharedWorld::new(view));
        let clock = ManualClock::new();
        let _ = std::fs::remove_file(path);
        let options = OpenOptions {
            stimulus: None,
            record: Some(path.to_path_buf()),
        };
        let config = EmulatorConfig {
            time_scale: 0.0,
            ..config
        };
        let r = sim_with(
            world.clone() as Arc<dyn World>,
            config,
            &options,
            Arc::new(clock.clone()),
        );
        let (m, step) = match r {
            Ok(m) => (Some(m), json!({"open": "ok"})),
            Err(e) => (None, json!({"open": "error", "error": message(&e)})),
        };
        Run {
            world,
            clock,
            m,
            steps: vec![step],
        }
    }

    fn m(&mut self) -> &mut dyn Instrument {
        self.m.as_deref_mut().expect("opened")
    }

    fn option(&mut self, name: &str, value: &str) {
        self.m().set_option(name, value).unwrap();
        self.steps.push(json!({"option": [name, value]}));
    }

    fn calibrate(&mut self, mode: MeasureMode) {
        self.world.set(View::WhiteTile);
        let r = self.m().calibrate(mode, &CalibrationCondition::OnWhiteTile);
        self.steps.push(match r {
            Ok(_) => json!({"calibrate": mode.name()}),
            Err(e) => json!({"calibrate": mode.name(), "error": message(&e)}),
        });
    }

    fn advance(&mut self, s: f64) {
        self.clock.advance(s);
        self.steps.push(json!({"advance_s": s}));
    }

    /// Measures `view`; `light` is what an exact instrument would read (noise off only).
    fn measure(&mut self, mode: MeasureMode, view: View, exact: Option<[f64; 3]>) {
        self.world.set(view);
        let r = self.m().measure(&Request { mode });
        let mut step = json!({"measure": mode.name()});
        match r {
            Ok(r) => {
                step["XYZ"] = json!(r.xyz);
                step["integration_s"] = json!(r.integration_s);
                step["flags"] = json!(r.flags.iter().map(|f| f.name()).collect::<Vec<_>>());
                if let Some(x) = exact {
                    step["exact_XYZ"] = json!(x);
                }
            }
            Err(e) => step["error"] = json!(message(&e)),
        }
        self.steps.push(step);
    }

    fn finish(self, path: &Path, description: &str) {
        drop(self.m);
        let text = std::fs::read_to_string(path).unwrap();
        let (head, rest) = text.split_once('\n').unwrap();
        let mut header: Value = serde_json::from_str(head).unwrap();
        header["origin"] = json!("synthesized from the protocol documentation");
        header["description"] = json!(description);
        header["expect"] = Value::Array(self.steps);
        std::fs::write(path, format!("{header}\n{rest}")).unwrap();
        println!("{}", path.display());
    }
}

/// The error as the replay must show it: without the link's name, which is the
/// simulator's when recording and the file's when replaying.
fn message(e: &metamer_drivers::DriverError) -> String {
    let s = e.to_string();
    match s.find("disconnected during") {
        Some(i) => s[i..].to_string(),
        None => s,
    }
}

fn light() -> View {
    View::radiance(default_light()).unwrap()
}

/// The XYZ of the light on the instrument's 36 bands.
fn exact(s: &Spectrum) -> [f64; 3] {
    let grid = Spectrum::measured(380.0, 10.0, s.on_grid(380.0, 10.0, 36)).unwrap();
    radiance_to_xyz(&grid, ObserverKind::Cie1931).to_array()
}

fn quiet(revision: Revision) -> EmulatorConfig {
    EmulatorConfig {
        revision,
        noise: false,
        ..EmulatorConfig::default()
    }
}

/// A display's darkest patches on a noisy Rev D: a CRT's black (0.05 cd/m²), too dim for
/// one reading at 2 s, is read six times; a dimmer light, read six times, still does not
/// stand out of the noise; no light at all is too dark at once (no longer reading could
/// lift it); an LCD's black (0.22 cd/m²) is one reading.
fn dark_patches(dir: &Path) {
    let path = dir.join("dark_patches.jsonl");
    let noisy = EmulatorConfig {
        seed: 5,
        ..EmulatorConfig::default()
    };
    let mut r = Run::open(&path, noisy, View::WhiteTile);
    r.calibrate(MeasureMode::Emissive);
    for cd in [0.05, 0.025, 0.0, 0.22] {
        let view = if cd > 0.0 {
            View::radiance(default_light().scaled(cd / 100.0)).unwrap()
        } else {
            View::Capped
        };
        r.measure(MeasureMode::Emissive, view, None);
    }
    r.finish(&path, "Rev D with its noise (seed 5): a display's darkest patches. 0.05 cd/m² of LED-RGB1 (the ideal-crt preset's black) does not stand 5σ above the sensor's noise in one reading of 2 s, so five more readings of 2 s join it and the six are a reading; 0.025 cd/m², read six times, still does not (too dark, averaged over 6 readings); a capped sensor is too dark after one reading, since no longer reading could lift it; 0.22 cd/m² (the ips-lcd black) is one reading of 2 s. Recorded from sim:i1pro with noise on.");
}

fn main() {
    let dir = PathBuf::from("protocols/i1pro/transcripts");
    std::fs::create_dir_all(&dir).unwrap();
    if let Some(name) = std::env::args().nth(1) {
        match name.as_str() {
            "dark_patches" => dark_patches(&dir),
            other => panic!("no transcript '{other}' is recorded on its own (known: dark_patches)"),
        }
        return;
    }
    dark_patches(&dir);
    let p = |name: &str| dir.join(format!("{name}.jsonl"));
    let emissive = MeasureMode::Emissive;
    let reflective = MeasureMode::Reflective;
    let led = exact(&default_light());

    let path = p("open_emissive");
    let mut r = Run::open(&path, quiet(Revision::AToD), View::WhiteTile);
    r.calibrate(emissive);
    r.measure(emissive, light(), Some(led));
    r.finish(&path, "Rev D (firmware 505): open (GetMisc, reset, its two clock modes read by selecting each, whole EEPROM), dark calibration on the white tile (212 readings of 4.716 ms in clock mode 2, nine of 2 s in mode 1), one emissive reading of 100 cd/m² of LED-RGB1 with the integration time (1.82 s) found by a trial reading. Recorded from sim:i1pro with noise off.");

    let path = p("fixed_integration");
    let mut r = Run::open(&path, quiet(Revision::AToD), View::WhiteTile);
    r.calibrate(emissive);
    r.option("integration_s", "0.25");
    r.measure(emissive, light(), Some(led));
    r.finish(&path, "Rev D: emissive reading at a fixed integration time of 0.25 s (3676 clocks of 68 µs, three readings), no trial reading. Recorded from sim:i1pro with noise off.");

    let patches = colorchecker(ColorCheckerSet::BabelColorAverage);
    let path = p("reflective_calibration");
    let mut r = Run::open(&path, EmulatorConfig::default(), View::WhiteTile);
    r.calibrate(reflective);
    r.measure(reflective, View::surface(patches[0].clone()).unwrap(), None);
    r.measure(
        reflective,
        View::surface(patches[18].clone()).unwrap(),
        None,
    );
    r.finish(&path, "Rev D: reflective calibration on the white tile (a lamp-off dark and a lamp-lit white, 8 readings of 20 ms each), then ColorChecker dark skin and white 9.5. Recorded from sim:i1pro with its noise (seed 1).");

    let path = p("calibration_expired");
    let mut r = Run::open(&path, EmulatorConfig::default(), View::WhiteTile);
    r.calibrate(reflective);
    r.measure(
        reflective,
        View::surface(patches[14].clone()).unwrap(),
        None,
    );
    r.advance(1801.0);
    r.measure(
        reflective,
        View::surface(patches[14].clone()).unwrap(),
        None,
    );
    r.calibrate(reflective);
    r.measure(
        reflective,
        View::surface(patches[14].clone()).unwrap(),
        None,
    );
    r.finish(&path, "Rev D: a reflective reading, then 30 min 1 s later (the dark's validity on Rev A–D) the driver refuses to measure without a transfer, asks for the white tile again, calibrates and measures. Recorded from sim:i1pro with its noise; the clock is advanced by hand.");

    let path = p("saturated");
    let bright = View::radiance(default_light().scaled(1000.0)).unwrap();
    let mut r = Run::open(&path, quiet(Revision::AToD), View::WhiteTile);
    r.calibrate(emissive);
    r.measure(emissive, bright.clone(), None);
    r.option("integration_s", "0.5");
    r.measure(
        emissive,
        View::radiance(default_light().scaled(10.0)).unwrap(),
        None,
    );
    r.finish(&path, "Rev D: 100 000 cd/m² saturates the sensor at the trial time and again at the shortest time, 4.716 ms in clock mode 2 (too bright); then 1000 cd/m² at a fixed 0.5 s saturates too. Both are errors that say what to do, never a clipped spectrum. Recorded from sim:i1pro with noise off.");

    let path = p("too_dark");
    let mut r = Run::open(&path, quiet(Revision::AToD), View::WhiteTile);
    r.calibrate(emissive);
    r.measure(
        emissive,
        View::radiance(default_light().scaled(1e-6)).unwrap(),
        None,
    );
    r.finish(&path, "Rev D: 0.0001 cd/m² gives no signal distinguishable from the sensor's noise even at the longest integration time (2 s): too dark. Recorded from sim:i1pro with noise off.");

    let path = p("eeprom_missing_key");
    let r = Run::open(
        &path,
        EmulatorConfig {
            missing_keys: vec![key::EMISSIVE],
            ..quiet(Revision::AToD)
        },
        View::WhiteTile,
    );
    r.finish(&path, "Rev D whose EEPROM lacks the emissive calibration factors (key 0x044D): open reads the whole EEPROM and fails naming the key. Recorded from sim:i1pro with that key left out of its image.");

    let path = p("short_bulk_read");
    let mut r = Run::open(
        &path,
        EmulatorConfig {
            fault: Some(Fault::ShortRead(1)),
            ..quiet(Revision::AToD)
        },
        View::WhiteTile,
    );
    r.calibrate(emissive);
    r.finish(&path, "Rev D: the first dark's bulk read delivers 27136 of its 54272 bytes (212 readings); the driver reports the short read and makes no reading of it. Recorded from sim:i1pro with its short-read fault injected.");

    let path = p("disconnect_mid_read");
    let mut r = Run::open(
        &path,
        EmulatorConfig {
            fault: Some(Fault::DisconnectMidRead(3)),
            ..quiet(Revision::AToD)
        },
        View::WhiteTile,
    );
    r.calibrate(emissive);
    r.measure(emissive, light(), None);
    r.finish(&path, "Rev D: the instrument is unplugged while the driver waits for the trial reading's data: a disconnect error naming the request, no reading. Recorded from sim:i1pro with its disconnect fault injected.");

    let path = p("short_integration_bright");
    let mut r = Run::open(&path, quiet(Revision::AToD), View::WhiteTile);
    r.calibrate(emissive);
    let bright = default_light().scaled(300.0);
    r.measure(
        emissive,
        View::radiance(bright.clone()).unwrap(),
        Some(exact(&bright)),
    );
    r.measure(emissive, light(), Some(led));
    r.finish(&path, "Rev D: 30 000 cd/m² (a bare LED, a lamp): the trial at 0.1 s saturates, the trial at 4.716 ms (clock mode 2, 131 clocks of 36 µs) gives the rate, and the reading integrates 6.05 ms in mode 2, below mode 1's 8.84 ms; then 100 cd/m² in mode 1 again. Recorded from sim:i1pro with noise off.");

    let path = p("one_clock_mode_bright");
    let mut r = Run::open(
        &path,
        EmulatorConfig {
            clock_modes: 1,
            ..quiet(Revision::AToD)
        },
        View::WhiteTile,
    );
    r.calibrate(emissive);
    r.measure(emissive, View::radiance(bright).unwrap(), None);
    let lamp = default_light().scaled(200.0);
    r.measure(
        emissive,
        View::radiance(lamp.clone()).unwrap(),
        Some(exact(&lamp)),
    );
    r.finish(&path, "Rev D that reports one clock mode (68 µs × 130): the shortest integration is 8.84 ms, never less; 30 000 cd/m² saturates there (too bright, the unit has no shorter mode), 20 000 cd/m² is measured at 9.0 ms. Recorded from sim:i1pro with one clock mode and noise off.");

    let path = p("display_luminances");
    let mut r = Run::open(&path, quiet(Revision::AToD), View::WhiteTile);
    r.calibrate(emissive);
    for cd in [0.22, 10.0, 300.0, 1000.0] {
        let s = default_light().scaled(cd / 100.0);
        let x = (cd >= 100.0).then(|| exact(&s));
        r.measure(emissive, View::radiance(s).unwrap(), x);
    }
    r.finish(&path, "Rev D: the integration times real luminances force: a display's black (0.22 cd/m²) and 10 cd/m² at the longest time (2 s), 300 cd/m² at 0.60 s, a 1000 cd/m² light tile at 0.18 s. Recorded from sim:i1pro with noise off.");

    let path = p("ambient_no_table");
    let mut r = Run::open(
        &path,
        EmulatorConfig {
            no_ambient_table: true,
            ..quiet(Revision::AToD)
        },
        View::WhiteTile,
    );
    r.measure(MeasureMode::Ambient, light(), None);
    r.calibrate(emissive);
    r.measure(emissive, light(), Some(led));
    r.finish(&path, "Rev D whose EEPROM's capability bits (0x0BC2 = 0x6000) claim the diffuser while its ambient table (0x044E) is the −1 \"no ambient\" marker: ambient mode is refused with the reason, before any transfer; emissive readings work. Recorded from sim:i1pro with that table.");

    let path = p("rev_e_open_reading");
    let mut r = Run::open(&path, quiet(Revision::E), View::WhiteTile);
    r.calibrate(emissive);
    r.measure(emissive, light(), Some(led));
    r.finish(&path, "Rev E (i1Pro 2, firmware 629): open (GetMisc, reset, measurement characteristics, EEPROM size, 16 KiB EEPROM with both directories), bands from the factory wavelength cubic, dark calibration (204 readings of 4.896 ms, nine of 2 s) and one emissive reading with 0xD4. Recorded from sim:i1pro?rev=e with noise off.");
}
