//! Parsers of the files a session or an experiment writes and reads back: the measure-box
//! plan, `validate`'s readings, the light fit's fall-off CSV, session journals (as any
//! JSON lines, and line by line as a session reads its own: entries, readings, spectra)
//! and the experiment's stage records.

use std::path::Path;

use metamer::experiment::cache::{Inputs, Product, StageDir};
use metamer::light::{fit, Falloff, ModelChoice};
use metamer::measure_box::{BoxPlan, BoxStage};
use metamer::session::{reading_problem, Entry, Header, Journal, JournalEntry};
use metamer::validation::readings::parse_readings;
use serde::de::DeserializeOwned;
use serde::Serialize;
use serde_json::Value;

use crate::targets::{read, scratch, Check, Target};

/// The most steps an accepted plan may ask for: the plan caps tiles per side at 64,
/// repeats at 100, and a session of more than this would not end in an evening.
const MAX_PLAN_STEPS: usize = 2_000_000;

fn box_plan(bytes: &[u8], dir: &Path) -> Check {
    let path = scratch(dir, "plan.json", bytes);
    let Ok(plan) = BoxPlan::load(&path) else {
        return Ok(());
    };
    // The fall-off fit needs a reading on each side of the normal.
    let a = &plan.falloff_angles_deg;
    if !(a.iter().any(|&v| v < 0.0) && a.iter().any(|&v| v > 0.0)) {
        return Err(format!(
            "fall-off angles {a:?} accepted, which the fit cannot use"
        ));
    }
    let g = &plan.geometry;
    if !(g.size_m.is_finite() && g.size_m > 0.0) {
        return Err(format!("a plan with a box of {} m accepted", g.size_m));
    }
    let mut steps = 0;
    for stage in BoxStage::ALL {
        steps += plan.steps(stage).len();
        if steps > MAX_PLAN_STEPS {
            return Err(format!(
                "a plan of more than {MAX_PLAN_STEPS} steps accepted"
            ));
        }
    }
    for target in plan.steps(BoxStage::Tiles).iter().take(3) {
        let _ = plan.prompt(&target.data.target);
    }
    Ok(())
}

fn readings(bytes: &[u8], _: &Path) -> Check {
    let Ok(set) = parse_readings(&String::from_utf8_lossy(bytes), Path::new("fuzz.csv")) else {
        return Ok(());
    };
    for (n, p) in set.patches.iter().chain(set.white.iter().map(|w| (&0, w))) {
        if p.xyz.iter().chain(p.u_xyz).any(|v| !v.is_finite()) {
            return Err(format!("patch {n} read as {:?} ± {:?}", p.xyz, p.u_xyz));
        }
    }
    let (white, _) = set.white_or_brightest();
    if !white.to_array().iter().all(|v| v.is_finite()) {
        return Err(format!("a white of {white:?}"));
    }
    Ok(())
}

fn falloff(bytes: &[u8], _: &Path) -> Check {
    if let Ok(f) = Falloff::parse_csv(&String::from_utf8_lossy(bytes), Path::new("fuzz.csv")) {
        let _ = f.validate();
    }
    Ok(())
}

/// The fit of what the reader accepted: its C-γ table (what IES, EULUMDAT and scenes are
/// made from) must be finite and ≥ 0 everywhere. Cross-validation makes it a thousand
/// times slower than the reader, so it is a target of its own.
fn falloff_fit(bytes: &[u8], _: &Path) -> Check {
    let Ok(f) = Falloff::parse_csv(&String::from_utf8_lossy(bytes), Path::new("fuzz.csv")) else {
        return Ok(());
    };
    let Ok(fitted) = fit(&f, ModelChoice::Auto) else {
        return Ok(());
    };
    for c in [0.0, 90.0, 180.0, 270.0, 300.0] {
        for g in [0.0, 45.0, 89.0, 90.0] {
            let v = fitted.table.at(c, g);
            if !v.is_finite() || v < 0.0 {
                return Err(format!("a fitted table of {v} at C {c}°, γ {g}"));
            }
        }
    }
    if !(fitted.normal_luminance.is_finite() && fitted.normal_luminance > 0.0) {
        return Err(format!("a normal luminance of {}", fitted.normal_luminance));
    }
    Ok(())
}

/// The header a resume expects: that of the seed journal, so mutated journals get past the
/// plan check and into their entries.
fn journal_header<H: DeserializeOwned>(seed: &[u8]) -> Header<H> {
    let first = seed.split(|&b| b == b'\n').next().unwrap();
    let mut v: Value = serde_json::from_slice(first).unwrap();
    v.as_object_mut().unwrap().remove("type");
    serde_json::from_value(v).unwrap()
}

