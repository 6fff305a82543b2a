//! Finding and driving headless Chromium for the report tests: the binary on PATH (its
//! absence fails under `METAMER_ORACLES=required`), a run with logging on and a profile of
//! the test's own, and a page loaded with its console checked and a screenshot that is not
//! blank.

use std::path::{Path, PathBuf};
use std::process::Command;

use crate::support::fresh_dir;
use crate::support::oracle::CHROMIUM;

/// Width and height from a PNG's IHDR chunk.
fn png_size(bytes: &[u8]) -> Option<(u32, u32)> {
    if bytes.len() < 24 || &bytes[..8] != b"\x89PNG\r\n\x1a\n" || &bytes[12..16] != b"IHDR" {
        return None;
    }
    let be = |i: usize| u32::from_be_bytes([bytes[i], bytes[i + 1], bytes[i + 2], bytes[i + 3]]);
    Some((be(16), be(20)))
}

pub fn headless(browser: &Path, dir: &Path, extra: &[&str], page: &Path) -> std::process::Output {
    Command::new(browser)
        .args([
            "--headless",
            "--disable-gpu",
            "--no-sandbox",
            "--enable-logging=stderr",
            "--v=0",
            "--no-first-run",
            "--hide-scrollbars",
            "--allow-file-access-from-files",
        ])
        .arg(format!("--user-data-dir={}", dir.join("profile").display()))
        .args(extra)
        .arg(format!("file://{}", page.display()))
        .output()
        .expect("chromium runs")
}

/// Headless Chromium, or None (the test skipped with the reason) where it is missing.
pub fn browser() -> Option<PathBuf> {
    CHROMIUM.find()
}

/// A fresh directory for one test.
pub fn fresh(name: &str) -> PathBuf {
    fresh_dir(name)
}

/// Loads `page` in headless Chromium: no console error, a screenshot of 1100 × 2400 that is
/// not blank (kept at `$keep_env` when that is set); returns the DOM.
pub fn load(browser: &Path, dir: &Path, page: &Path, keep_env: &str) -> String {
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
