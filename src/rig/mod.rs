//! The rig: the devices in front of the instruments, real and simulated. A screen shows
//! uniform colours to be measured (a full-screen window on a monitor, or a simulated
//! monitor); display mathematics (models, fitting, reproduction) stays in `display`.

pub mod scenario;
pub mod sim_meter;
pub mod spec;
pub mod virtual_display;
pub mod window;

pub use crate::session::screen::{MeterAim, Placement, Screen, ScreenError};
pub use scenario::Scenario;
pub use spec::{OpenError, ScreenSpec};
pub use virtual_display::{Preset, VirtualDisplay, VirtualPanel};
