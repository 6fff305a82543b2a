//! The real screen: an override-redirect X11 window covering one
//! monitor, filled with exactly the requested 8-bit RGB, with the pointer hidden over it.
//!
//! It speaks the X11 protocol itself through `x11rb` (no system library), so it works on
//! any X server and on XWayland. The colour is the window's background pixel, painted by
//! the server itself (X11 protocol §8, ChangeWindowAttributes + ClearArea): no drawing code,
//! no events to serve, and the server repaints it after anything covered it. Monitors come
//! from RandR 1.5 `GetMonitors` (the layout the desktop shows), else the whole root window.
//! Colour management (a compositor's ICC transform, night-light filters) must be off for
//! the panel itself to be measured; that is outside what an X client can check.

mod image;
mod pixels;

use std::time::Duration;

use x11rb::connection::{Connection, RequestConnection};
use x11rb::protocol::randr::{self, ConnectionExt as _};
use x11rb::protocol::xproto::{
    ChangeWindowAttributesAux, ConfigureWindowAux, ConnectionExt as _, CreateGCAux,
    CreateWindowAux, ImageFormat, ImageOrder, Rectangle, StackMode, VisualClass, WindowClass,
};
use x11rb::rust_connection::RustConnection;
use x11rb::wrapper::ConnectionExt as _;

pub use pixels::PixelFormat;

use super::{Placement, Screen, ScreenError};
use crate::image::Drive8Image;

/// The window backend could not open or draw.
#[derive(Debug, thiserror::Error)]
pub enum WindowError {
    #[error("no X display: the environment variable DISPLAY is not set (run this in the desktop session of the monitor to measure, e.g. DISPLAY=:0, or use a virtual display)")]
    NoDisplay,
    #[error("cannot connect to X display '{display}': {message} (is an X server running there, and may this user use it? see xhost and XAUTHORITY)")]
    Connect { display: String, message: String },
    #[error("X display '{display}' has no monitor {index}; it has {count}: {list}")]
    NoSuchMonitor {
        display: String,
        index: usize,
        count: usize,
        list: String,
    },
    #[error("X display '{display}': the root window's visual is {class}, not TrueColor, so exact RGB cannot be shown")]
    NotTrueColor { display: String, class: String },
    #[error("X display '{display}': {what} failed: {message}")]
    Protocol {
        display: String,
        what: &'static str,
        message: String,
    },
}

/// A monitor as the X server lays it out.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Monitor {
    /// RandR output name (`DP-1`, `HDMI-0`), or `screen` without RandR.
    pub name: String,
    pub x: i16,
    pub y: i16,
    pub width: u16,
    pub height: u16,
    pub primary: bool,
    /// RandR outputs driving it (empty without RandR).
    pub outputs: Vec<u32>,
}

impl std::fmt::Display for Monitor {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} {}×{}+{}+{}{}",
            self.name,
            self.width,
            self.height,
            self.x,
            self.y,
            if self.primary { " (primary)" } else { "" }
        )
    }
}

/// Wait before measuring a freshly shown patch: LCD pixels take tens of milliseconds to
/// settle, a compositor adds a frame or two, and some panels' backlight regulation longer.
pub const DEFAULT_SETTLE: Duration = Duration::from_millis(500);

/// A full-screen window on one monitor of an X display.
pub struct WindowDisplay {
    conn: RustConnection,
    display: String,
    root: u32,
    window: u32,
    cursor: u32,
    monitor_index: usize,
    monitor: Monitor,
    format: PixelFormat,
    /// The root window's depth, which the window has (its pixmaps need it too).
    depth: u8,
    shown: [u8; 3],
    /// The image last given to `show_image`, and the slide it is on screen at (None while
    /// a colour covers it), so a slide is made from the image as given.
    given: Option<(Drive8Image, Option<[i64; 2]>)>,
}

