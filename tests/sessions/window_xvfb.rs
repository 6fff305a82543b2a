//! The full-screen patch window on a real X server (Xvfb): a screenshot of the monitor
//! must show exactly the requested 8-bit RGB, every pixel. Each test starts its own Xvfb,
//! which picks a free display number itself (`-displayfd`), so tests and parallel runs do
//! not collide. Without Xvfb the tests are skipped with a reason, unless
//! `METAMER_ORACLES=required` (`.ci/run` installs it), when a missing Xvfb is a failure.

use std::io::BufRead;
use std::os::fd::FromRawFd;
use std::process::{Child, Command, Stdio};

use metamer::image::Drive8Image;
use metamer::rig::window::{list_monitors, WindowDisplay, WindowError};
use metamer::rig::{Placement, Screen};

use crate::support::oracle::XVFB;
use crate::support::unused_dir;

struct Xvfb {
    child: Child,
    display: String,
}

impl Drop for Xvfb {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

/// Starts `Xvfb -screen 0 WxHx24`, or None (with the reason printed) when Xvfb is
/// missing and not required (`support::oracle`).
fn xvfb(width: u32, height: u32) -> Option<Xvfb> {
    let xvfb = XVFB.find()?;
    let mut fds = [0; 2];
    // SAFETY: pipe writes two new descriptors into the array; without O_CLOEXEC the write
    // end is inherited by Xvfb, which reports its display number on it when ready.
    assert_eq!(unsafe { libc::pipe(fds.as_mut_ptr()) }, 0);
    let child = Command::new(xvfb)
        .args(["-displayfd", &fds[1].to_string()])
        .args(["-screen", "0", &format!("{width}x{height}x24")])
        .args(["-nolisten", "tcp"])
        // Without -noreset the server resets when its last client leaves, and a client
        // connecting just then is dropped ("failed to read whole buffer").
        .arg("-noreset")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("Xvfb starts");
    // SAFETY: both descriptors came from pipe() above and are owned here alone.
    let mut read_end = unsafe { std::fs::File::from_raw_fd(fds[0]) };
    drop(unsafe { std::fs::File::from_raw_fd(fds[1]) });
    // Read one line, not to EOF: an Xvfb that another test thread spawns meanwhile inherits
    // this pipe's write end too and keeps it open, so EOF may never come (seen as a hang).
    // Xvfb writes the number followed by a newline.
    let mut number = String::new();
    std::io::BufReader::new(&mut read_end)
        .read_line(&mut number)
        .expect("Xvfb reports its display number");
    let number = number.trim();
    assert!(
        !number.is_empty(),
        "Xvfb exited without reporting a display"
    );
    Some(Xvfb {
        child,
        display: format!(":{number}"),
    })
}

#[test]
fn screenshot_shows_exactly_the_requested_rgb() {
    let Some(x) = xvfb(640, 480) else { return };
    let mut window = WindowDisplay::open(Some(&x.display), 0).unwrap();
    let m = window.monitor().clone();
    assert_eq!((m.x, m.y, m.width, m.height), (0, 0, 640, 480), "{m}");
    // Opens black.
    assert!(window.screenshot().unwrap().iter().all(|&p| p == [0, 0, 0]));
    for rgb in [
        [255, 255, 255],
        [255, 0, 0],
        [0, 255, 0],
        [0, 0, 255],
        [1, 2, 3],
        [128, 64, 200],
        [254, 1, 127],
        [0, 0, 0],
    ] {
        window.show(rgb).unwrap();
        let pixels = window.screenshot().unwrap();
        assert_eq!(pixels.len(), 640 * 480);
        let wrong = pixels.iter().filter(|&&p| p != rgb).count();
        assert_eq!(
            wrong,
            0,
            "{rgb:?}: {wrong} pixels differ, e.g. {:?}",
            pixels.iter().find(|&&p| p != rgb)
        );
    }
    assert_eq!(window.spec(), "window:0");
    assert!(window.describe().contains(&x.display));
}

/// A 2×2 image on a 640×480 monitor, scaled to fit: 480×480 at 80 from the left, each
/// source pixel a 240×240 block, black bars either side; a colour shown afterwards covers
/// everything again.
#[test]
fn an_image_is_shown_whole_scaled_to_fit() {
    let Some(x) = xvfb(640, 480) else { return };
    let mut window = WindowDisplay::open(Some(&x.display), 0).unwrap();
    let (a, b, c, d) = ([255, 0, 0], [0, 255, 0], [0, 0, 255], [10, 20, 30]);
    let image = Drive8Image::new(2, 2, vec![a, b, c, d]).unwrap();
    let placement = window.show_image(&image).unwrap();
    assert_eq!(
        placement,
        Placement {
            left: 80.0 / 640.0,
            top: 0.0,
            width: 480.0 / 640.0,
            height: 1.0
        }
    );
    let pixels = window.screenshot().unwrap();
    let want = |x: usize, y: usize| match (x, y) {
        (x, _) if !(80..560).contains(&x) => [0, 0, 0],
        (x, y) => match (x < 320, y < 240) {
            (true, true) => a,
            (false, true) => b,
            (true, false) => c,
            (false, false) => d,
        },
    };
    let wrong = (0..640 * 480)
        .filter(|&i| pixels[i] != want(i % 640, i / 640))
        .count();
    assert_eq!(wrong, 0, "{wrong} pixels differ");
    window.show([7, 8, 9]).unwrap();
    assert!(window.screenshot().unwrap().iter().all(|&p| p == [7, 8, 9]));
}

#[test]
fn monitors_errors_and_reopening() {
    let Some(x) = xvfb(320, 200) else { return };
    let monitors = list_monitors(Some(&x.display)).unwrap();
    assert_eq!(monitors.len(), 1, "{monitors:?}");
    assert_eq!((monitors[0].width, monitors[0].height), (320, 200));
    let e = WindowDisplay::open(Some(&x.display), 3).err().unwrap();
    assert!(
        matches!(
            e,
            WindowError::NoSuchMonitor {
                index: 3,
                count: 1,
                ..
            }
        ),
        "{e}"
    );
    assert!(
        e.to_string().contains("has no monitor 3; it has 1: 0: "),
        "{e}"
    );
    {
        let mut w = WindowDisplay::open(Some(&x.display), 0).unwrap();
        w.show([9, 99, 199]).unwrap();
        assert!(w.screenshot().unwrap().iter().all(|&p| p == [9, 99, 199]));
    }
    // A new session on the same server opens black again, on top of whatever was there.
    let w = WindowDisplay::open(Some(&x.display), 0).unwrap();
    assert!(w.screenshot().unwrap().iter().all(|&p| p == [0, 0, 0]));
}

#[test]
fn a_display_nobody_serves_is_a_clear_error() {
    // Display numbers are below 65536 on every server; this one has no socket.
    let e = WindowDisplay::open(Some(":65000"), 0).err().unwrap();
    let text = e.to_string();
    assert!(
        text.starts_with("cannot connect to X display ':65000': ") && text.contains("xhost"),
        "{text}"
    );
}

#[test]
fn characterize_runs_through_the_window_backend() {
    let Some(x) = xvfb(320, 240) else { return };
    let dir = unused_dir("characterize");
    let _ = std::fs::remove_dir_all(&dir);
    let o = Command::new(env!("CARGO_BIN_EXE_metamer"))
        .args(["characterize", "--display", "window", "--instrument"])
        .arg("sim:cs100a?time_scale=0")
        .args(["--settle-ms", "0", "--stop-after", "5", "-o"])
        .arg(&dir)
        .env("DISPLAY", &x.display)
        .stdin(Stdio::null())
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(
        err.contains("a simulated instrument cannot see a real screen"),
        "{err}"
    );
    let log = std::fs::read_to_string(dir.join("log.jsonl")).unwrap();
    assert!(log
        .lines()
        .next()
        .unwrap()
        .contains("\"display\":\"window:0\""));
    assert_eq!(log.lines().count(), 6);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_video_lut_that_is_not_identity_is_reported() {
    use x11rb::connection::Connection;
    use x11rb::protocol::randr::ConnectionExt as _;
    let Some(x) = xvfb(320, 240) else { return };
    let window = WindowDisplay::open(Some(&x.display), 0).unwrap();
    // Xvfb applies no gamma and reports an all-zero ramp: that is "no LUT", not a warning.
    assert_eq!(window.video_lut().unwrap(), None);
    assert!(window.warnings().is_empty());
    // A night-light filter sets blue to 70 %; Xvfb keeps the ramp it is given.
    let (conn, screen) = x11rb::connect(Some(&x.display)).unwrap();
    let root = conn.setup().roots[screen].root;
    let res = conn
        .randr_get_screen_resources_current(root)
        .unwrap()
        .reply()
        .unwrap();
    let crtc = res.crtcs[0];
    let n = usize::from(
        conn.randr_get_crtc_gamma_size(crtc)
            .unwrap()
            .reply()
            .unwrap()
            .size,
    );
    let ramp: Vec<u16> = (0..n).map(|i| (65535 * i / (n - 1)) as u16).collect();
    let blue: Vec<u16> = ramp.iter().map(|&v| (f64::from(v) * 0.7) as u16).collect();
    conn.randr_set_crtc_gamma(crtc, &ramp, &ramp, &blue)
        .unwrap()
        .check()
        .unwrap();
    let lut = window.video_lut().unwrap().expect("the ramp just set");
    assert_eq!((lut.red, lut.blue), (ramp.clone(), blue));
    let warnings = window.warnings();
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    assert!(
        warnings[0].contains("departs from identity by up to 30.0 %"),
        "{}",
        warnings[0]
    );
    // Identity again: nothing to say.
    conn.randr_set_crtc_gamma(crtc, &ramp, &ramp, &ramp)
        .unwrap()
        .check()
        .unwrap();
    assert!(window.warnings().is_empty());
}
