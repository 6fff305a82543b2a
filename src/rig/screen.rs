//! A screen: one trait for "show exactly these 8-bit drive values on the measured area",
//! implemented by a real full-screen window on a monitor (`window[:N]`, see
//! [`super::window`]) and by a simulated monitor that the simulated instruments measure
//! (`virtual[:PRESET]`, see [`super::virtual_display`]). Opening one by name is
//! [`super::spec`]'s job, so this trait depends on none of its implementations.

use std::sync::Arc;
use std::time::Duration;

use metamer_drivers::World;

/// Something that shows uniform colours in front of an instrument.
pub trait Screen {
    /// The screen as named on the command line and in logs: `virtual:ips-lcd`, `window:0`.
    fn spec(&self) -> String;
    /// A longer human description (monitor name and geometry, preset parameters).
    fn describe(&self) -> String;
    /// Shows the 8-bit drive values `rgb` over the whole measured area. Returns once the
    /// display system has the new colour, which is before a physical panel has settled:
    /// the caller waits [`Screen::default_settle`] (or the user's choice) before measuring.
    fn show(&mut self, rgb: [u8; 3]) -> Result<(), ScreenError>;
    /// The wait between showing a colour and measuring it when the user gives none.
    fn default_settle(&self) -> Duration;
    /// Conditions the user should know before measuring (e.g. an active video LUT).
    fn warnings(&self) -> Vec<String> {
        Vec::new()
    }
    /// What a simulated instrument aimed at this screen sees, for screens that are
    /// themselves simulated; `None` for real screens.
    fn stimulus(&self) -> Option<Arc<dyn World>>;
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
}
