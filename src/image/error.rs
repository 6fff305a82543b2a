//! What is wrong with an image or its file: one error for the XYZ files (PFM, OpenEXR, the
//! sRGB preview), the drive values' PNG and an image's size.
//!
//! Two variants each for I/O and PNG keep the words users have seen: the XYZ files name the
//! file and the cause (`Io`), a PNG to show says it was being read (`Read`); writing a PNG
//! names the format (`Png`), reading one says why a screen cannot show it
//! (`NotShowablePng`).

use std::path::PathBuf;

use super::xyz::MAX_PIXELS;
use crate::output::OutputError;

#[derive(Debug, thiserror::Error)]
pub enum ImageError {
    /// Reading or writing an XYZ image file.
    #[error("{file}: {source}")]
    Io {
        file: PathBuf,
        source: std::io::Error,
    },
    /// Opening a PNG of drive values to show.
    #[error("reading {}: {source}", file.display())]
    Read {
        file: PathBuf,
        source: std::io::Error,
    },
    #[error("{file}: not a colour PFM: {message}")]
    Pfm { file: PathBuf, message: String },
    #[error("{file}: {message}")]
    Exr { file: PathBuf, message: String },
    /// A PNG (the sRGB preview or the drive values) that cannot be encoded.
    #[error("{file}: PNG: {message}")]
    Png { file: PathBuf, message: String },
    /// A file that is not an 8-bit RGB PNG, which is what a screen shows.
    #[error("{}: not a PNG image a screen can show: {message}", file.display())]
    NotShowablePng { file: PathBuf, message: String },
    #[error("{file}: unknown image type (use .pfm or .exr)")]
    UnknownType { file: PathBuf },
    #[error("{0}")]
    Output(#[from] OutputError),
    #[error(
        "{file}: {width}×{height} pixels is more than this reader accepts ({MAX_PIXELS} pixels); \
         the header is corrupt or the image is not one metamer rendered"
    )]
    TooLarge {
        file: PathBuf,
        width: usize,
        height: usize,
    },
    #[error("{file}: pixel ({x}, {y}) (from the top left) is {value:?}, not a finite XYZ")]
    NotFinite {
        file: PathBuf,
        x: usize,
        y: usize,
        value: [f32; 3],
    },
    /// Pixels that do not fill the image's size.
    #[error("an image of {width}×{height} pixels needs {need} pixel values, got {got}")]
    Size {
        width: usize,
        height: usize,
        need: usize,
        got: usize,
    },
}
