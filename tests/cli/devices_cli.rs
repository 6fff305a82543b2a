//! `metamer devices` on a machine with no instruments (this one, and CI).

use std::process::Command;

#[test]
fn devices_lists_without_instruments() {
    let o = Command::new(env!("CARGO_BIN_EXE_metamer"))
        .arg("devices")
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(
        out.starts_with("Serial ports (a CS-100A: --instrument cs100a:PORT):\n"),
        "{out}"
    );
    assert!(out.contains("USB/HID instruments:\n"), "{out}");
    assert!(out.contains("Simulated: sim:cs100a"), "{out}");
    // Denied access always comes with its fix, never a bare "permission denied".
    assert!(!out.to_lowercase().contains("permission denied"), "{out}");
}

#[test]
fn devices_json_is_one_document() {
    let o = Command::new(env!("CARGO_BIN_EXE_metamer"))
        .args(["devices", "--json"])
        .output()
        .unwrap();
    assert!(o.status.success());
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(v["serial_ports"].is_array() && v["instruments"].is_array() && v["notes"].is_array());
    for p in v["serial_ports"].as_array().unwrap() {
        assert!(p["path"].as_str().unwrap().starts_with("/dev/"), "{p}");
        match p["access"].as_str().unwrap() {
            "ok" | "unknown" => {}
            "denied" => assert!(p["fix"].as_str().unwrap().contains("udev"), "{p}"),
            other => panic!("access {other}"),
        }
    }
}

fn run(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_metamer"))
        .args(args)
        .env_remove("METAMER_SIM_TIME_SCALE")
        .output()
        .unwrap()
}

