//! Journals that a crash or a hand left in an odd state: blank lines, an empty file, a
//! header cut off while it was written.

use super::*;

#[derive(Debug, PartialEq, Serialize, Deserialize)]
struct Item {
    n: u32,
}

impl JournalEntry for Item {}

fn header() -> Header<String> {
    Header {
        format: JOURNAL_FORMAT.into(),
        version: JOURNAL_VERSION,
        kind: "test".into(),
        fingerprint: "f".into(),
        options: BTreeMap::new(),
        steps: 3,
        started_s: 1.0,
        data: "rig".into(),
    }
}

fn temp(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("metamer-recover-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir.join("j.jsonl")
}

#[test]
fn blank_lines_are_skipped_and_line_numbers_kept() {
    let path = temp("blank");
    let h = header();
    let mut j = Journal::<String, Item>::create(&path, &h).unwrap();
    j.append(&Item { n: 1 }).unwrap();
    drop(j);
    // A blank line, one of spaces, then an entry, as an editor or a tool may leave them.
    let mut f = OpenOptions::new().append(true).open(&path).unwrap();
    f.write_all(b"\n   \n{\"type\":\"entry\",\"n\":2}\n")
        .unwrap();
    drop(f);
    let (_, rec) = Journal::<String, Item>::resume(&path, &h).unwrap();
    // Line 1 header, 2 entry, 3 and 4 blank, 5 entry.
    assert_eq!(rec.entries, vec![(2, Item { n: 1 }), (5, Item { n: 2 })]);
}

#[test]
fn an_empty_journal_and_a_torn_header_hold_no_session() {
    let path = temp("broken");
    let full = serde_json::to_string(&LineRef::<String, Item>::Header(&header())).unwrap();
    let cases: [(&[u8], &str); 3] = [
        (b"", "it is empty"),
        (b"\n \n", "it holds only blank lines"),
        (
            &full.as_bytes()[..20],
            "its header line was cut off after 20 bytes",
        ),
    ];
    for (bytes, what) in cases {
        std::fs::write(&path, bytes).unwrap();
        let e = Journal::<String, Item>::resume(&path, &header())
            .err()
            .expect("nothing to resume");
        match &e {
            JournalError::Broken { what: w, .. } => assert_eq!(w, what),
            other => panic!("{other}"),
        }
        assert!(e.to_string().contains("resuming sets it aside"), "{e}");
        // Starting anew over it is refused with the same reason, and the file kept.
        match Journal::<String, Item>::create(&path, &header()) {
            Err(JournalError::Broken { what: w, .. }) => assert_eq!(w, what),
            Err(other) => panic!("{other}"),
            Ok(_) => panic!("created over an existing file"),
        }
        assert!(matches!(
            refuse_existing(&path),
            Err(JournalError::Broken { .. })
        ));
        assert_eq!(std::fs::read(&path).unwrap(), bytes);
    }
    // A whole header line is a session, even with nothing after it.
    std::fs::write(&path, format!("{full}\n")).unwrap();
    assert!(Journal::<String, Item>::resume(&path, &header()).is_ok());
    assert!(matches!(
        refuse_existing(&path),
        Err(JournalError::Exists { entries: 0, .. })
    ));
}

#[test]
fn setting_aside_numbers_the_copies_and_deletes_nothing() {
    let path = temp("aside");
    let dir = path.parent().unwrap().to_path_buf();
    std::fs::write(&path, "first").unwrap();
    assert_eq!(set_aside(&path).unwrap(), dir.join("j.jsonl.broken-1"));
    std::fs::write(&path, "second").unwrap();
    assert_eq!(set_aside(&path).unwrap(), dir.join("j.jsonl.broken-2"));
    assert!(!path.exists());
    assert_eq!(
        std::fs::read_to_string(dir.join("j.jsonl.broken-1")).unwrap(),
        "first"
    );
    assert_eq!(
        std::fs::read_to_string(dir.join("j.jsonl.broken-2")).unwrap(),
        "second"
    );
}

/// An editor that saved the journal with a byte-order mark: the header still reads, for a
/// journal of several lines and for one whose only line lost its newline.
#[test]
fn a_byte_order_mark_before_the_header_is_skipped() {
    let h = header();
    for with_entry in [true, false] {
        let path = temp(&format!("bom-{with_entry}"));
        let mut j = Journal::<String, Item>::create(&path, &h).unwrap();
        if with_entry {
            j.append(&Item { n: 7 }).unwrap();
        }
        drop(j);
        let mut bytes = "\u{feff}".as_bytes().to_vec();
        let written = std::fs::read(&path).unwrap();
        bytes.extend_from_slice(if with_entry {
            &written
        } else {
            written.strip_suffix(b"\n").unwrap()
        });
        std::fs::write(&path, &bytes).unwrap();
        let (_, r) = Journal::<String, Item>::resume(&path, &h).unwrap();
        assert_eq!(r.header, h);
        let expected = if with_entry {
            vec![(2, Item { n: 7 })]
        } else {
            vec![]
        };
        assert_eq!(r.entries, expected);
        assert_eq!(r.torn_bytes, 0);
    }
}

/// A megabyte in a field is cut to its first 80 characters in every message that quotes it.
#[test]
fn a_megabyte_field_is_not_echoed_whole() {
    let big = "x".repeat(1 << 20);
    let h = header();
    // A format name of a megabyte.
    let path = temp("big-format");
    let line = serde_json::json!({"type": "header", "format": big, "version": 1});
    std::fs::write(&path, format!("{line}\n")).unwrap();
    let e = Journal::<String, Item>::resume(&path, &h)
        .err()
        .unwrap()
        .to_string();
    assert!(e.len() < 600, "{} bytes: {}", e.len(), &e[..600]);
    assert!(e.contains("line 1: format \"xxx"), "{e}");
    assert!(
        e.ends_with("is not metamer-session-journal version 2"),
        "{e}"
    );
    // An option value of a megabyte, logged by the journal's session.
    let path = temp("big-option");
    let mut logged = header();
    logged.fingerprint = "other".into();
    logged.options.insert("seed".into(), big.clone());
    drop(Journal::<String, Item>::create(&path, &logged).unwrap());
    let mut now = header();
    now.options.insert("seed".into(), "1".into());
    let e = Journal::<String, Item>::resume(&path, &now)
        .err()
        .unwrap()
        .to_string();
    assert!(e.len() < 600, "{} bytes", e.len());
    assert!(e.contains("its option seed is xxx"), "{e}");
    assert!(
        e.contains("(1048576 characters in all), this one's is 1"),
        "{e}"
    );
    // An entry whose field is a megabyte string where a number belongs.
    let path = temp("big-entry");
    drop(Journal::<String, Item>::create(&path, &h).unwrap());
    append_line(&path, &format!("{{\"type\":\"entry\",\"n\":\"{big}\"}}\n"));
    let e = Journal::<String, Item>::resume(&path, &h)
        .err()
        .unwrap()
        .to_string();
    assert!(e.len() < 600, "{} bytes", e.len());
    assert!(e.contains("line 2: not an entry or calibration"), "{e}");
}

fn append_line(path: &Path, line: &str) {
    OpenOptions::new()
        .append(true)
        .open(path)
        .unwrap()
        .write_all(line.as_bytes())
        .unwrap();
}

/// The lock: while one journal is open (created or resumed), opening it again is refused
/// as in use, by resume and by a new session alike; closing it lets the next one in.
#[test]
fn a_journal_open_elsewhere_is_in_use() {
    let path = temp("lock");
    let h = header();
    let in_use = |r: Result<(), JournalError>| matches!(r, Err(JournalError::InUse { .. }));
    let first = Journal::<String, Item>::create(&path, &h).unwrap();
    assert!(in_use(Journal::<String, Item>::resume(&path, &h).map(drop)));
    assert!(in_use(refuse_existing(&path)));
    drop(first);
    let (second, _) = Journal::<String, Item>::resume(&path, &h).unwrap();
    let e = Journal::<String, Item>::resume(&path, &h).err().unwrap();
    assert!(
        e.to_string().contains("is in use by another session"),
        "{e}"
    );
    drop(second);
    assert!(Journal::<String, Item>::resume(&path, &h).is_ok());
}

/// Two sessions that wrote one journal: the first entry of each step is kept in its
/// place, the later ones go to the side file byte for byte, and the journal goes on.
#[test]
fn later_entries_of_a_step_are_set_aside_and_the_first_kept() {
    use serde_json::{json, Value};
    let path = temp("twice");
    let h = header();
    drop(Journal::<String, Value>::create(&path, &h).unwrap());
    let line = |i: u32, v: &str| format!("{{\"type\":\"entry\",\"index\":{i},\"v\":\"{v}\"}}");
    let later = [line(1, "c"), line(0, "d")];
    append_line(
        &path,
        &format!(
            "{}\n{}\n{}\n{}\n{}",
            line(0, "a"),
            line(1, "b"),
            later[0],
            later[1],
            line(2, "e")
        ),
    );
    let (mut j, r) = Journal::<String, Value>::resume(&path, &h).unwrap();
    assert_eq!(r.duplicates, vec![(4, 1), (5, 0)]);
    assert_eq!(r.duplicate_bytes, later[0].len() + later[1].len() + 2);
    let kept: Vec<&str> = r
        .entries
        .iter()
        .map(|(_, e)| e["v"].as_str().unwrap())
        .collect();
    assert_eq!(kept, ["a", "b", "e"]);
    assert_eq!(
        std::fs::read_to_string(duplicates_path(&path)).unwrap(),
        later.join("\n") + "\n"
    );
    j.append(&json!({"index": 3, "v": "f"})).unwrap();
    drop(j);
    let (_, r) = Journal::<String, Value>::resume(&path, &h).unwrap();
    assert!(r.duplicates.is_empty());
    let kept: Vec<&str> = r
        .entries
        .iter()
        .map(|(_, e)| e["v"].as_str().unwrap())
        .collect();
    assert_eq!(kept, ["a", "b", "e", "f"]);
}
