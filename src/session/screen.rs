//! The screen: one trait for "show exactly these 8-bit drive values on the measured area"
//! (or a whole 8-bit image, for spot readings aimed at its parts). The session engine shows
//! its steps' colours on it; the rig implements it by a real full-screen window on a monitor
//! (`window[:N]`, `rig::window`) and by a simulated monitor that the simulated instruments
//! measure (`virtual[:PRESET]`, `rig::virtual_display`). It lives with the engine, below
//! the rig, so a session depends on no screen's implementation.

use std::sync::{Arc, RwLock};
use std::time::Duration;

use metamer_drivers::World;

use crate::image::{Drive8Image, ScreenSpot};

/// Where an image landed on a screen, as fractions of the screen's width and height: its
/// left and top edges and its width and height (the whole screen, or less when the image
/// was scaled to fit a screen of another shape).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placement {
    pub left: f64,
    pub top: f64,
    pub width: f64,
    pub height: f64,
}

impl Placement {
    pub const WHOLE: Placement = Placement {
        left: 0.0,
        top: 0.0,
        width: 1.0,
        height: 1.0,
    };

    /// The screen spot of a spot given in fractions of the image.
    pub fn on_screen(&self, in_image: ScreenSpot) -> ScreenSpot {
        ScreenSpot {
            x: self.left + self.width * in_image.x,
            y: self.top + self.height * in_image.y,
            radius: self.height * in_image.radius,
        }
    }
}

/// Where a simulated meter looks at a simulated screen, shared by the screen (which emits
/// what lies under the spot) and whoever aims the meter (a simulated operator). No aim:
/// the meter sees the mean of the whole screen.
#[derive(Clone, Debug, Default)]
pub struct MeterAim(Arc<RwLock<Option<ScreenSpot>>>);

impl MeterAim {
    pub fn set(&self, spot: Option<ScreenSpot>) {
        *self.0.write().unwrap_or_else(|e| e.into_inner()) = spot;
    }

    pub fn get(&self) -> Option<ScreenSpot> {
        *self.0.read().unwrap_or_else(|e| e.into_inner())
    }
}

/// Something that shows uniform colours (and images) in front of an instrument: what a
/// session's steps show drive values on, with what opening, describing and aiming at a real
/// or simulated monitor needs.
pub trait Screen {
    /// Shows the 8-bit drive values `rgb` over the whole measured area. Returns once the
    /// display system has the new colour, which is before a physical panel has settled:
    /// the caller waits the screen's settle time (or the user's choice) before measuring.
    fn show(&mut self, rgb: [u8; 3]) -> Result<(), ScreenError>;
    /// The screen as named on the command line and in logs: `virtual:ips-lcd`, `window:0`.
    fn spec(&self) -> String;
    /// A longer human description (monitor name and geometry, preset parameters).
    fn describe(&self) -> String;
    /// Shows `image` full-screen, scaled to fit with its aspect ratio kept (black around
    /// it); returns where it landed. The same wait as after showing a colour
    /// ([`Screen::show`]) applies: [`Screen::default_settle`].
    fn show_image(&mut self, image: &Drive8Image) -> Result<Placement, ScreenError>;
    /// Shows the image last given to [`Screen::show_image`] slid `by` of its own pixels
    /// (right, down) within the area it was given, as [`Drive8Image::shifted`] slides it:
    /// what leaves the area is not shown, what the slide uncovers is black. Not
    /// cumulative: `[0, 0]` shows it where `show_image` put it. The same wait as after
    /// showing a colour applies.
    fn shift_image(&mut self, by: [i64; 2]) -> Result<(), ScreenError>;
    /// The wait between showing a colour and measuring it when the user gives none.
    fn default_settle(&self) -> Duration;
    /// Conditions the user should know before measuring (e.g. an active video LUT).
    fn warnings(&self) -> Vec<String> {
        Vec::new()
    }
    /// What a simulated instrument aimed at this screen sees, for screens that are
    /// themselves simulated; `None` for real screens.
    fn stimulus(&self) -> Option<Arc<dyn World>>;
    /// For simulated screens: where the simulated meter of [`Screen::stimulus`] is aimed;
    /// `None` for real screens, where a person aims a real meter.
    fn meter_aim(&self) -> Option<MeterAim> {
        None
    }
    /// The luminance (cd/m²) showing `rgb` is known to give, for a measurement's budget
    /// before it runs: a simulated monitor knows it; None for a real screen, whose
    /// response is what is being measured.
    fn expected_cd_m2(&self, rgb: [u8; 3]) -> Option<f64> {
        let _ = rgb;
        None
    }
}

/// A screen could not show a colour.
#[derive(Debug, thiserror::Error)]
pub enum ScreenError {
    /// The backend failed (the X connection broke, a request was refused); the source says
    /// how, in the backend's own terms.
    #[error("{screen}: {source}")]
    Backend {
        screen: String,
        #[source]
        source: Box<dyn std::error::Error + Send + Sync>,
    },
    /// An image was to be slid across the screen before any image was shown on it.
    #[error("{screen}: no image has been shown to slide across the screen")]
    NoImage { screen: String },
}
