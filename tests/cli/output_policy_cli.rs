//! Every command writes its files under one policy (`metamer::output`): never onto one of
//! its inputs, never over an existing file without `--force`, through symlinks to the file
//! they name, in place onto a device, and nothing half-written on failure. One test per
//! way a command used to lose data.

use std::os::unix::fs::FileTypeExt;
use std::path::{Path, PathBuf};
use std::process::Output;

use crate::support::{dispread_analytic, fresh_dir, metamer_unscaled_in_root, text};

struct Scratch(PathBuf);

impl Scratch {
    fn new(tag: &str) -> Scratch {
        Scratch(fresh_dir(tag))
    }
    fn path(&self, name: &str) -> PathBuf {
        self.0.join(name)
    }
    fn s(&self, name: &str) -> String {
        self.path(name).to_str().unwrap().to_string()
    }
    /// The measured patches of the analytic test display, as `fit` reads them.
    fn measurements(&self) -> PathBuf {
        let p = self.path("m.ti3");
        std::fs::copy(dispread_analytic(), &p).unwrap();
        p
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

fn fit(measurements: &Path, output: &str, extra: &[&str]) -> Output {
    let m = measurements.to_str().unwrap();
    metamer_unscaled_in_root(&[&["fit", "--measurements", m, "-o", output], extra].concat())
}

#[test]
fn fit_refuses_to_write_onto_its_own_input_even_forced() {
    let s = Scratch::new("fit-input");
    let m = s.measurements();
    let before = std::fs::read(&m).unwrap();
    // The same file under another spelling and through a symlink.
    std::os::unix::fs::symlink(&m, s.path("alias.json")).unwrap();
    for out in [s.s("m.ti3"), s.s("./m.ti3"), s.s("alias.json")] {
        let o = fit(&m, &out, &["--force"]);
        assert_eq!(o.status.code(), Some(1), "{out}");
        let err = text(&o.stderr);
        assert!(
            err.contains(&format!(
                "refusing to write {out}: it is the input {}",
                m.display()
            )),
            "{err}"
        );
        assert_eq!(std::fs::read(&m).unwrap(), before);
    }
}

#[test]
fn fit_refuses_an_existing_profile_unless_forced() {
    let s = Scratch::new("fit-exists");
    let m = s.measurements();
    std::fs::write(s.path("p.json"), "keep me").unwrap();
    let o = fit(&m, &s.s("p.json"), &[]);
    assert_eq!(o.status.code(), Some(1));
    let err = text(&o.stderr);
    assert!(
        err.contains("refusing to overwrite the existing file") && err.contains("--force"),
        "{err}"
    );
    assert_eq!(
        std::fs::read_to_string(s.path("p.json")).unwrap(),
        "keep me"
    );
    let o = fit(&m, &s.s("p.json"), &["--force"]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let p: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(s.path("p.json")).unwrap()).unwrap();
    assert!(p["format"]
        .as_str()
        .unwrap()
        .starts_with("metamer-display-profile"));
    // No temporary or `.partial` file left beside it.
    let mut names: Vec<String> = std::fs::read_dir(&s.0)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(names, ["m.ti3", "p.json"]);
}

#[test]
fn fit_writes_through_a_symlink_and_onto_a_device_without_replacing_them() {
    let s = Scratch::new("fit-link");
    let m = s.measurements();
    std::fs::create_dir(s.path("profiles")).unwrap();
    std::os::unix::fs::symlink("profiles/real.json", s.path("current.json")).unwrap();
    let o = fit(&m, &s.s("current.json"), &[]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let link = std::fs::symlink_metadata(s.path("current.json")).unwrap();
    assert!(link.file_type().is_symlink(), "the link was replaced");
    assert!(std::fs::read_to_string(s.path("profiles/real.json"))
        .unwrap()
        .contains("metamer-display-profile"));
    // A character device is written in place: /dev/null stays a device.
    let o = fit(&m, "/dev/null", &[]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(std::fs::metadata("/dev/null")
        .unwrap()
        .file_type()
        .is_char_device());
}

#[test]
fn reproduce_refuses_its_profile_and_targets_as_output() {
    let s = Scratch::new("reproduce");
    let m = s.measurements();
    let o = fit(&m, &s.s("p.json"), &[]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    std::fs::write(s.path("t.csv"), "X,Y,Z\n20,21,22\n").unwrap();
    let profile = std::fs::read(s.path("p.json")).unwrap();
    for out in ["p.json", "t.csv"] {
        let o = metamer_unscaled_in_root(&[
            "reproduce",
            "--profile",
            &s.s("p.json"),
            "--xyz",
            &s.s("t.csv"),
            "-o",
            &s.s(out),
            "--force",
        ]);
        assert_eq!(o.status.code(), Some(1), "{out}");
        assert!(
            text(&o.stderr).contains("it is the input"),
            "{}",
            text(&o.stderr)
        );
    }
    assert_eq!(std::fs::read(s.path("p.json")).unwrap(), profile);
    assert_eq!(
        std::fs::read_to_string(s.path("t.csv")).unwrap(),
        "X,Y,Z\n20,21,22\n"
    );
    let o = metamer_unscaled_in_root(&[
        "reproduce",
        "--profile",
        &s.s("p.json"),
        "--xyz",
        &s.s("t.csv"),
        "-o",
        &s.s("rgb.csv"),
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(std::fs::read_to_string(s.path("rgb.csv"))
        .unwrap()
        .starts_with("r,g,b,out_of_gamut\n"));
}

#[test]
fn render_image_refuses_an_existing_preview_before_rendering() {
    let s = Scratch::new("render");
    std::fs::write(s.path("old.png"), "an earlier preview").unwrap();
    let args = |extra: &[&str]| {
        let mut a = vec![
            "render".to_string(),
            "image".into(),
            "data/scenes/validation-box.json".into(),
            "--spp".into(),
            "1".into(),
            "--width".into(),
            "4".into(),
            "--height".into(),
            "4".into(),
            "-o".into(),
            s.s("img.pfm"),
        ];
        a.extend(extra.iter().map(|e| e.to_string()));
        a
    };
    let run = |a: Vec<String>| {
        metamer_unscaled_in_root(&a.iter().map(String::as_str).collect::<Vec<_>>())
    };
    let o = run(args(&["--preview", &s.s("old.png")]));
    assert_eq!(o.status.code(), Some(1));
    assert!(text(&o.stderr).contains("--force"), "{}", text(&o.stderr));
    assert!(!s.path("img.pfm").exists(), "nothing rendered or written");
    assert_eq!(
        std::fs::read_to_string(s.path("old.png")).unwrap(),
        "an earlier preview"
    );
    // The preview may not be the image itself.
    let o = run(args(&["--preview", &s.s("img.pfm")]));
    assert_eq!(o.status.code(), Some(2), "{}", text(&o.stderr));
    // Forced: both written, the preview a PNG.
    let o = run(args(&["--preview", &s.s("old.png"), "--force"]));
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(std::fs::read(s.path("old.png"))
        .unwrap()
        .starts_with(b"\x89PNG\r\n\x1a\n"));
    assert!(std::fs::read(s.path("img.pfm"))
        .unwrap()
        .starts_with(b"PF\n4 4\n"));
}

#[test]
fn characterize_refuses_to_overwrite_a_profile_in_a_directory_without_a_log() {
    let s = Scratch::new("char");
    let dir = s.path("out");
    std::fs::create_dir(&dir).unwrap();
    std::fs::write(dir.join("profile.json"), "someone's profile").unwrap();
    let base = [
        "characterize",
        "--display",
        "virtual:ideal-crt",
        "--instrument",
        "sim:cs100a?time_scale=0",
        "--ramp-steps",
        "3",
        "-o",
        dir.to_str().unwrap(),
    ];
    let o = metamer_unscaled_in_root(&base);
    assert_eq!(o.status.code(), Some(1));
    let err = text(&o.stderr);
    assert!(
        err.contains("profile.json") && err.contains("--force"),
        "{err}"
    );
    // Refused before anything was measured: no log was started.
    assert!(!dir.join("log.jsonl").exists());
    assert_eq!(
        std::fs::read_to_string(dir.join("profile.json")).unwrap(),
        "someone's profile"
    );
    let o = metamer_unscaled_in_root(&[&base[..], &["--force"]].concat());
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(std::fs::read_to_string(dir.join("profile.json"))
        .unwrap()
        .contains("metamer-display-profile"));
}

#[test]
fn reproduce_refuses_its_image_as_output_and_a_failed_conversion_keeps_the_old_png() {
    let s = Scratch::new("reproduce-image");
    let m = s.measurements();
    assert!(fit(&m, &s.s("p.json"), &[]).status.success());
    // A 2×1 PFM: one finite pixel, then one NaN pixel.
    let pfm = |second: f32| {
        let mut b = b"PF\n2 1\n-1.0\n".to_vec();
        for v in [20.0f32, 21.0, 22.0, second, 21.0, 22.0] {
            b.extend(v.to_le_bytes());
        }
        b
    };
    std::fs::write(s.path("img.pfm"), pfm(20.0)).unwrap();
    let image = std::fs::read(s.path("img.pfm")).unwrap();
    let reproduce = |img: &str, out: &str| {
        metamer_unscaled_in_root(&[
            "reproduce",
            "--profile",
            &s.s("p.json"),
            "--image",
            &s.s(img),
            "-o",
            &s.s(out),
            "--force",
        ])
    };
    let o = reproduce("img.pfm", "img.pfm");
    assert_eq!(o.status.code(), Some(1));
    assert!(
        text(&o.stderr).contains("it is the input"),
        "{}",
        text(&o.stderr)
    );
    assert_eq!(std::fs::read(s.path("img.pfm")).unwrap(), image);
    // A good conversion, then a failed one onto the same PNG: the first stays whole.
    assert!(reproduce("img.pfm", "out.png").status.success());
    let png = std::fs::read(s.path("out.png")).unwrap();
    std::fs::write(s.path("nan.pfm"), pfm(f32::NAN)).unwrap();
    let o = reproduce("nan.pfm", "out.png");
    assert_eq!(o.status.code(), Some(1));
    assert!(
        text(&o.stderr).contains("not a finite XYZ"),
        "{}",
        text(&o.stderr)
    );
    assert_eq!(std::fs::read(s.path("out.png")).unwrap(), png);
}

/// An output that is a FIFO nothing reads made the command wait in `open` for ever; it is
/// an error at once, and one with a reader gets the file.
#[test]
fn fit_onto_a_fifo_without_a_reader_fails_at_once() {
    let s = Scratch::new("fifo");
    let m = s.measurements();
    let fifo = s.path("p.json");
    let c = std::ffi::CString::new(fifo.as_os_str().as_encoded_bytes()).unwrap();
    // SAFETY: a NUL-terminated path and a mode.
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o644) }, 0);
    let start = std::time::Instant::now();
    let o = fit(&m, &s.s("p.json"), &[]);
    let e = text(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(
        e.contains("p.json: it is a named pipe (FIFO) that nothing is reading"),
        "{e}"
    );
    assert!(start.elapsed() < std::time::Duration::from_secs(30));
    assert!(std::fs::symlink_metadata(&fifo)
        .unwrap()
        .file_type()
        .is_fifo());
}