/// Resumes `bytes` as a journal of header `H` and entries `E`: what is kept and what is
/// set aside account for every byte, no step is kept twice, and `accepted` holds for
/// every entry kept.
fn journal_as<H, E>(
    bytes: &[u8],
    dir: &Path,
    expected: &Header<H>,
    accepted: impl Fn(&E) -> Check,
) -> Check
where
    H: Serialize + DeserializeOwned,
    E: Serialize + DeserializeOwned + JournalEntry,
{
    let path = scratch(dir, "log.jsonl", bytes);
    let _ = std::fs::remove_file(metamer::session::torn_path(&path));
    let _ = std::fs::remove_file(metamer::session::duplicates_path(&path));
    if let Ok((_, recovered)) = Journal::<H, E>::resume(&path, expected) {
        let kept = std::fs::metadata(&path).map_err(|e| e.to_string())?.len() as usize;
        let aside = recovered.torn_bytes + recovered.duplicate_bytes;
        if kept + aside < bytes.len() {
            return Err(format!(
                "{} bytes of the journal neither kept nor set aside",
                bytes.len() - kept - aside
            ));
        }
        // Every step is in what was kept once: the later entries were set aside.
        let mut steps = std::collections::BTreeSet::new();
        for (line, e) in &recovered.entries {
            if let Some(step) = e.step() {
                if !steps.insert(step) {
                    return Err(format!("step {step} kept twice (line {line})"));
                }
            }
            accepted(e).map_err(|what| format!("line {line}: {what}"))?;
        }
    }
    Ok(())
}

fn journal(bytes: &[u8], dir: &Path, expected: &Header<Value>) -> Check {
    journal_as::<Value, Value>(bytes, dir, expected, |_| Ok(()))
}

/// The header of the seed measure-box journal, as a session reads its own.
type BoxHeader = Header<metamer::session::SessionHeader<Value>>;

/// A measure-box journal read as the session reads it: each line an entry whose reading
/// (XYZ, chromaticity, spectrum, flags) is typed and checked. What is kept is a reading an
/// instrument can have given: finite, and its XYZ following from its spectrum.
fn journal_lines(bytes: &[u8], dir: &Path) -> Check {
    thread_local! {
        static HEADER: BoxHeader = journal_header(&read(BOX_JOURNAL));
    }
    HEADER.with(|h| {
        journal_as::<_, Entry<Value>>(bytes, dir, h, |e| {
            if e.reading.xyz.iter().any(|v| !v.is_finite()) {
                return Err(format!("a reading of {:?} kept", e.reading.xyz));
            }
            match reading_problem(&e.reading) {
                Some(p) => Err(format!("a reading kept although {p}")),
                None => Ok(()),
            }
        })
    })
}

/// A measure-box tiles journal of three readings with spectra, written by
/// `metamer measure-box --plan P --spectral 'sim:i1pro?time_scale=0' --spot
/// 'sim:cs100a?time_scale=0' --stop-after 3` with P `{"repeats": 2, "geometry": {"rows": 3,
/// "cols": 3}}`.
const BOX_JOURNAL: &str = "tests/data/fuzz/box-tiles.jsonl";

