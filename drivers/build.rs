//! Generates one test per transcript of each instrument (`protocols/MODEL/transcripts/
//! *.jsonl`), so a new transcript is a new test without touching any code. Each model's
//! tests go to `OUT_DIR/MODEL_transcript_tests.rs` and call that test file's
//! `replay_transcript(path)`.

use std::fmt::Write;
use std::path::Path;

/// The models with transcripts.
const MODELS: &[&str] = &["cs100a", "i1pro"];

fn main() {
    for model in MODELS {
        generate(model);
    }
}

fn generate(model: &str) {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../protocols")
        .join(model)
        .join("transcripts");
    println!("cargo:rerun-if-changed={}", dir.display());
    let mut names: Vec<_> = std::fs::read_dir(&dir)
        .map(|entries| {
            entries
                .filter_map(Result::ok)
                .map(|e| e.path())
                .filter(|p| p.extension().is_some_and(|e| e == "jsonl"))
                .collect()
        })
        .unwrap_or_default();
    names.sort();
    let mut code = String::new();
    for path in names {
        let stem = path.file_stem().unwrap().to_string_lossy();
        let ident: String = stem
            .chars()
            .map(|c| {
                if c.is_ascii_alphanumeric() {
                    c.to_ascii_lowercase()
                } else {
                    '_'
                }
            })
            .collect();
        writeln!(
            code,
            "#[test]\nfn replay_{ident}() {{\n    replay_transcript({:?});\n}}",
            path.canonicalize()
                .unwrap_or(path.clone())
                .display()
                .to_string()
        )
        .unwrap();
    }
    let out =
        Path::new(&std::env::var("OUT_DIR").unwrap()).join(format!("{model}_transcript_tests.rs"));
    std::fs::write(out, code).unwrap();
}
