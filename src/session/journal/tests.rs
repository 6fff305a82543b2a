//! The journal's own tests: a line that lost its newline, refusals naming what differs,
//! and readings that must agree with their spectra.

use super::*;
use metamer_drivers::Reading;

#[derive(Debug, PartialEq, Serialize, Deserialize)]
struct Item {
    n: u32,
}

impl JournalEntry for Item {}

fn header(options: &[(&str, &str)], fingerprint: &str) -> Header<String> {
    Header {
        format: JOURNAL_FORMAT.into(),
        version: JOURNAL_VERSION,
        kind: "test".into(),
        fingerprint: fingerprint.into(),
        options: options
            .iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect(),
        steps: 3,
        started_s: 1.0,
        data: "rig".into(),
    }
}

fn temp(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("metamer-journal-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir.join("j.jsonl")
}

fn append_raw(path: &Path, bytes: &[u8]) {
    OpenOptions::new()
        .append(true)
        .open(path)
        .unwrap()
        .write_all(bytes)
        .unwrap();
}

#[test]
fn a_line_that_lost_only_its_newline_is_kept() {
    let path = temp("newline");
    let h = header(&[("a", "1")], "f1");
    let mut j = Journal::<String, Item>::create(&path, &h).unwrap();
    j.append(&Item { n: 1 }).unwrap();
    drop(j);
    append_raw(&path, br#"{"type":"entry","n":2}"#);
    let (mut j, rec) = Journal::<String, Item>::resume(&path, &h).unwrap();
    assert_eq!(rec.torn_bytes, 0);
    assert_eq!(rec.entries, vec![(2, Item { n: 1 }), (3, Item { n: 2 })]);
    assert_eq!(rec.header, h);
    j.append(&Item { n: 3 }).unwrap();
    drop(j);
    let (_, rec) = Journal::<String, Item>::resume(&path, &h).unwrap();
    assert_eq!(rec.entries.len(), 3);
    assert!(!torn_path(&path).exists());
    std::fs::remove_dir_all(path.parent().unwrap()).unwrap();
}

#[test]
fn the_differing_option_is_named_and_other_damage_refused() {
    let path = temp("refuse");
    let h = header(&[("a", "1"), ("b", "2")], "f1");
    drop(Journal::<String, Item>::create(&path, &h).unwrap());
    let before = std::fs::read(&path).unwrap();
    let resume = |h: &Header<String>| {
        Journal::<String, Item>::resume(&path, h)
            .err()
            .unwrap()
            .to_string()
    };
    // An option missing from one side is named too.
    let e = resume(&header(&[("a", "1"), ("b", "2"), ("c", "3")], "f2"));
    assert!(
        e.contains("its option c is (not set), this one's is 3"),
        "{e}"
    );
    let e = resume(&header(&[("a", "1"), ("b", "5")], "f2"));
    assert!(e.contains("its option b is 2, this one's is 5"), "{e}");
    let e = resume(&header(&[("a", "1"), ("b", "2")], "f2"));
    assert!(
        e.contains("every option is the same but its steps differ"),
        "{e}"
    );
    let mut other_kind = h.clone();
    other_kind.kind = "measure-box".into();
    assert!(resume(&other_kind).contains("written by a test session, not a measure-box"));
    assert_eq!(std::fs::read(&path).unwrap(), before);
    // A second header, and a journal of another format.
    append_raw(&path, &before);
    let e = resume(&h);
    assert!(e.contains("j.jsonl, line 2: a second header line"), "{e}");
    std::fs::write(&path, b"{\"format\":\"other\",\"version\":1}\n").unwrap();
    let e = resume(&h);
    assert!(
        e.contains("line 1: format \"other\" version 1 is not metamer-session-journal"),
        "{e}"
    );
    std::fs::remove_dir_all(path.parent().unwrap()).unwrap();
}

/// A reading's XYZ must follow from its spectrum: as the instrument computed it, it
/// does (to the rounding of a JSON round trip); an edit of either is a problem; a
/// reading without a spectrum is checked only for being a number.
#[test]
fn a_reading_must_agree_with_its_spectrum() {
    use metamer_color::{Quantity, Spectrum};
    let values: Vec<f64> = (0..36).map(|i| 0.01 + 0.0002 * f64::from(i)).collect();
    let spectrum = Spectrum::from_grid(380.0, 10.0, values)
        .unwrap()
        .with_quantity(Quantity::Radiance);
    let xyz = Reading::xyz_of_spectrum(&spectrum).unwrap();
    let reading = Reading {
        spectrum: Some(spectrum),
        xyz,
        ..Reading::from_yxy(1.0, 0.3, 0.3, "i1pro")
    };
    let back: Reading = serde_json::from_str(&serde_json::to_string(&reading).unwrap()).unwrap();
    assert_eq!(reading_problem(&back), None);
    let mut edited = back.clone();
    edited.xyz[1] *= 1.01;
    let p = reading_problem(&edited).unwrap();
    assert!(p.contains("do not follow from its spectrum"), "{p}");
    let mut values = back.spectrum.as_ref().unwrap().values().to_vec();
    values[18] = -1e6;
    let mut edited = back.clone();
    edited.spectrum = Some(
        Spectrum::from_grid(380.0, 10.0, values)
            .unwrap()
            .with_quantity(Quantity::Radiance),
    );
    assert!(reading_problem(&edited).is_some());
    let colorimeter = Reading::from_yxy(50.0, 0.31, 0.33, "cs100a");
    assert_eq!(reading_problem(&colorimeter), None);
    let mut huge = colorimeter;
    huge.xyz[0] = 1e308;
    assert!(reading_problem(&huge)
        .unwrap()
        .contains("not a measurement"));
}