/// Single lines of the box journal, each after the header, so the mutations fall on one
/// entry at a time.
fn journal_line_seeds() -> Vec<Vec<u8>> {
    let all = read(BOX_JOURNAL);
    let lines: Vec<&[u8]> = all.split_inclusive(|&b| b == b'\n').collect();
    let mut seeds = vec![all.clone()];
    for line in &lines[1..] {
        seeds.push([lines[0], line].concat());
    }
    // The seed itself resumes with its three readings kept, so mutations of it reach the
    // entries' parser and checks rather than stopping at the header.
    let dir = std::env::temp_dir().join(format!("metamer-fuzz-seed-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = scratch(&dir, "log.jsonl", &all);
    let header: BoxHeader = journal_header(&all);
    let (_, kept) = Journal::<_, Entry<Value>>::resume(&path, &header).unwrap();
    assert_eq!(kept.entries.len(), 3, "the seed journal's readings");
    std::fs::remove_dir_all(&dir).unwrap();
    seeds
}

fn characterize_journal(bytes: &[u8], dir: &Path) -> Check {
    thread_local! {
        static HEADER: Header<Value> = journal_header(&characterize_seed());
    }
    HEADER.with(|h| journal(bytes, dir, h))
}

fn characterize_seed() -> Vec<u8> {
    // The header and the first entries: enough lines to mutate, small enough to be quick.
    let all = read("tests/data/report/experiment/display/log.jsonl");
    let lines: Vec<&[u8]> = all.split_inclusive(|&b| b == b'\n').take(12).collect();
    lines.concat()
}

fn stage_record(bytes: &[u8], dir: &Path) -> Check {
    let stage = StageDir::new(dir, "stage");
    std::fs::create_dir_all(&stage.dir).map_err(|e| e.to_string())?;
    std::fs::write(stage.path("stage.json"), bytes).map_err(|e| e.to_string())?;
    std::fs::write(stage.path("out.txt"), b"output\n").map_err(|e| e.to_string())?;
    let products = [Product {
        file: "out.txt",
        always: true,
    }];
    if let Some(record) = stage.reusable(&Inputs::new().value("options", &1), &products) {
        if !record.outputs.contains_key("out.txt") {
            return Err("a record that leaves its product out was trusted".into());
        }
    }
    Ok(())
}

/// A stage record as `StageDir::finish` writes it, for the inputs `stage_record` asks with.
fn seed_stage_record(dir: &Path) -> Vec<u8> {
    let stage = StageDir::new(dir, "stage");
    std::fs::create_dir_all(&stage.dir).unwrap();
    std::fs::write(stage.path("out.txt"), b"output\n").unwrap();
    let inputs = Inputs::new().value("options", &1);
    stage
        .finish(&inputs, &["out.txt"], 1.5, Default::default())
        .unwrap();
    let bytes = std::fs::read(stage.path("stage.json")).unwrap();
    let products = [Product {
        file: "out.txt",
        always: true,
    }];
    assert!(
        stage.reusable(&inputs, &products).is_some(),
        "the seed record is reusable"
    );
    std::fs::remove_dir_all(&stage.dir).unwrap();
    bytes
}

fn falloff_seeds() -> Vec<Vec<u8>> {
    vec![
        read("data/light_falloff_9_angles.csv"),
        b"angle_deg,horizontal\n-40,0.7\n0,1\n20,0.95\n40,0.75\n".to_vec(),
    ]
}

pub fn all(dir: &Path) -> Vec<Target> {
    vec![
        Target {
            name: "box plan",
            seeds: vec![
                br#"{"repeats": 2, "geometry": {"rows": 3, "cols": 3}}"#.to_vec(),
                br#"{"repeats": 3, "material_repeats": 2, "falloff_repeats": 2,
                     "falloff_angles_deg": [-40, 0, 20, 60], "falloff_tile": [1, 1],
                     "patches": [1, 2, 19, 24],
                     "geometry": {"size_m": 0.5, "rows": 5, "cols": 5,
                                  "light_m": [0.1, 0.1, 0.3, 0.3],
                                  "viewpoint_m": [0.25, 0.25, 1.0], "acceptance_deg": 1.0}}"#
                    .to_vec(),
            ],
            run: box_plan,
        },
        Target {
            name: "readings",
            seeds: vec![
                read("tests/data/validate/box.csv"),
                read("tests/data/validate/display.csv"),
                read("tests/data/report/experiment/box/spots.csv"),
                read("tests/data/report/experiment/display-spots/journal.jsonl"),
                br#"{"method": "path", "patches": [
                    {"patch": 1, "XYZ": [10, 11, 12], "XYZ_stderr": [0.1, 0.1, 0.1], "de_ci95": 0.5},
                    {"patch": "white", "XYZ": [95, 100, 108]}]}"#
                    .to_vec(),
                b"{\"patch\": 1, \"XYZ\": [10, 11, 12], \"instrument\": \"cs100a\"}\n\
                  {\"patch\": 2, \"XYZ\": [20, 21, 22]}\n{\"XYZ\": [30, 31, 32]}\n"
                    .to_vec(),
            ],
            run: readings,
        },
        Target {
            name: "falloff CSV",
            seeds: falloff_seeds(),
            run: falloff,
        },
        Target {
            name: "falloff fit",
            seeds: falloff_seeds(),
            run: falloff_fit,
        },
        Target {
            name: "session journal",
            seeds: vec![characterize_seed()],
            run: characterize_journal,
        },
        Target {
            name: "journal line",
            seeds: journal_line_seeds(),
            run: journal_lines,
        },
        Target {
            name: "stage record",
            seeds: vec![seed_stage_record(dir)],
            run: stage_record,
        },
    ]
}
