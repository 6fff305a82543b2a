//! Journals that a crash or a hand left in an odd state: blank lines, an empty file, a
//! header cut off while it was written.

use super::*;

#[derive(Debug, PartialEq, Serialize, Deserialize)]
struct Item {
    n: u32,
}

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