impl WindowDisplay {
    /// Opens a black full-screen window on monitor `index` (0 = the first the server
    /// lists) of X display `display`, or of `$DISPLAY` when None.
    pub fn open(display: Option<&str>, index: usize) -> Result<WindowDisplay, WindowError> {
        let (conn, display, screen_num) = connect(display)?;
        let screen = conn.setup().roots[screen_num].clone();
        let format = pixel_format(&conn, &screen, &display)?;
        let monitors = monitors_of(&conn, &screen, &display)?;
        let monitor = monitors
            .get(index)
            .cloned()
            .ok_or_else(|| WindowError::NoSuchMonitor {
                display: display.clone(),
                index,
                count: monitors.len(),
                list: monitors
                    .iter()
                    .enumerate()
                    .map(|(i, m)| format!("{i}: {m}"))
                    .collect::<Vec<_>>()
                    .join(", "),
            })?;

        let cursor = invisible_cursor(&conn, screen.root, &display)?;

        let window = conn
            .generate_id()
            .map_err(perr(&display, "allocating an id"))?;
        // Override-redirect: the window manager neither decorates nor moves it, so it
        // covers exactly the monitor's rectangle.
        let aux = CreateWindowAux::new()
            .background_pixel(format.encode([0; 3]))
            .override_redirect(1)
            .cursor(cursor);
        conn.create_window(
            x11rb::COPY_DEPTH_FROM_PARENT,
            window,
            screen.root,
            monitor.x,
            monitor.y,
            monitor.width,
            monitor.height,
            0,
            WindowClass::INPUT_OUTPUT,
            x11rb::COPY_FROM_PARENT,
            &aux,
        )
        .map_err(perr(&display, "CreateWindow"))?
        .check()
        .map_err(perr(&display, "CreateWindow"))?;
        conn.change_property8(
            x11rb::protocol::xproto::PropMode::REPLACE,
            window,
            x11rb::protocol::xproto::AtomEnum::WM_NAME,
            x11rb::protocol::xproto::AtomEnum::STRING,
            b"metamer characterize",
        )
        .map_err(perr(&display, "ChangeProperty"))?;
        conn.map_window(window)
            .map_err(perr(&display, "MapWindow"))?
            .check()
            .map_err(perr(&display, "MapWindow"))?;
        let mut this = WindowDisplay {
            conn,
            display,
            root: screen.root,
            window,
            cursor,
            monitor_index: index,
            monitor,
            format,
            depth: screen.root_depth,
            shown: [0; 3],
            given: None,
        };
        this.show_rgb([0; 3])?;
        Ok(this)
    }

    /// The monitor the window covers.
    pub fn monitor(&self) -> &Monitor {
        &self.monitor
    }

    /// How the server packs pixels.
    pub fn pixel_format(&self) -> PixelFormat {
        self.format
    }

    /// Shows `rgb` and returns once the server has painted it (a round trip).
    pub fn show_rgb(&mut self, rgb: [u8; 3]) -> Result<(), WindowError> {
        let pixel = self.format.encode(rgb);
        self.conn
            .change_window_attributes(
                self.window,
                &ChangeWindowAttributesAux::new().background_pixel(pixel),
            )
            .map_err(perr(&self.display, "ChangeWindowAttributes"))?;
        // Stay on top of anything mapped since (notifications, other override-redirects).
        self.conn
            .configure_window(
                self.window,
                &ConfigureWindowAux::new().stack_mode(StackMode::ABOVE),
            )
            .map_err(perr(&self.display, "ConfigureWindow"))?;
        self.conn
            .clear_area(false, self.window, 0, 0, 0, 0)
            .map_err(perr(&self.display, "ClearArea"))?
            .check()
            .map_err(perr(&self.display, "ClearArea"))?;
        self.shown = rgb;
        if let Some((_, on_screen)) = &mut self.given {
            *on_screen = None;
        }
        Ok(())
    }

    /// The drive values shown now.
    pub fn shown(&self) -> [u8; 3] {
        self.shown
    }