/// An i1Pro that cannot be reached gives every command the words `devices` gives: on a
/// machine without USB (this one: no /dev/bus/usb) the reason libusb's "Other error"
/// stands for, on one with USB that no i1Pro is plugged in.
#[test]
fn every_command_explains_an_unreachable_i1pro_as_devices_does() {
    let v: serde_json::Value = serde_json::from_slice(&run(&["devices", "--json"]).stdout).unwrap();
    let expected = v["notes"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|n| n.as_str()?.strip_suffix("; no USB instruments listed"))
        .find(|n| n.starts_with("USB is not available on this machine: "))
        .map(String::from)
        .unwrap_or_else(|| {
            "no usb:0971:2000 is plugged in; `metamer devices` lists the instruments of this \
             machine"
                .into()
        });
    let dir = std::env::temp_dir().join(format!("metamer-usb-{}", std::process::id()));
    let out = |name: &str| dir.join(name).display().to_string();
    for args in [
        vec!["spot", "--instrument", "i1pro", "--unattended"],
        vec![
            "measure-box",
            "-o",
            &out("box"),
            "--spectral",
            "i1pro",
            "--spot",
            "cs100a:/dev/null",
            "--unattended",
        ],
        vec![
            "experiment",
            "-o",
            &out("experiment"),
            "--spectral",
            "i1pro",
            "--spot",
            "cs100a:/dev/null",
            "--unattended",
        ],
    ] {
        let o = run(&args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {err}");
        assert!(
            err.lines().last() == Some(format!("error: {expected}").as_str()),
            "{args:?}: {err}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// What a model can do, from the registry and its driver: the CS-100A's one emissive mode
/// without calibration and its ±0.2 % / ±0.001 (its sheet's figures, as 2σ); the i1Pro's
/// darks valid 30 min on Rev A–D and 1 h on the i1Pro 2, its white 1 h
/// (protocols/i1pro/README.md, "Calibration validity"); the i1Pro 3 not supported.
#[test]
fn describe_tells_what_a_model_can_do() {
    let text = |args: &[&str]| {
        let o = run(args);
        assert!(
            o.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        String::from_utf8_lossy(&o.stdout).into_owned()
    };
    let cs = text(&["devices", "--describe", "cs100a"]);
    assert!(cs.starts_with("Konica Minolta CS-100A (cs100a)\n"), "{cs}");
    assert!(
        cs.contains("\n    emissive (aimed): no calibration\n"),
        "{cs}"
    );
    assert!(
        cs.contains("\n    emissive: ±0.2 % in Y and ±0.001 in x, y, plus the last of the 4 significant digits of Y it sends ["),
        "{cs}"
    );
    assert!(cs.contains("option speed: "), "{cs}");
    // Its time budget at FAST: 0.1 s of measuring and 33 characters of 11 bits at 4800 baud
    // on the wire, 0.175625 s; no calibration.
    assert!(
        cs.contains(
            "\n    one reading of 100 cd/m² (lx in ambient): emissive 0.176 s (calibration 0.000 s)\n"
        ),
        "{cs}"
    );
    let i1 = text(&["devices", "--describe", "i1pro"]);
    let dark = "dark (place the instrument on its white calibration tile; valid";
    let rev_d = i1.find("a simulated i1Pro (Rev A–D)").unwrap();
    let rev_e = i1.find("a simulated i1Pro 2 (Rev E)").unwrap();
    assert!(
        i1[rev_d..rev_e].contains(&format!("emissive (placed): {dark} 30 min)\n")),
        "{i1}"
    );
    assert!(
        i1[rev_e..].contains(&format!("emissive (placed): {dark} 1 h)\n")),
        "{i1}"
    );
    assert!(
        i1[rev_e..].contains(&format!(
            "reflective (placed): {dark} 1 h), then white (place the instrument on its white \
             calibration tile; valid 1 h)\n"
        )),
        "{i1}"
    );
    assert!(
        i1.contains("refused word i1pro2: an i1Pro 2 (Rev E)"),
        "{i1}"
    );
    // The i1Pro 2 is described as what it is: the i1Pro driver's Rev E unit.
    assert_eq!(text(&["devices", "--describe", "i1pro2"]), i1);
    let three = text(&["devices", "--describe", "i1pro3"]);
    assert!(
        three.starts_with(
            "X-Rite i1Pro 3 (i1pro3)\n  not supported: it speaks a USB protocol of its own"
        ),
        "{three}"
    );
    let v: serde_json::Value =
        serde_json::from_str(&text(&["devices", "--describe", "i1pro", "--json"])).unwrap();
    assert_eq!(
        v["units"][0]["capabilities"]["modes"][0]["mode"],
        "emissive"
    );
    assert_eq!(v["repeatability"][1]["mode"], "reflective");
    // The Rev E unit's emissive dark: 204 readings of 4.896 ms and nine of 2 s.
    let times = &v["units"][1]["times"][0];
    assert_eq!(times["mode"], "emissive");
    let dark = times["calibration_s"].as_f64().unwrap();
    assert!((dark - (204.0 * 4.896e-3 + 18.0)).abs() < 1e-9, "{dark}");
    let o = run(&["devices", "--describe", "spectro"]);
    assert_eq!(o.status.code(), Some(2));
    assert_eq!(
        String::from_utf8_lossy(&o.stderr),
        "error: --describe: no instrument model is named 'spectro' (known: cs100a, i1pro, \
         i1pro3, colormunki, i1d3)\n"
    );
}

/// `i1pro2` is answered with how to name an i1Pro 2, `i1pro3` with "not supported" and
/// why, as usage errors before anything is opened.
#[test]
fn the_i1pro_2_and_3_are_answered_by_name() {
    let o = run(&["spot", "--instrument", "i1pro2"]);
    assert_eq!(o.status.code(), Some(2));
    assert_eq!(
        String::from_utf8_lossy(&o.stderr),
        "error: instrument 'i1pro2': an i1Pro 2 (Rev E) is the X-Rite i1Pro / i1Pro 2: name it \
         i1pro[:SERIAL], and simulate one with sim:i1pro?rev=e\n"
    );
    let o = run(&["spot", "--instrument", "i1pro3"]);
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.starts_with("error: instrument 'i1pro3': the X-Rite i1Pro 3 is not supported: it speaks a USB protocol of its own"),
        "{err}"
    );
    let dir = std::env::temp_dir().join(format!("metamer-i1pro3-{}", std::process::id()));
    let o = run(&[
        "measure-box",
        "-o",
        &dir.display().to_string(),
        "--spectral",
        "sim:i1pro3",
        "--spot",
        "sim:cs100a",
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        String::from_utf8_lossy(&o.stderr)
            .starts_with("error: instrument 'sim:i1pro3': the X-Rite i1Pro 3 is not supported"),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let _ = std::fs::remove_dir_all(&dir);
}
