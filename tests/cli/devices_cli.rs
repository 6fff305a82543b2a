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
