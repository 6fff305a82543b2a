//! The emulated CS-100A on a pseudo-terminal, opened through the real `serialport` backend
//! exactly as a meter on /dev/ttyUSB0 would be.
#![cfg(unix)]

use std::io::{Read, Write};
use std::sync::Arc;
use std::time::Duration;

use metamer_drivers::cs100a::emulator::{Cs100aEmulator, EmulatorConfig};
use metamer_drivers::cs100a::pty::PtyEmulator;
use metamer_drivers::{
    open_instrument, open_instrument_with, OpenOptions, Request, SharedWorld, Speed, World,
};

/// XYZ of an sRGB-red-like patch: x = 0.64, y = 0.33, Y = 21.26 cd/m².
const RED: [f64; 3] = [0.64 / 0.33 * 21.26, 21.26, 0.03 / 0.33 * 21.26];

fn start(light: Arc<SharedWorld>, seed: u64) -> PtyEmulator {
    let config = EmulatorConfig {
        seed,
        // A hundredth of the meter's pace: FAST ≈ 1.6 ms, SLOW ≈ 4.6 ms per reading.
        time_scale: 0.01,
        noise: true,
    };
    PtyEmulator::start(Cs100aEmulator::new(light, config)).unwrap()
}

#[test]
fn readings_through_the_real_serial_backend() {
    let light = Arc::new(SharedWorld::new(RED));
    let emu = start(light.clone(), 3);
    let spec = format!("cs100a:{}", emu.path());
    let mut meter = open_instrument(&spec, None).unwrap();
    assert_eq!(meter.info().connection, emu.path());
    for speed in [Speed::Fast, Speed::Slow, Speed::Fast] {
        meter.set_option("speed", speed.name()).unwrap();
        let r = meter.measure(&Request::default()).unwrap();
        // Repeatability ±0.2 % (2σ) in Y and ±0.001 in x, y; 5σ bounds plus the meter's
        // rounding to 4 significant digits / 4 decimals.
        assert!((r.xyy[2] / 21.26 - 1.0).abs() < 0.005 + 5e-4, "{r:?}");
        assert!((r.xyy[0] - 0.64).abs() < 0.0026, "{r:?}");
        assert!((r.xyy[1] - 0.33).abs() < 0.0026, "{r:?}");
        assert!(r.flags.is_empty());
    }
    // The light changes (a display shows the next patch): low light is flagged.
    light.set([0.004, 0.005, 0.006]);
    let r = meter.measure(&Request::default()).unwrap();
    assert_eq!(r.flags, vec![metamer_drivers::Flag::LowLight]);
    light.set([700_000.0; 3]);
    let e = meter.measure(&Request::default()).unwrap_err().to_string();
    assert!(
        e.contains("ER10: luminance and chromaticity over the measuring range"),
        "{e}"
    );
}

#[test]
fn a_recorded_session_replays_to_the_same_readings() {
    let dir = std::env::temp_dir().join(format!("metamer-pty-rec-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("session.jsonl");
    let _ = std::fs::remove_file(&path);
    let emu = start(Arc::new(SharedWorld::new(RED)), 9);
    let options = OpenOptions {
        stimulus: None,
        record: Some(path.clone()),
    };
    let mut live = open_instrument_with(&format!("cs100a:{}", emu.path()), &options).unwrap();
    let a = [live.measure(&Request::default()).unwrap(), {
        live.set_option("speed", "slow").unwrap();
        live.measure(&Request::default()).unwrap()
    }];
    drop(live);
    let mut replayed = open_instrument(&format!("replay:{}", path.display()), None).unwrap();
    let b = [replayed.measure(&Request::default()).unwrap(), {
        replayed.set_option("speed", "slow").unwrap();
        replayed.measure(&Request::default()).unwrap()
    }];
    for (a, b) in a.iter().zip(&b) {
        assert_eq!(a.xyy, b.xyy);
        assert_eq!(a.xyz, b.xyz);
    }
    // The recording is a transcript the replay tests accept: header, then events.
    let text = std::fs::read_to_string(&path).unwrap();
    let first = text.lines().next().unwrap();
    assert!(first.contains(r#""origin":"recorded""#), "{first}");
    assert!(first.contains(r#""parity":"even""#), "{first}");
    assert!(text.contains(r#""data":"MDS,07\r\n""#), "{text}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn the_real_backend_sets_4800_7e2_and_talks_to_the_meter() {
    use metamer_drivers::cs100a::Cs100a;
    use metamer_drivers::link::serial::PortLink;
    use metamer_drivers::link::LineSettings;
    let emu = start(Arc::new(SharedWorld::new(RED)), 2);
    let link = PortLink::open(emu.path(), LineSettings::CS100A).unwrap();
    let os = link.os_settings().unwrap();
    assert_eq!((os.baud, os.stop_bits), (4800, 2), "{os:?}");
    // Linux's pty driver forces CS8 without parity whatever is asked (pty_set_termios in
    // drivers/tty/pty.c), so 7E on a pty reads back as 8N there; a real port keeps 7E.
    let seven_even = (os.data_bits, os.parity) == (7, metamer_drivers::link::Parity::Even);
    let pty_forced = (os.data_bits, os.parity) == (8, metamer_drivers::link::Parity::None);
    assert!(
        seven_even || (cfg!(target_os = "linux") && pty_forced),
        "{os:?}"
    );
    let mut meter = Cs100a::new(link);
    meter.connect().unwrap();
    meter.set_speed(Speed::Slow).unwrap();
    let (status, value) = meter.measure_yxy().unwrap();
    assert_eq!(status, metamer_protocols::cs100a::Status::Ok00);
    assert!((value.luminance.unwrap() / 21.26 - 1.0).abs() < 0.0055);
}

#[test]
fn a_command_without_terminator_gets_er00_like_the_ls100() {
    let emu = start(Arc::new(SharedWorld::new(RED)), 1);
    let mut port = serialport::new(emu.path(), 4800)
        .timeout(Duration::from_secs(2))
        .open()
        .unwrap();
    port.write_all(b"ME").unwrap();
    let mut got = Vec::new();
    let mut buf = [0u8; 16];
    while !got.ends_with(b"\r\n") {
        let n = port.read(&mut buf).unwrap();
        got.extend_from_slice(&buf[..n]);
    }
    assert_eq!(got, b"ER00\r\n");
}

#[test]
fn the_meter_going_away_is_a_disconnect() {
    let emu = start(Arc::new(SharedWorld::new(RED)), 1);
    let mut meter = open_instrument(&format!("cs100a:{}", emu.path()), None).unwrap();
    meter.measure(&Request::default()).unwrap();
    drop(emu);
    let e = meter.measure(&Request::default()).unwrap_err().to_string();
    assert!(e.contains("disconnected during 'MES'"), "{e}");
}

#[test]
fn stimulus_trait_objects_are_accepted() {
    // A session passes its own Arc<SharedWorld> as Arc<dyn World>.
    let light: Arc<dyn World> = Arc::new(SharedWorld::new(RED));
    let mut m = open_instrument("sim:cs100a?time_scale=0.01&seed=5", Some(light)).unwrap();
    let r = m.measure(&Request::default()).unwrap();
    assert!((r.xyy[2] / 21.26 - 1.0).abs() < 0.0055, "{r:?}");
}
