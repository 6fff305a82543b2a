//! `metamer lab` is the experiment on the simulated rig: the same stage directories and
//! files, a second call that re-uses every stage, the box's light part of the box stage's
//! inputs, and which ColorChecker colours the `ips-lcd` can show under each light checked
//! against the display's primaries computed here.

use std::path::Path;
use std::process::Output;

use metamer::experiment::readings::read_readings;
use metamer::experiment::validate::ValidationResult;
use metamer::rig::{Preset, VirtualPanel};
use nalgebra::{Matrix3, Vector3};

use crate::support::{json, metamer_unscaled, unused_dir};

/// A fast lab: ΔE 0.5 renders, a 256² image, one reading per box target and per display
/// patch.
fn quick_lab(dir: &Path, extra: &[&str]) -> Output {
    let mut args = vec![
        "lab",
        "-o",
        dir.to_str().unwrap(),
        "--target-de",
        "0.5",
        "--repeats",
        "1",
        "--box-repeats",
        "1",
        "--image-size",
        "256",
    ];
    args.extend_from_slice(extra);
    let o = metamer_unscaled(&args);
    assert!(
        o.status.success(),
        "{}\n{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    o
}

/// Stage name → "ran" or "re-used", from the stage table.
fn stages(o: &Output) -> Vec<(String, String)> {
    String::from_utf8_lossy(&o.stdout)
        .lines()
        .filter_map(|l| {
            let mut f = l.split_whitespace();
            let (s, how) = (f.next()?, f.next()?);
            matches!(how, "ran" | "re-used").then(|| (s.to_string(), how.to_string()))
        })
        .collect()
}

const STAGES: [&str; 6] = [
    "box",
    "simulation",
    "display",
    "reproduction",
    "display-spots",
    "validation",
];

/// Each patch of the box's measured spot readings in `dir`, with the least of its linear
/// drives on the `ips-lcd`'s primaries: the three full-on channels above black, from the
/// panel itself, as paper Eq. 9 without the tone curves. All ≥ 0: inside the primaries'
/// triangle; the scale of the white does not change the sign.
fn least_linear_drive(dir: &Path) -> Vec<(usize, f64)> {
    let panel = VirtualPanel::preset(Preset::IpsLcd);
    let black = Vector3::from(panel.xyz([0; 3]).to_array());
    let column = |rgb: [u8; 3]| Vector3::from(panel.xyz(rgb).to_array()) - black;
    let inv = Matrix3::from_columns(&[
        column([255, 0, 0]),
        column([0, 255, 0]),
        column([0, 0, 255]),
    ])
    .try_inverse()
    .unwrap();
    read_readings(&dir.join("box/spots.csv"))
        .unwrap()
        .patches
        .iter()
        .map(|(&patch, p)| {
            let lin = inv * Vector3::from(p.xyz.to_array());
            (patch, lin.min() / lin.max())
        })
        .collect()
}

/// The simulated patches (the colours the display is asked to show) that the `ips-lcd`
/// panel, at the white luminance in `display/display.json`, has no drive values 0–1 for.
fn unreachable_on_the_panel(dir: &Path) -> Vec<usize> {
    let white = json(&dir.join("display/display.json"))["virtual_white_cd_m2"]
        .as_f64()
        .unwrap();
    let panel = VirtualPanel::preset(Preset::IpsLcd).with_white_luminance(white);
    read_readings(&dir.join("simulation/spots.csv"))
        .unwrap()
        .patches
        .iter()
        .filter(|(_, p)| panel.drive_for(p.xyz).is_none())
        .map(|(&patch, _)| patch)
        .collect()
}

/// Patches whose least linear drive is below `-depth` of their largest.
fn outside(reach: &[(usize, f64)], depth: f64) -> Vec<usize> {
    reach
        .iter()
        .filter(|(_, l)| *l < -depth)
        .map(|(p, _)| *p)
        .collect()
}

#[test]
fn the_lab_is_the_experiment_on_the_simulated_rig() {
    let dir = unused_dir("pipeline");
    let first = quick_lab(&dir, &[]);
    let said = String::from_utf8_lossy(&first.stdout);
    assert_eq!(
        stages(&first),
        STAGES.map(|s| (s.to_string(), "ran".to_string())),
        "{said}"
    );
    // The experiment's files, stage by stage.
    for f in [
        "box/scene.json",
        "box/spots.csv",
        "box/stage.json",
        "simulation/stage.json",
        "display/profile.json",
        "display/display.json",
        "reproduction/stage.json",
        "display-spots/stage.json",
        "validation/comparisons.json",
        "validation/report.html",
        "lab.json",
    ] {
        assert!(dir.join(f).exists(), "{f} missing");
    }
    // The run ends by saying where the report is.
    let last = said.lines().last().unwrap_or_default();
    assert!(
        last.starts_with("report: ") && last.contains("validation/report.html"),
        "{said}"
    );
    // lab.json is the validation's result in short.
    let lab = json(&dir.join("lab.json"));
    let v: ValidationResult =
        serde_json::from_value(json(&dir.join("validation/comparisons.json"))).unwrap();
    assert_eq!(lab["options"]["scenario"], "display-white");
    assert_eq!(lab["options"]["box_repeats"], 1);
    assert_eq!(
        lab["out_of_gamut_patches"],
        serde_json::to_value(&v.out_of_gamut_patches).unwrap()
    );
    let report = std::fs::read_to_string(dir.join("validation/report.html")).unwrap();
    for (key, a) in [
        ("display_vs_box", &v.display_vs_box),
        ("simulation_vs_box", &v.simulation_vs_box),
        ("display_vs_simulation", &v.display_vs_simulation),
    ] {
        // One verdict everywhere: lab.json, comparisons.json and the terminal count the
        // same patches below, above and undecided at 95 %, and the point-estimate count
        // only under its name.
        let counts = &lab[key]["jnd"];
        assert_eq!(
            [&counts["below"], &counts["above"], &counts["undecided"]],
            [a.jnd.below, a.jnd.above, a.jnd.undecided]
                .map(serde_json::Value::from)
                .each_ref(),
            "{key}"
        );
        assert_eq!(lab[key]["below_jnd_point"], a.below_jnd_point, "{key}");
        assert_eq!(
            lab[key]["max_de76"]["value"].as_f64(),
            Some(a.max_de76.value)
        );
        assert!(said.contains(&a.summary()), "{key}: {said}");
        assert!(
            a.summary().contains(&format!(
                "{} of 24 patches below the JND (ΔE*ab 2.3) at 95 % confidence, {} above, {} undecided ({} below by point estimate)",
                a.jnd.below, a.jnd.above, a.jnd.undecided, a.below_jnd_point
            )),
            "{}",
            a.summary()
        );
        // No interval excludes its estimate.
        for p in &a.patches {
            for (what, value, i) in [
                ("ΔE*ab", p.de76, p.de76_interval),
                ("ΔE00", p.de00, p.de00_interval),
            ] {
                assert!(
                    i.lo <= value && value <= i.hi && i.lo >= 0.0,
                    "{key} patch {} {what} {value} outside {i:?}",
                    p.patch
                );
            }
        }
        for (what, s) in [
            ("mean ΔE*ab", a.mean_de76),
            ("max ΔE*ab", a.max_de76),
            ("mean ΔE00", a.mean_de00),
            ("max ΔE00", a.max_de00),
        ] {
            let i = s
                .interval
                .unwrap_or_else(|| panic!("{key} {what}: no interval"));
            assert!(i.lo <= s.value && s.value <= i.hi, "{key} {what} {s:?}");
        }
    }
    // The report's headline counts as the rest do.
    let b = &v.display_vs_box;
    assert!(
        report.contains(&format!(
            "display vs box: {} of 24 patches are below the JND (ΔE*ab 2.3) with 95 % confidence, {} above and {} undecided ({} below by point estimate)",
            b.jnd.below, b.jnd.above, b.jnd.undecided, b.below_jnd_point
        )),
        "the report's verdict"
    );
    // The box and the simulation differ by the instruments' noise and the render's
    // ±0.5 only: all 24 below the JND by point estimate, none above.
    assert_eq!(v.simulation_vs_box.below_jnd_point, 24);
    assert_eq!(v.simulation_vs_box.jnd.above, 0);
    // Single readings carry the meter's stated repeatability, the simulation its
    // render's uncertainty: no patch's interval is a point.
    for p in &v.display_vs_box.patches {
        assert!(p.de76_interval.hi > p.de76_interval.lo, "patch {}", p.patch);
    }

    // Lit by the display's white, no measured colour lies clearly outside the display's
    // primaries: at most 1 % of its largest drive on the wrong side of an edge (the yellow
    // sits on one, see src/measure_box/simulated_box.rs).
    let reach = least_linear_drive(&dir);
    assert_eq!(reach.len(), 24);
    assert!(outside(&reach, 0.01).is_empty(), "{reach:?}");
    // What the reproduction flags (through the fitted display model) is what the panel
    // itself, set to the white the display stage chose, cannot emit: its exact inverse,
    // with crosstalk, drifting primaries and tone curves.
    let unreachable = unreachable_on_the_panel(&dir);
    assert_eq!(v.out_of_gamut_patches, unreachable, "{reach:?}");
    assert!(unreachable.len() <= 2, "{unreachable:?}");
    // Every other colour comes back from the display within the JND.
    for p in &v.display_vs_box.patches {
        if !unreachable.contains(&p.patch) {
            assert!(p.de76 < 2.3, "patch {}: ΔE*ab {}", p.patch, p.de76);
        }
    }

    // A second call re-uses every stage, and lab.json keeps each stage's recorded time.
    let log = std::fs::read(dir.join("display/log.jsonl")).unwrap();
    let second = quick_lab(&dir, &[]);
    assert_eq!(
        stages(&second),
        STAGES.map(|s| (s.to_string(), "re-used".to_string()))
    );
    assert_eq!(std::fs::read(dir.join("display/log.jsonl")).unwrap(), log);
    let again = json(&dir.join("lab.json"));
    assert!(again["seconds"].as_f64().unwrap() < 5.0);
    assert_eq!(
        again["stages"],
        serde_json::Value::from(
            lab["stages"]
                .as_array()
                .unwrap()
                .iter()
                .map(|s| {
                    let mut s = s.clone();
                    s["reused"] = true.into();
                    s
                })
                .collect::<Vec<_>>()
        )
    );
    assert!(again["stages"][0]["seconds"].as_f64().unwrap() > 0.0);
    assert_eq!(again["options"]["box_repeats"], 1);
    assert_eq!(again["display_vs_box"]["jnd"], lab["display_vs_box"]["jnd"]);

    // Another light is another box: the box stage runs again (its measurements kept
    // aside), and with it every stage after it.
    let led = quick_lab(&dir, &["--scenario", "led-rgb1"]);
    assert_eq!(
        stages(&led),
        STAGES.map(|s| (s.to_string(), "ran".to_string()))
    );
    assert!(dir.join("box.old-1/scene.json").exists());
    let v: ValidationResult =
        serde_json::from_value(json(&dir.join("validation/comparisons.json"))).unwrap();
    // Under the warm LED the saturated oranges, yellows and reds lie clearly outside the
    // primaries, and the reproduction flags each of them.
    let reach = least_linear_drive(&dir);
    let far = outside(&reach, 0.01);
    assert!(far.len() >= 4, "{reach:?}");
    for p in [12, 15, 16] {
        assert!(far.contains(&p), "{reach:?}");
    }
    for p in &far {
        assert!(
            v.out_of_gamut_patches.contains(p),
            "{p}: {:?}",
            v.out_of_gamut_patches
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn bad_options_are_usage_errors() {
    let never = "/nonexistent/never-written";
    for (args, needle) in [
        (&["--display", "oled"][..], "unknown display 'oled'"),
        (&["--display", "window:0"][..], "name it virtual:PRESET"),
        (&["--model", "magic"][..], "magic"),
        (&["--gamut", "hue"][..], "unknown gamut mapping"),
        (&["--target-de", "0"][..], "--target-de"),
        (&["--repeats", "0"][..], "--repeats"),
        (&["--box-repeats", "0"][..], "--box-repeats"),
        (&["--time-scale=-1"][..], "--time-scale"),
        (
            &["--scenario", "sodium"][..],
            "unknown box light 'sodium' (known: display-white, led-rgb1)",
        ),
        (&["--scene", "x.json"][..], "--scene"),
    ] {
        let out = metamer_unscaled(&[&["lab", "-o", never][..], args].concat());
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(needle), "{args:?}: {err}");
    }
    assert!(!Path::new(never).exists());
}

/// The light belongs to the simulated box: with real instruments it is refused before
/// anything is opened or written.
#[test]
fn a_light_is_refused_for_the_real_box() {
    let never = "/nonexistent/never-written";
    for command in ["experiment", "measure-box"] {
        let out = metamer_unscaled(&[
            command,
            "-o",
            never,
            "--spectral",
            "i1pro",
            "--spot",
            "cs100a:/dev/null",
            "--scenario",
            "led-rgb1",
        ]);
        assert_eq!(out.status.code(), Some(2), "{command}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            err.contains("--scenario sets the light of the simulated box"),
            "{command}: {err}"
        );
    }
    assert!(!Path::new(never).exists());
}
