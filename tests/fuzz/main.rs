//! A fuzz harness on stable Rust (libFuzzer needs nightly): every parser that reads user
//! files or instrument bytes is fed mutated seed files and random bytes from a seeded
//! generator, each input under `catch_unwind`, with a time limit per input and a memory cap
//! (the counting allocator in `alloc.rs`). A panic, a timeout, a breached cap or an
//! accepted input whose result is unusable fails the run.
//!
//! CI runs the short test (a few hundred inputs per parser). The long run:
//! `METAMER_FUZZ_ITERS=1000000 cargo test --release --test fuzz -- --ignored --nocapture`
//! (`METAMER_FUZZ_SEED` changes the inputs, `METAMER_FUZZ_ONLY` picks parsers by name).

mod alloc;
mod exr_class;
mod mutate;
mod targets;
mod targets_session;

use std::sync::mpsc;
use std::time::{Duration, Instant};

use targets::Target;

#[global_allocator]
static ALLOCATOR: alloc::Counting = alloc::Counting;

/// One input may take this long; the slowest parsers take milliseconds.
const TIME_LIMIT: Duration = Duration::from_secs(5);

enum Outcome {
    Accepted,
    Lie(String),
    Panic(String),
}

#[derive(Default)]
struct Counts {
    inputs: usize,
    accepted: usize,
    failures: Vec<String>,
}

fn show(input: &[u8]) -> String {
    let text = String::from_utf8_lossy(&input[..input.len().min(300)]);
    format!("{text:?} ({} bytes)", input.len())
}