    /// What the screen shows over the monitor's rectangle, read back from the root window
    /// (GetImage), row by row as 8-bit RGB.
    pub fn screenshot(&self) -> Result<Vec<[u8; 3]>, WindowError> {
        let m = &self.monitor;
        let reply = self
            .conn
            .get_image(
                ImageFormat::Z_PIXMAP,
                self.root,
                m.x,
                m.y,
                m.width,
                m.height,
                !0,
            )
            .map_err(perr(&self.display, "GetImage"))?
            .reply()
            .map_err(perr(&self.display, "GetImage"))?;
        self.format
            .decode_image(&reply.data, m.width.into(), m.height.into())
            .ok_or_else(|| WindowError::Protocol {
                display: self.display.clone(),
                what: "GetImage",
                message: format!(
                    "{} bytes do not hold a {}×{} image of {} bits per pixel",
                    reply.data.len(),
                    m.width,
                    m.height,
                    self.format.bits_per_pixel
                ),
            })
    }
}

/// A CRTC's video LUT (RandR gamma ramp): what the graphics card does to the drive values
/// on their way to the panel, 16-bit per entry.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct VideoLut {
    pub red: Vec<u16>,
    pub green: Vec<u16>,
    pub blue: Vec<u16>,
}

impl VideoLut {
    /// Largest departure from the identity ramp (entry i of n = i·65535/(n − 1)), as a
    /// fraction of full scale.
    pub fn max_deviation(&self) -> f64 {
        [&self.red, &self.green, &self.blue]
            .iter()
            .flat_map(|ramp| {
                let n = ramp.len().max(2) - 1;
                ramp.iter().enumerate().map(move |(i, &v)| {
                    (f64::from(v) - 65535.0 * i as f64 / n as f64).abs() / 65535.0
                })
            })
            .fold(0.0, f64::max)
    }
}

/// A video LUT departing from identity by more than this is reported: a 1 % change is
/// about one 8-bit code, more than the meter's repeatability at mid grey.
pub const VIDEO_LUT_TOLERANCE: f64 = 0.01;

impl WindowDisplay {
    /// The video LUT of the first CRTC showing this monitor, None when the server has no
    /// RandR CRTC for it (no RandR 1.5, or a virtual output).
    pub fn video_lut(&self) -> Result<Option<VideoLut>, WindowError> {
        for &output in &self.monitor.outputs {
            let info = self
                .conn
                .randr_get_output_info(output, x11rb::CURRENT_TIME)
                .map_err(perr(&self.display, "RRGetOutputInfo"))?
                .reply()
                .map_err(perr(&self.display, "RRGetOutputInfo"))?;
            if info.crtc == 0 {
                continue;
            }
            let gamma = self
                .conn
                .randr_get_crtc_gamma(info.crtc)
                .map_err(perr(&self.display, "RRGetCrtcGamma"))?
                .reply()
                .map_err(perr(&self.display, "RRGetCrtcGamma"))?;
            // Servers without hardware gamma (Xvfb) answer with an all-zero ramp they do not
            // apply; a real all-zero LUT would show nothing at all.
            let all = gamma.red.iter().chain(&gamma.green).chain(&gamma.blue);
            if gamma.red.is_empty() || all.clone().all(|&v| v == 0) {
                continue;
            }
            return Ok(Some(VideoLut {
                red: gamma.red,
                green: gamma.green,
                blue: gamma.blue,
            }));
        }
        Ok(None)
    }
}

impl Drop for WindowDisplay {
    fn drop(&mut self) {
        // Best effort: the server removes both when the connection closes anyway.
        let _ = self.conn.destroy_window(self.window);
        let _ = self.conn.free_cursor(self.cursor);
        let _ = self.conn.flush();
    }
}

impl Screen for WindowDisplay {
    fn show(&mut self, rgb: [u8; 3]) -> Result<(), ScreenError> {
        self.show_rgb(rgb).map_err(|e| ScreenError::Backend {
            screen: self.spec(),
            source: Box::new(e),
        })
    }

    fn spec(&self) -> String {
        format!("window:{}", self.monitor_index)
    }

    fn describe(&self) -> String {
        format!(
            "full-screen window on monitor {} ({}) of X display '{}'",
            self.monitor_index, self.monitor, self.display
        )
    }

