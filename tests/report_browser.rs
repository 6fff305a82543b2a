//! The validation report in a real browser: headless Chromium loads `report.html` from
//! disk, with logging on, and must log no console error, draw a non-trivial screenshot and
//! have the figures in its DOM. Skipped (with the reason printed) only where no chromium
//! binary is installed; in CI (`CI` set) a missing chromium fails the test.

use std::path::{Path, PathBuf};
use std::process::Command;

fn chromium() -> Option<PathBuf> {
    ["chromium", "chromium-browser", "google-chrome"]
        .iter()
        .find_map(|name| {
            std::env::var_os("PATH").and_then(|paths| {
                std::env::split_paths(&paths)
                    .map(|p| p.join(name))
                    .find(|p| p.is_file())
            })
        })
}

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/validate")
        .join(name)
}

/// Width and height from a PNG's IHDR chunk.
fn png_size(bytes: &[u8]) -> Option<(u32, u32)> {
    if bytes.len() < 24 || &bytes[..8] != b"\x89PNG\r\n\x1a\n" || &bytes[12..16] != b"IHDR" {
        return None;
    }
    let be = |i: usize| u32::from_be_bytes([bytes[i], bytes[i + 1], bytes[i + 2], bytes[i + 3]]);
    Some((be(16), be(20)))
}

fn headless(browser: &Path, dir: &Path, extra: &[&str], page: &Path) -> std::process::Output {
    Command::new(browser)
        .args([
            "--headless",
            "--disable-gpu",
            "--no-sandbox",
            "--enable-logging=stderr",
            "--v=0",
            "--no-first-run",
            "--allow-file-access-from-files",
        ])
        .arg(format!("--user-data-dir={}", dir.join("profile").display()))
        .args(extra)
        .arg(format!("file://{}", page.display()))
        .output()
        .expect("chromium runs")
}

fn browser() -> Option<PathBuf> {
    let found = chromium();
    if found.is_none() {
        assert!(
            std::env::var_os("CI").is_none(),
            "CI is set but no chromium binary is installed (.ci/run installs Debian's chromium)"
        );
        eprintln!("skipped: no chromium binary on PATH (apt-get install chromium)");
    }
    found
}

/// Loads `page` in headless Chromium: no console error, a screenshot of 1100 × 2400 that is
/// not blank (kept at `$keep_env` when that is set); returns the DOM.
fn load(browser: &Path, dir: &Path, page: &Path, keep_env: &str) -> String {
    let shot = dir.join("report.png");
    let run = headless(
        browser,
        dir,
        &[
            &format!("--screenshot={}", shot.display()),
            "--window-size=1100,2400",
        ],
        page,
    );
    let log = String::from_utf8_lossy(&run.stderr);
    // Chromium logs page console messages as `CONSOLE(line)` / `Console` entries; an
    // uncaught error or a failed resource load shows as ":ERROR:" with the page's URL.
    let console_errors: Vec<&str> = log
        .lines()
        .filter(|l| {
            (l.contains("CONSOLE") || l.contains("Console")) && l.to_lowercase().contains("error")
                || l.contains("report.html") && l.contains(":ERROR:")
        })
        .collect();
    assert!(
        console_errors.is_empty(),
        "console errors: {console_errors:#?}"
    );
    let png = std::fs::read(&shot)
        .unwrap_or_else(|e| panic!("no screenshot ({e}); chromium said:\n{log}"));
    assert_eq!(png_size(&png), Some((1100, 2400)), "not the PNG asked for");
    // A blank page compresses to a few kB; the figures, swatches and table do not.
    assert!(
        png.len() > 60_000,
        "screenshot of {} bytes looks empty",
        png.len()
    );
    if let Ok(keep) = std::env::var(keep_env) {
        std::fs::copy(&shot, keep).unwrap();
    }
    let dom = headless(browser, dir, &["--dump-dom"], page);
    String::from_utf8_lossy(&dom.stdout).into_owned()
}

