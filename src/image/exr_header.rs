//! What an OpenEXR header says the pixels mean: which channels hold the colour and in which
//! space, the cd/m² of a value of 1, and which of the stored pixels make the picture. Every
//! reader of an XYZ image goes through [`meaning`], so an attribute that changes what a
//! pixel is cannot be honoured by one command and ignored by another.
//!
//! The attributes (OpenEXR "Technical Introduction", "Standard Optional Attributes"):
//!
//! - `dataWindow` is the rectangle of pixels stored, `displayWindow` the picture's frame;
//!   both are inclusive pixel bounds in one plane and may differ. A data window inside the
//!   display window is a crop (pbrt-v4's `cropwindow` and `pixelbounds` write one, keeping
//!   the full frame as the display window); one that encloses it holds overscan.
//! - `chromaticities`: the CIE xy of the RGB primaries and of the white (1, 1, 1). Absent,
//!   they are those of ITU-R BT.709-3 with the D65 white: "If a file doesn't have a
//!   chromaticities attribute, display software should assume that the file's primaries
//!   and the white point match Rec. ITU-R BT.709-3" (the `exr` crate's documentation of
//!   the attribute), and OpenEXR's `Imf::Chromaticities` defaults to red (0.64, 0.33),
//!   green (0.30, 0.60), blue (0.15, 0.06), white (0.3127, 0.3290) (`ImfChromaticities.h`).
//!   Mitsuba 3's `hdrfilm` writes linear sRGB (the same primaries and white) without the
//!   attribute.
//! - `whiteLuminance`: "for RGB images, the luminance, in Nits (candelas per square meter)
//!   of the RGB value (1.0, 1.0, 1.0)". The chromaticities' matrix gives (1, 1, 1) Y = 1,
//!   so absolute XYZ is that matrix times the pixel times `whiteLuminance`.
//! - `pixelAspectRatio`: a pixel's width over its height; the camera's frame is made of
//!   square pixels.

use super::chromaticities::{Chromaticities, XYZ_CHROMATICITIES};

/// ITU-R BT.709-3's primaries and D65, the space of an RGB file that names none.
pub const REC709_CHROMATICITIES: Chromaticities = Chromaticities {
    red: [0.64, 0.33],
    green: [0.30, 0.60],
    blue: [0.15, 0.06],
    white: [0.3127, 0.3290],
};

/// Which channels of an OpenEXR part hold the XYZ, and how.
#[derive(Clone, Copy, Debug)]
pub(super) enum ExrChannels {
    /// Channels named X, Y, Z (Mitsuba 3's `specfilm` with those names, its `hdrfilm`'s
    /// `xyz` format).
    Xyz,
    /// R, G, B: XYZ itself (XYZ's chromaticities), or RGB to convert by the matrix its
    /// `chromaticities` attribute (or their BT.709 default) defines.
    Rgb(Option<[[f64; 3]; 3]>),
}

/// The display window's place in the stored pixels: the data window's pixels from
/// (`x`, `y`) on, `width` × `height` of them, are the picture.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) struct Frame {
    pub x: usize,
    pub y: usize,
    pub width: usize,
    pub height: usize,
}

/// What a part's pixels mean.
#[derive(Clone, Copy, Debug)]
pub(super) struct Meaning {
    pub channels: ExrChannels,
    /// cd/m² of a value of 1 after the channels' conversion (`whiteLuminance`, or 1).
    pub scale: f64,
    /// The picture inside the stored pixels.
    pub frame: Frame,
}

/// An OpenEXR window as the format states it: inclusive minimum and maximum.
fn window(position: exr::math::Vec2<i32>, size: exr::math::Vec2<usize>) -> String {
    let end = |p: i32, s: usize| i64::from(p) + s as i64 - 1;
    format!(
        "({}, {})–({}, {})",
        position.x(),
        position.y(),
        end(position.x(), size.width()),
        end(position.y(), size.height())
    )
}