    fn show_image(&mut self, image: &Drive8Image) -> Result<Placement, ScreenError> {
        let placement = self.show_scaled(image).map_err(|e| ScreenError::Backend {
            screen: self.spec(),
            source: Box::new(e),
        })?;
        self.given = Some((image.clone(), Some([0, 0])));
        Ok(placement)
    }

    fn shift_image(&mut self, by: [i64; 2]) -> Result<(), ScreenError> {
        let Some((image, now)) = &self.given else {
            return Err(ScreenError::NoImage {
                screen: self.spec(),
            });
        };
        // Repeated readings of one spot slide by the same amount: the picture stays.
        if *now == Some(by) {
            return Ok(());
        }
        let slid = image.shifted(by);
        self.show_scaled(&slid).map_err(|e| ScreenError::Backend {
            screen: self.spec(),
            source: Box::new(e),
        })?;
        if let Some((_, now)) = &mut self.given {
            *now = Some(by);
        }
        Ok(())
    }

    fn default_settle(&self) -> Duration {
        DEFAULT_SETTLE
    }

    fn warnings(&self) -> Vec<String> {
        match self.video_lut() {
            Ok(Some(lut)) if lut.max_deviation() > VIDEO_LUT_TOLERANCE => vec![format!(
                "the video LUT of monitor {} departs from identity by up to {:.1} % of full scale \
                 (a calibration loader or night-light filter is active); the profile will include it",
                self.monitor_index,
                100.0 * lut.max_deviation()
            )],
            // No LUT to read, or one we could not read: nothing to say.
            _ => Vec::new(),
        }
    }

    fn stimulus(&self) -> Option<std::sync::Arc<dyn metamer_drivers::World>> {
        None
    }
}

/// The monitors of X display `display` (or `$DISPLAY`), in the server's order.
pub fn list_monitors(display: Option<&str>) -> Result<Vec<Monitor>, WindowError> {
    let (conn, display, screen_num) = connect(display)?;
    let screen = conn.setup().roots[screen_num].clone();
    monitors_of(&conn, &screen, &display)
}

/// An invisible pointer: a 1×1 cursor whose mask pixel is 0, so the pointer parked in the
/// middle of the screen does not stand in front of the meter.
fn invisible_cursor(conn: &RustConnection, root: u32, display: &str) -> Result<u32, WindowError> {
    let pixmap = conn
        .generate_id()
        .map_err(perr(display, "allocating an id"))?;
    conn.create_pixmap(1, pixmap, root, 1, 1)
        .map_err(perr(display, "CreatePixmap"))?;
    let gc = conn
        .generate_id()
        .map_err(perr(display, "allocating an id"))?;
    conn.create_gc(gc, pixmap, &CreateGCAux::new().foreground(0))
        .map_err(perr(display, "CreateGC"))?;
    conn.poly_fill_rectangle(
        pixmap,
        gc,
        &[Rectangle {
            x: 0,
            y: 0,
            width: 1,
            height: 1,
        }],
    )
    .map_err(perr(display, "PolyFillRectangle"))?;
    let cursor = conn
        .generate_id()
        .map_err(perr(display, "allocating an id"))?;
    conn.create_cursor(cursor, pixmap, pixmap, 0, 0, 0, 0, 0, 0, 0, 0)
        .map_err(perr(display, "CreateCursor"))?;
    conn.free_gc(gc).map_err(perr(display, "FreeGC"))?;
    conn.free_pixmap(pixmap)
        .map_err(perr(display, "FreePixmap"))?;
    Ok(cursor)
}

fn connect(display: Option<&str>) -> Result<(RustConnection, String, usize), WindowError> {
    let display = match display {
        Some(d) => d.to_string(),
        None => std::env::var("DISPLAY")
            .ok()
            .filter(|d| !d.is_empty())
            .ok_or(WindowError::NoDisplay)?,
    };
    let (conn, screen) = x11rb::connect(Some(&display)).map_err(|e| WindowError::Connect {
        display: display.clone(),
        message: e.to_string(),
    })?;
    Ok((conn, display, screen))
}