#[test]
fn report_renders_in_headless_chromium_without_console_errors() {
    let Some(browser) = browser() else {
        return;
    };
    let dir = std::env::temp_dir().join(format!("metamer-report-browser-{}", std::process::id()));
    std::fs::remove_dir_all(&dir).ok();
    let out = Command::new(env!("CARGO_BIN_EXE_metamer"))
        .args(["validate", "--reference"])
        .arg(data("box.csv"))
        .arg("--test")
        .arg(data("display.csv"))
        .arg("--simulation")
        .arg(data("box.csv"))
        .args(["--out-of-gamut", "7,12", "-o"])
        .arg(&dir)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let page = dir.join("report.html");
    let dom = load(&browser, &dir, &page, "METAMER_KEEP_SCREENSHOT");
    for id in ["fig4", "fig5", "fig6", "fig7", "verdict"] {
        assert!(dom.contains(&format!("id=\"{id}\"")), "the DOM lacks #{id}");
    }
    // Three bar charts of 24 patches and one figure of two planes with 24 arrows each.
    assert_eq!(dom.matches("class=\"bar\"").count(), 3 * 24);
    assert_eq!(dom.matches("class=\"arrow\"").count(), 2 * 24);
    assert_eq!(dom.matches("class=\"oog\"").count(), 3 * 2);
    std::fs::remove_dir_all(&dir).ok();
}

/// The experiment's report with every section, built from a small experiment directory
/// (`tests/data/report/`), in a real browser: no console error, every section in the DOM,
/// the light chart inlined without scripts.
#[test]
fn experiment_report_has_every_section_in_headless_chromium() {
    use metamer::experiment::validate::{report_input, ReadingFiles};
    use metamer::output::OutputPolicy;
    use metamer::validation::write_report_files;

    let Some(browser) = browser() else {
        return;
    };
    let exp = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/report/experiment");
    let dir =
        std::env::temp_dir().join(format!("metamer-report-experiment-{}", std::process::id()));
    std::fs::remove_dir_all(&dir).ok();
    let files = ReadingFiles {
        box_spots: &exp.join("box/spots.csv"),
        simulation: &exp.join("simulation/spots.csv"),
        display: &exp.join("display-spots/spots.csv"),
    };
    let white = [29.424_122_518_279_695, 31.015, 34.538_708_337_905_01];
    let oog = [1, 4, 7, 9, 11, 12, 14, 15, 16];
    let input = report_input(&exp.join("validation"), white, &files, &oog).unwrap();
    write_report_files(&dir, &input, &OutputPolicy::new(true)).unwrap();
    let page = dir.join("report.html");
    let dom = load(&browser, &dir, &page, "METAMER_KEEP_EXPERIMENT_SCREENSHOT");
    for id in [
        "verdict",
        "fig4",
        "fig6",
        "uncertainty",
        "display-model",
        "display-verification",
        "light-fit",
        "light-chart",
        "render-confidence",
        "instruments",
        "inputs",
    ] {
        assert!(dom.contains(&format!("id=\"{id}\"")), "the DOM lacks #{id}");
    }
    assert!(!dom.contains("<script"), "the page must run no code");
    // The verdict names the six patches above the JND and why.
    assert!(
        dom.contains("18 of 24 patches are below the JND"),
        "verdict"
    );
    assert!(dom.contains(
        "6 outside the display's gamut (7 orange, 11 yellow green, 12 orange yellow, 14 green, 15 red, 16 yellow)"
    ));
    assert!(dom.contains(
        "In all 6 the simulation is within 0.4 of the box: the error arises on the display."
    ));
    // The i1Pro's two calibrations (emissive for the tiles, reflective for the materials).
    assert_eq!(dom.matches("on white tile").count(), 2);
    // The render's bound enters the simulation's intervals.
    assert!(dom.contains("radiosity solver's per-patch error bound"));
    std::fs::remove_dir_all(&dir).ok();
}
