//! The spec grammar against the registry: what opens, what is refused and with which
//! words, and what counts as physical.

use super::*;
use crate::instrument::{MeasureMode, Request};
use crate::open::OpenOptions;
use crate::registry::{self, ModelEntry};
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
    for spec in ["nothing", "cs100a:", "replay:"] {
        let e = open_instrument(spec, None).err().unwrap();
        assert!(
            e.to_string().contains("expected cs100a:PORT"),
            "{spec}: {e}"
        );
    }
    // A model the registry knows but does not drive says so.
    let e = open_instrument("sim:i1d3", None).err().unwrap().to_string();
    assert!(
        e.starts_with(
            "instrument 'sim:i1d3': the X-Rite i1Display Pro is not supported: metamer has no \
             codec for its HID protocol; known: cs100a:PORT"
        ),
        "{e}"
    );
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
const FAKE: &[ModelEntry] = &[ModelEntry {
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
    described_by: &[],
    modes: &[],
    repeatability: &[],
    time_budget: None,
    other_names: &[],
    unsupported: None,
}];

#[test]
fn a_row_is_opened_by_any_of_its_prefixes_with_or_without_its_optional_address() {
    let opened = |spec: &str| {
        Spec::new(spec)
            .open_in(FAKE, &OpenOptions::default())
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

#[test]
fn a_spec_keeps_its_text_and_reads_its_form() {
    let s = Spec::new("sim:cs100a?");
    assert_eq!(s.as_str(), "sim:cs100a?");
    assert_eq!(serde_json::to_string(&s).unwrap(), "\"sim:cs100a?\"");
    let back: Spec = serde_json::from_str("\"sim:cs100a?\"").unwrap();
    assert_eq!(back, s);
    assert_eq!(
        s.kind(),
        &SpecForm::Simulated {
            model: "cs100a".into(),
            options: String::new()
        }
    );
    let r = Spec::new("replay:a:b.jsonl");
    assert_eq!(r.replay_file(), Some(std::path::Path::new("a:b.jsonl")));
    assert!(!r.is_simulated() && !r.is_physical());
    for text in ["sim", "replay", "replay:", "cs100a", "i1pro:123"] {
        let s = Spec::new(text);
        assert!(!s.is_simulated() && s.replay_file().is_none(), "{text}");
    }
    assert_eq!(
        Spec::new("cs100a:COM3").kind(),
        &SpecForm::Device {
            prefix: "cs100a".into(),
            address: "COM3".into()
        }
    );
}

#[test]
fn options_and_seeds_are_appended_as_the_text_was_written_by_hand() {
    // The texts the lab and the patch-budget study wrote before there was a builder: the
    // experiment hashes them, so the builder must give the same bytes.
    let lab = Spec::simulated("i1pro").with_option("time_scale", 0.01);
    assert_eq!(lab.as_str(), "sim:i1pro?time_scale=0.01");
    let budget = Spec::simulated("cs100a")
        .with_option("time_scale", 0.0)
        .with_option("seed", 7);
    assert_eq!(budget.as_str(), "sim:cs100a?time_scale=0&seed=7");
    assert_eq!(
        Spec::new("sim:cs100a").with_seed_unless_set(3).as_str(),
        "sim:cs100a?seed=3"
    );
    assert_eq!(
        Spec::new("sim:cs100a?time_scale=0")
            .with_seed_unless_set(3)
            .as_str(),
        "sim:cs100a?time_scale=0&seed=3"
    );
    assert_eq!(
        Spec::new("sim:cs100a?seed=9")
            .with_seed_unless_set(3)
            .as_str(),
        "sim:cs100a?seed=9"
    );
    // Only a simulation has a seed.
    for text in ["cs100a:/dev/ttyUSB0", "replay:x.jsonl", "i1pro"] {
        assert_eq!(Spec::new(text).with_seed_unless_set(3).as_str(), text);
    }
    assert_eq!(
        Spec::replay(std::path::Path::new("/tmp/x.jsonl")).as_str(),
        "replay:/tmp/x.jsonl"
    );
}

/// `i1pro2` is answered with how to name an i1Pro 2 (the i1Pro driver reads Rev E units,
/// protocols/i1pro/README.md), `i1pro3` with "not supported" and why, in every form and by
/// the check as by opening.
#[test]
fn the_i1pro_2_is_named_as_an_i1pro_and_the_i1pro_3_is_not_supported() {
    let i1pro2 = "an i1Pro 2 (Rev E) is the X-Rite i1Pro / i1Pro 2: name it i1pro[:SERIAL], \
                  and simulate one with sim:i1pro?rev=e";
    for spec in ["i1pro2", "i1pro2:1234", "sim:i1pro2?time_scale=0"] {
        let e = check_spec(spec).unwrap_err();
        assert!(e.is_spec(), "{e}");
        assert_eq!(e.to_string(), format!("instrument '{spec}': {i1pro2}"));
        assert_eq!(
            open_instrument(spec, None).err().unwrap().to_string(),
            e.to_string()
        );
    }
    for spec in ["i1pro3", "sim:i1pro3"] {
        let e = check_spec(spec).unwrap_err().to_string();
        assert!(
            e.starts_with(&format!(
                "instrument '{spec}': the X-Rite i1Pro 3 is not supported: it speaks a USB \
                 protocol of its own"
            )),
            "{e}"
        );
        assert!(
            e.ends_with(
                "; known: cs100a:PORT, i1pro[:SERIAL], replay:FILE.jsonl, sim:cs100a or sim:i1pro"
            ),
            "{e}"
        );
    }
    // Any other word stays an unknown spec.
    assert!(check_spec("i1pro4")
        .unwrap_err()
        .to_string()
        .starts_with("unknown instrument 'i1pro4': expected cs100a:PORT"));
}

#[test]
fn a_model_is_found_by_its_name_another_word_or_a_spec() {
    let name = |n: &str| model_named(n).map(|m| m.name);
    for (given, model) in [
        ("cs100a", Some("cs100a")),
        ("CS-100A", Some("cs100a")),
        (" i1Pro ", Some("i1pro")),
        ("i1pro2", Some("i1pro")),
        ("sim:i1pro?seed=2", Some("i1pro")),
        ("cs100a:/dev/ttyUSB0", Some("cs100a")),
        ("i1d3", Some("i1d3")),
        ("replay:cs100a.jsonl", None),
        ("spectralon", None),
        ("", None),
    ] {
        assert_eq!(name(given), model, "{given:?}");
    }
}
