//! Images and their files, for every part of the chain that holds one.
//!
//! Two kinds of image travel through the chain: the renderer's XYZ image of the camera
//! (absolute cd/m², 32-bit floats; [`XyzImage`]), written and read back as PFM or OpenEXR
//! with an sRGB PNG preview, and the reproduction's drive values (8-bit RGB; [`Drive8Image`]),
//! read from the PNG a screen shows. Both renderers produce the first, the display's
//! reproduction turns it into the second and the rig shows that; living here, below
//! `render`, `display` and `rig`, the images are shared without any of them importing
//! another for its pixels. One error, [`ImageError`], says what is wrong with an image or
//! its file.

mod chromaticities;
mod error;
mod exr_header;
mod exr_layout;
#[cfg(test)]
mod foreign_exr_tests;
mod rgb;
mod xyz;
mod xyz_file;

pub use chromaticities::{Chromaticities, XYZ_CHROMATICITIES};
pub use error::ImageError;
pub use exr_header::REC709_CHROMATICITIES;
pub use rgb::{Drive8Image, ScreenSpot};
pub use xyz::{XyzImage, MAX_PIXELS};
pub use xyz_file::{read_xyz_image, write_srgb_preview, write_xyz_image};