/// The meaning of `header`'s pixels, or why they cannot be read as absolute XYZ of the
/// camera's whole frame.
pub(super) fn meaning(header: &exr::meta::header::Header) -> Result<Meaning, String> {
    let channels = channels(header)?;
    let aspect = header.shared_attributes.pixel_aspect;
    if (aspect - 1.0).abs() > 1e-6 {
        return Err(format!(
            "its pixelAspectRatio is {aspect}: its pixels are not square, and the camera's \
             frame is made of square pixels"
        ));
    }
    let scale = match (header.own_attributes.white_luminance, channels) {
        (None, _) => 1.0,
        (Some(w), _) if !(w.is_finite() && w > 0.0) => {
            return Err(format!(
                "its whiteLuminance is {w}: the luminance of a white must be a positive number \
                 of cd/m²"
            ))
        }
        (Some(w), ExrChannels::Rgb(_)) => f64::from(w),
        (Some(w), ExrChannels::Xyz) if (w - 1.0).abs() <= 1e-6 => 1.0,
        (Some(w), ExrChannels::Xyz) => {
            return Err(format!(
                "its whiteLuminance is {w}, which OpenEXR defines for RGB images only, but its \
                 channels are X, Y, Z: whether a value of 1 is 1 cd/m² or {w} cd/m² is not \
                 stated"
            ))
        }
    };
    Ok(Meaning {
        channels,
        scale,
        frame: frame(header)?,
    })
}

/// The display window inside the data window, or why the file does not hold all of it.
fn frame(header: &exr::meta::header::Header) -> Result<Frame, String> {
    let data_at = header.own_attributes.layer_position;
    let data_size = header.layer_size;
    let display = header.shared_attributes.display_window;
    let x = i64::from(display.position.x()) - i64::from(data_at.x());
    let y = i64::from(display.position.y()) - i64::from(data_at.y());
    let (width, height) = (display.size.width(), display.size.height());
    let inside = x >= 0
        && y >= 0
        && x as u64 + width as u64 <= data_size.width() as u64
        && y as u64 + height as u64 <= data_size.height() as u64;
    if !inside {
        return Err(format!(
            "its data window {} does not cover its display window {}: the file holds part of \
             the camera's frame (a crop render, such as pbrt-v4's cropwindow or pixelbounds), \
             and a reading or a reproduction needs the whole frame; render it without the crop",
            window(data_at, data_size),
            window(display.position, display.size)
        ));
    }
    Ok(Frame {
        x: x as usize,
        y: y as usize,
        width,
        height,
    })
}

/// The layout of a part's channels, or why it cannot be read as XYZ.
fn channels(header: &exr::meta::header::Header) -> Result<ExrChannels, String> {
    let has = |name: &str| header.channels.list.iter().any(|c| c.name.eq(name));
    let stated = header
        .shared_attributes
        .chromaticities
        .map(|c| Chromaticities {
            red: [f64::from(c.red.0), f64::from(c.red.1)],
            green: [f64::from(c.green.0), f64::from(c.green.1)],
            blue: [f64::from(c.blue.0), f64::from(c.blue.1)],
            white: [f64::from(c.white.0), f64::from(c.white.1)],
        });
    let is_xyz = |c: &Chromaticities| {
        let near =
            |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).abs() < 1e-6 && (a[1] - b[1]).abs() < 1e-6;
        let x = XYZ_CHROMATICITIES;
        near(c.red, x.red)
            && near(c.green, x.green)
            && near(c.blue, x.blue)
            && near(c.white, x.white)
    };
    if has("X") && has("Y") && has("Z") {
        return match stated {
            Some(c) if !is_xyz(&c) => Err(format!(
                "names its channels X, Y, Z but its chromaticities say RGB with primaries R \
                 {:?}, G {:?}, B {:?} (white {:?})",
                c.red, c.green, c.blue, c.white
            )),
            _ => Ok(ExrChannels::Xyz),
        };
    }
    if !(has("R") && has("G") && has("B")) {
        let names: Vec<String> = header
            .channels
            .list
            .iter()
            .map(|c| metamer_color::text::echo(&c.name.to_string()))
            .collect();
        return Err(format!(
            "has the channels {} — an XYZ image needs X, Y, Z, or R, G, B with the \
             chromaticities they hold",
            names.join(", ")
        ));
    }
    let c = stated.unwrap_or(REC709_CHROMATICITIES);
    if is_xyz(&c) {
        return Ok(ExrChannels::Rgb(None));
    }
    c.rgb_to_xyz()
        .map(|m| ExrChannels::Rgb(Some(m)))
        .ok_or_else(|| {
            format!(
                "holds RGB whose chromaticities (R {:?}, G {:?}, B {:?}, white {:?}) define no \
                 conversion to XYZ",
                c.red, c.green, c.blue, c.white
            )
        })
}
