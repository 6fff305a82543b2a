//! The screen a session shows drive values on: the one thing the engine needs from a
//! display, and the supertrait of the rig's screens (`rig::Screen`), so every screen a
//! rig opens is one and a session depends on no screen's implementation.

/// Something that shows 8-bit drive values over the measured area.
pub trait Screen {
    /// Shows the 8-bit drive values `rgb` over the whole measured area. Returns once the
    /// display system has the new colour, which is before a physical panel has settled:
    /// the caller waits the screen's settle time (or the user's choice) before measuring.
    fn show(&mut self, rgb: [u8; 3]) -> Result<(), ScreenError>;
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
