//! What the integration-test binaries share: running the built `metamer`, directories of
//! their own under the system's temporary directory, and paths to the repository's data.
//! Included by each binary's `main.rs` as `#[path = "../support/mod.rs"] mod support;`.

// Each test binary uses a subset of these helpers.
#![allow(dead_code)]

use std::ffi::OsStr;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::atomic::{AtomicUsize, Ordering};

use serde_json::Value;

pub mod oracle;

/// The repository's root (the root package's manifest directory).
pub fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// A file of the repository, by its path from the root, as text.
pub fn root_text(rel: &str) -> String {
    std::fs::read_to_string(root().join(rel)).unwrap()
}

/// A file under `tests/data`.
pub fn test_data(rel: &str) -> PathBuf {
    root().join("tests/data").join(rel)
}

/// A file of the `validate` fixture (`tests/data/validate`).
pub fn validate_data(name: &str) -> PathBuf {
    test_data("validate").join(name)
}

/// The `.ti3` in the layout ArgyllCMS dispread writes, of an analytic display.
pub fn dispread_analytic() -> PathBuf {
    test_data("dispread_analytic.ti3")
}

/// `data/scenes`, the scenes shipped with metamer.
pub fn scenes_dir() -> &'static Path {
    Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/data/scenes"))
}

/// The built `metamer` binary, nothing else set.
pub fn metamer_command() -> Command {
    Command::new(env!("CARGO_BIN_EXE_metamer"))
}

/// Runs `metamer args` in the test's own working directory and environment.
pub fn metamer<S: AsRef<OsStr>>(args: &[S]) -> Output {
    metamer_command()
        .args(args)
        .output()
        .expect("the metamer binary runs")
}

/// Runs `metamer args` in the repository's root, so paths such as `data/…` are found.
pub fn metamer_in_root<S: AsRef<OsStr>>(args: &[S]) -> Output {
    metamer_command()
        .args(args)
        .current_dir(root())
        .output()
        .expect("the metamer binary runs")
}

/// Runs `metamer args` without `METAMER_SIM_TIME_SCALE`, so the simulated instruments take
/// the time their options say and not what the environment running the tests sets.
pub fn metamer_unscaled<S: AsRef<OsStr>>(args: &[S]) -> Output {
    metamer_command()
        .args(args)
        .env_remove("METAMER_SIM_TIME_SCALE")
        .output()
        .expect("the metamer binary runs")
}

/// [`metamer_unscaled`] in the repository's root.
pub fn metamer_unscaled_in_root<S: AsRef<OsStr>>(args: &[S]) -> Output {
    metamer_command()
        .args(args)
        .current_dir(root())
        .env_remove("METAMER_SIM_TIME_SCALE")
        .output()
        .expect("the metamer binary runs")
}

/// Bytes (a command's output) as text.
pub fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}

/// A command's standard error as text.
pub fn stderr(o: &Output) -> String {
    text(&o.stderr)
}

/// A JSON file's value.
pub fn json(path: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// A path under the system's temporary directory that nothing else uses: named after the
/// calling test file and `tag`, this process and a count of the calls, so that tests running
/// at once in one binary (one process id) never share one. Does not exist yet.
#[track_caller]
pub fn unused_dir(tag: &str) -> PathBuf {
    static CALLS: AtomicUsize = AtomicUsize::new(0);
    let file = Path::new(std::panic::Location::caller().file());
    let stem = file.file_stem().and_then(OsStr::to_str).unwrap_or("test");
    let n = CALLS.fetch_add(1, Ordering::Relaxed);
    let dir = std::env::temp_dir().join(format!("metamer-{stem}-{tag}-{}-{n}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// [`unused_dir`], created empty.
#[track_caller]
pub fn fresh_dir(tag: &str) -> PathBuf {
    let dir = unused_dir(tag);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// An OpenEXR file of R, G, B channels: `pixel(x, y)` over the data window at `data_at`
/// (of `size`), inside a display window of `frame` at the origin, with the given
/// `chromaticities` (none if None) and `whiteLuminance`.
pub fn write_rgb_exr(
    path: &std::path::Path,
    size: (usize, usize),
    data_at: (i32, i32),
    frame: (usize, usize),
    chromaticities: Option<[f32; 8]>,
    white_luminance: Option<f32>,
    pixel: impl Fn(usize, usize) -> [f32; 3] + Sync,
) {
    use exr::prelude::*;
    let channels = SpecificChannels::rgb(|p: Vec2<usize>| {
        let v = pixel(p.x(), p.y());
        (v[0], v[1], v[2])
    });
    let mut image = Image::from_channels(size, channels);
    image.attributes.display_window = IntegerBounds::new(Vec2(0, 0), frame);
    image.layer_data.attributes.layer_position = Vec2(data_at.0, data_at.1);
    image.attributes.chromaticities =
        chromaticities.map(|c| exr::meta::attribute::Chromaticities {
            red: Vec2(c[0], c[1]),
            green: Vec2(c[2], c[3]),
            blue: Vec2(c[4], c[5]),
            white: Vec2(c[6], c[7]),
        });
    image.layer_data.attributes.white_luminance = white_luminance;
    image.write().to_file(path).unwrap();
}

/// XYZ's own chromaticities: R, G, B hold X, Y, Z.
pub const XYZ_CHROMATICITIES: [f32; 8] = [1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0 / 3.0, 1.0 / 3.0];

/// IEC 61966-2-1:1999 §5.2 (sRGB): linear R, G, B from XYZ (white Y = 1), as published to
/// four decimals; BT.709's primaries and D65, which OpenEXR assumes for an RGB file
/// without chromaticities.
pub fn srgb_from_xyz(xyz: [f64; 3]) -> [f32; 3] {
    let m = [
        [3.2406, -1.5372, -0.4986],
        [-0.9689, 1.8758, 0.0415],
        [0.0557, -0.2040, 1.0570],
    ];
    std::array::from_fn(|r| (0..3).map(|c| m[r][c] * xyz[c]).sum::<f64>() as f32)
}