/// `map_err` adapter: the X request `what` failed on `display`.
fn perr<'a, E: std::fmt::Display>(
    display: &'a str,
    what: &'static str,
) -> impl FnOnce(E) -> WindowError + 'a {
    move |e| WindowError::Protocol {
        display: display.to_string(),
        what,
        message: e.to_string(),
    }
}

fn pixel_format(
    conn: &RustConnection,
    screen: &x11rb::protocol::xproto::Screen,
    display: &str,
) -> Result<PixelFormat, WindowError> {
    let visual = screen
        .allowed_depths
        .iter()
        .flat_map(|d| &d.visuals)
        .find(|v| v.visual_id == screen.root_visual)
        .ok_or_else(|| WindowError::Protocol {
            display: display.to_string(),
            what: "reading the root visual",
            message: "the root visual is not among the screen's visuals".into(),
        })?;
    if visual.class != VisualClass::TRUE_COLOR && visual.class != VisualClass::DIRECT_COLOR {
        return Err(WindowError::NotTrueColor {
            display: display.to_string(),
            class: format!("{:?}", visual.class),
        });
    }
    let setup = conn.setup();
    let format = setup
        .pixmap_formats
        .iter()
        .find(|f| f.depth == screen.root_depth)
        .ok_or_else(|| WindowError::Protocol {
            display: display.to_string(),
            what: "reading the pixmap formats",
            message: format!("no image format for depth {}", screen.root_depth),
        })?;
    Ok(PixelFormat {
        masks: [visual.red_mask, visual.green_mask, visual.blue_mask],
        bits_per_pixel: format.bits_per_pixel,
        scanline_pad: format.scanline_pad,
        big_endian: setup.image_byte_order == ImageOrder::MSB_FIRST,
    })
}

fn monitors_of(
    conn: &RustConnection,
    screen: &x11rb::protocol::xproto::Screen,
    display: &str,
) -> Result<Vec<Monitor>, WindowError> {
    let mut monitors = Vec::new();
    let has_randr = conn
        .extension_information(randr::X11_EXTENSION_NAME)
        .map_err(perr(display, "QueryExtension RANDR"))?
        .is_some();
    if has_randr {
        let version = conn
            .randr_query_version(1, 5)
            .map_err(perr(display, "RRQueryVersion"))?
            .reply()
            .map_err(perr(display, "RRQueryVersion"))?;
        if (version.major_version, version.minor_version) >= (1, 5) {
            let reply = conn
                .randr_get_monitors(screen.root, true)
                .map_err(perr(display, "RRGetMonitors"))?
                .reply()
                .map_err(perr(display, "RRGetMonitors"))?;
            for m in reply.monitors {
                let name = conn
                    .get_atom_name(m.name)
                    .map_err(perr(display, "GetAtomName"))?
                    .reply()
                    .map_err(perr(display, "GetAtomName"))?;
                monitors.push(Monitor {
                    name: String::from_utf8_lossy(&name.name).into_owned(),
                    x: m.x,
                    y: m.y,
                    width: m.width,
                    height: m.height,
                    primary: m.primary,
                    outputs: m.outputs,
                });
            }
        }
    }
    if monitors.is_empty() {
        monitors.push(Monitor {
            name: "screen".into(),
            x: 0,
            y: 0,
            width: screen.width_in_pixels,
            height: screen.height_in_pixels,
            primary: true,
            outputs: Vec::new(),
        });
    }
    Ok(monitors)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn video_lut_deviation_from_identity() {
        let identity: Vec<u16> = (0..256u32).map(|i| (i * 65535 / 255) as u16).collect();
        let lut = VideoLut {
            red: identity.clone(),
            green: identity.clone(),
            blue: identity.clone(),
        };
        // Integer truncation leaves < 1/65535 of full scale.
        assert!(lut.max_deviation() < 1.0 / 65535.0);
        // Night light: blue at 80 % of full scale, the worst entry at the top.
        let dimmed = VideoLut {
            blue: identity
                .iter()
                .map(|&v| (f64::from(v) * 0.8) as u16)
                .collect(),
            ..lut
        };
        assert!((dimmed.max_deviation() - 0.2).abs() < 1e-4);
    }
}