/// Runs `iterations` inputs through every target whose name contains `only`.
fn fuzz(iterations: usize, seed: u64, only: &str) -> Vec<(String, Counts, Duration)> {
    // Memory-backed scratch where there is one: file targets write every input.
    let base = Some(std::path::PathBuf::from("/dev/shm"))
        .filter(|p| p.is_dir())
        .unwrap_or_else(std::env::temp_dir);
    let dir = base.join(format!("metamer-fuzz-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let targets: Vec<Target> = targets::all(&dir)
        .into_iter()
        .filter(|t| t.name.contains(only))
        .collect();
    let messages = std::sync::Arc::new(std::sync::Mutex::new(String::new()));
    let hook_messages = messages.clone();
    std::panic::set_hook(Box::new(move |info| {
        if let Ok(mut m) = hook_messages.lock() {
            *m = info.to_string();
        }
    }));
    let mut report = Vec::new();
    for (t, target) in targets.iter().enumerate() {
        let run = target.run;
        let scratch = dir.join(format!("t{t}"));
        std::fs::create_dir_all(&scratch).unwrap();
        // One worker per target: an input that hangs is abandoned with its thread.
        let (to_worker, inputs) = mpsc::channel::<Vec<u8>>();
        let (to_main, outcomes) = mpsc::channel::<Outcome>();
        let worker_messages = messages.clone();
        std::thread::spawn(move || {
            for input in inputs {
                alloc::set_input(&input);
                let outcome = match std::panic::catch_unwind(|| run(&input, &scratch)) {
                    Ok(Ok(())) => Outcome::Accepted,
                    Ok(Err(lie)) => Outcome::Lie(lie),
                    Err(_) => Outcome::Panic(
                        worker_messages
                            .lock()
                            .map(|m| m.clone())
                            .unwrap_or_default(),
                    ),
                };
                if to_main.send(outcome).is_err() {
                    return;
                }
            }
        });
        let mut mutator = mutate::Mutator::new(seed ^ (t as u64).wrapping_mul(0x9E37_79B9));
        let mut counts = Counts::default();
        let start = Instant::now();
        for _ in 0..iterations {
            let input = mutator.next(&target.seeds);
            counts.inputs += 1;
            to_worker.send(input.clone()).unwrap();
            match outcomes.recv_timeout(TIME_LIMIT) {
                Ok(Outcome::Accepted) => counts.accepted += 1,
                Ok(Outcome::Lie(what)) => counts
                    .failures
                    .push(format!("lie: {what}: {}", show(&input))),
                Ok(Outcome::Panic(what)) => counts
                    .failures
                    .push(format!("panic: {what}: {}", show(&input))),
                Err(_) => {
                    counts.failures.push(format!(
                        "no answer within {TIME_LIMIT:?} (hang): {}",
                        show(&input)
                    ));
                    break;
                }
            }
            if counts.failures.len() >= 20 {
                break;
            }
        }
        let elapsed = start.elapsed();
        let (peak, largest) = alloc::stats();
        println!(
            "{:<16} {:>9} inputs in {:>8.1} s: {:>3} failures; peak heap {:.1} MB, largest \
             allocation {:.1} MB",
            target.name,
            counts.inputs,
            elapsed.as_secs_f64(),
            counts.failures.len(),
            peak as f64 / 1e6,
            largest as f64 / 1e6
        );
        for f in &counts.failures {
            println!("    {f}");
        }
        report.push((target.name.to_string(), counts, elapsed));
    }
    let _ = std::panic::take_hook();
    std::fs::remove_dir_all(&dir).ok();
    report
}

fn env_or<T: std::str::FromStr>(name: &str, default: T) -> T {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

fn assert_clean(report: &[(String, Counts, Duration)]) {
    let failures: Vec<String> = report
        .iter()
        .flat_map(|(name, c, _)| c.failures.iter().map(move |f| format!("{name}: {f}")))
        .collect();
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn every_parser_survives_a_short_run_of_mutated_inputs() {
    let report = fuzz(env_or("METAMER_FUZZ_SHORT", 300), 1, "");
    assert!(report.iter().all(|(_, c, _)| c.inputs > 0));
    assert_clean(&report);
}

#[test]
#[ignore = "the long run: METAMER_FUZZ_ITERS inputs per parser (default 10⁶), minutes"]
fn every_parser_survives_a_long_run_of_mutated_inputs() {
    let iterations = env_or("METAMER_FUZZ_ITERS", 1_000_000);
    let seed = env_or("METAMER_FUZZ_SEED", 2);
    let only: String = env_or("METAMER_FUZZ_ONLY", String::new());
    let report = fuzz(iterations, seed, &only);
    assert_clean(&report);
}

/// The class of the EXR finding: small files whose header, offset table or chunks state
/// sizes the file cannot hold are refused in words about the file, before the `exr` crate
/// decodes them, and reading one allocates no more than a small multiple of its size.
#[test]
fn corrupt_exr_layouts_are_refused_in_our_words_within_the_memory_cap() {
    let dir = std::env::temp_dir().join(format!("metamer-exr-class-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let valid = exr_class::valid(&dir, 3, 2);
    for (what, bytes, words) in exr_class::corrupt(&valid) {
        let path = dir.join("corrupt.exr");
        std::fs::write(&path, &bytes).unwrap();
        alloc::reset_thread_largest();
        let e = metamer::image::read_xyz_image(&path)
            .expect_err(what)
            .to_string();
        let largest = alloc::thread_largest();
        assert!(e.contains(words), "{what}: {e}");
        assert!(e.starts_with(&path.display().to_string()), "{what}: {e}");
        assert!(!e.contains("missing bytes"), "{what}: {e}");
        assert!(
            largest < 64 * 1024,
            "{what}: an allocation of {largest} bytes for a file of {} bytes",
            bytes.len()
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// The LUT fit of a large scattered patch set once asked for 177 GB; its memory must grow
/// with the patches, not with a grid built from their distinct levels. Under the counting
/// allocator the run fails if any allocation passes the caps; peak heap is printed.
#[test]
#[ignore = "fits 10,000 patches: about 15 s"]
fn a_lut_fit_of_10000_scattered_patches_stays_within_the_memory_cap() {
    use metamer::display::{fit_profile, ModelKind, Sample};
    use metamer_drivers::noise::SplitMix64;
    let mut rng = SplitMix64::new(7);
    // An additive γ 2.2 display with sRGB primaries and a black of 0.2 cd/m².
    let m = [
        [41.24, 35.76, 18.05],
        [21.26, 71.52, 7.22],
        [1.93, 11.92, 95.05],
    ];
    let patches: Vec<Sample> = (0..10_000)
        .map(|i| {
            let rgb: [f64; 3] = match i {
                0 => [1.0; 3],
                1 => [0.0; 3],
                _ => std::array::from_fn(|_| (rng.uniform() * 1000.0).round() / 1000.0),
            };
            let lin = rgb.map(|d| d.powf(2.2));
            let xyz: [f64; 3] =
                std::array::from_fn(|r| 0.2 + (0..3).map(|k| m[r][k] * lin[k]).sum::<f64>());
            Sample {
                rgb,
                xyz: xyz.into(),
            }
        })
        .collect();
    let before = alloc::stats().0;
    let profile = fit_profile(ModelKind::Lut, &patches, None).unwrap();
    let (peak, largest) = alloc::stats();
    println!(
        "10,000-patch LUT fit: peak heap {:.1} MB (before {:.1} MB), largest allocation {:.1} MB",
        peak as f64 / 1e6,
        before as f64 / 1e6,
        largest as f64 / 1e6
    );
    assert!(profile.residuals.max_de00.is_finite());
    assert!(peak < alloc::LIVE_CAP && largest < alloc::SINGLE_CAP);
}
