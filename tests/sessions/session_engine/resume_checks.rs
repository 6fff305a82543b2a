//! What a resume checks besides the plan: every setting of every instrument (a reading
//! taken at another speed, by another unit or by a simulation with another seed is not
//! comparable), and what it does with a journal that holds no session.

use std::time::Duration;

use metamer::session::{InstrumentRecord, RunEnd, RunOptions, Session, SessionError};

use super::{instruments, open, plan, run, temp, Target, TILES};

/// A change to the record of an instrument.
type Change = dyn Fn(&mut InstrumentRecord);

#[test]
fn another_setting_or_unit_of_the_same_model_is_refused_by_name() {
    let path = temp("settings");
    let first = run(
        open(&path, plan(TILES, Duration::ZERO), false),
        vec![],
        &RunOptions {
            stop_after: Some(2),
            ..RunOptions::default()
        },
    );
    assert_eq!(first.end, RunEnd::Stopped { missing: 6 });
    drop(first);
    let before = std::fs::read(&path).unwrap();
    let reopen = |changed: &Change| {
        let mut now = instruments();
        changed(now.get_mut("spot").unwrap());
        Session::<String, Target>::open(
            &path,
            plan(TILES, Duration::ZERO),
            "a test rig".into(),
            now,
            true,
        )
        .err()
        .expect("refused")
    };
    // An option value (the CS-100A's speed, say), a simulation's seed, a new option.
    let cases: [(&Change, &str); 3] = [
        (
            &|r| {
                r.options.insert("speed".into(), "slow".into());
            },
            "whose speed was (not set); this session's is slow",
        ),
        (
            &|r| {
                r.options.insert("sim_seed".into(), "2".into());
            },
            "whose sim_seed was (not set); this session's is 2",
        ),
        (
            &|r| r.info.serial = Some("B-2".into()),
            "whose serial number was",
        ),
    ];
    for (change, says) in cases {
        let e = reopen(change);
        assert!(
            matches!(e, SessionError::InstrumentSettingDiffers(_)),
            "{e}"
        );
        let text = e.to_string();
        assert!(
            text.contains("with spot instrument fake-spot") && text.contains(says),
            "{text}"
        );
        assert_eq!(std::fs::read(&path).unwrap(), before);
    }
    // The same settings resume.
    let s = open(&path, plan(TILES, Duration::ZERO), true);
    assert_eq!(s.recovered, 2);
    std::fs::remove_dir_all(path.parent().unwrap()).unwrap();
}

#[test]
fn a_journal_that_holds_no_session_is_set_aside_on_resume_and_refused_otherwise() {
    let path = temp("broken");
    let dir = path.parent().unwrap().to_path_buf();
    // A crash while the header was written.
    std::fs::write(&path, br#"{"type":"header","format":"metamer-sess"#).unwrap();
    let e = Session::<String, Target>::open(
        &path,
        plan(TILES, Duration::ZERO),
        "a test rig".into(),
        instruments(),
        false,
    )
    .err()
    .expect("refused without resume");
    assert!(
        e.to_string().contains("holds no session to continue")
            && e.to_string().contains("header line was cut off"),
        "{e}"
    );
    let s = open(&path, plan(TILES, Duration::ZERO), true);
    let aside = dir.join("journal.jsonl.broken-1");
    assert_eq!(s.set_aside.as_deref(), Some(aside.as_path()));
    assert_eq!(s.recovered, 0);
    assert_eq!(
        std::fs::read(&aside).unwrap(),
        br#"{"type":"header","format":"metamer-sess"#
    );
    let ran = run(s, vec![], &RunOptions::default());
    assert_eq!(ran.end, RunEnd::Complete);
    // An empty journal the same way, kept under the next number.
    drop(ran);
    std::fs::write(&path, b"").unwrap();
    let s = open(&path, plan(TILES, Duration::ZERO), true);
    assert_eq!(
        s.set_aside.as_deref(),
        Some(dir.join("journal.jsonl.broken-2").as_path())
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
