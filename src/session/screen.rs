//! The screen a session shows drive values on, kept to the one thing the engine needs so
//! sessions do not depend on how displays are built.

use crate::rig;

/// Something that shows 8-bit drive values over the measured area.
pub trait Screen {
    fn show(&mut self, rgb: [u8; 3]) -> Result<(), Box<dyn std::error::Error + Send + Sync>>;
}

/// A rig screen as a session's screen.
pub struct DisplayScreen<'a>(pub &'a mut dyn rig::Screen);

impl Screen for DisplayScreen<'_> {
    fn show(&mut self, rgb: [u8; 3]) -> Result<(), Box<dyn std::error::Error + Send + Sync>> {
        self.0.show(rgb).map_err(Into::into)
    }
}
