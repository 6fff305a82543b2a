//! Reading and writing XYZ float images (absolute cd/m²): PFM (hand-written, the format of
//! Debevec's HDRShop: "PF" header, width height, negative scale for little-endian, rows
//! bottom to top) and OpenEXR (the `exr` crate), plus an sRGB PNG preview.
//!
//! OpenEXR has no XYZ channel layout of its own; its convention for XYZ data is R, G, B
//! channels whose `chromaticities` attribute — the CIE xy of the triples (1,0,0), (0,1,0),
//! (0,0,1) and (1,1,1) — is R = (1,0), G = (0,1), B = (0,0), W = (1/3,1/3): then (1,0,0) is
//! pure X, and so on. `whiteLuminance`, the cd/m² of (1,1,1), is 1 because the values are
//! cd/m² and (1,1,1) has Y = 1. A reader that honours the attributes converts to its display
//! correctly; without them it would take XYZ for Rec. 709 RGB.
//!
//! Read back are: R, G, B with these chromaticities; R, G, B with another space's
//! chromaticities, converted by the matrix they define (pbrt-v4 can only write its film's
//! RGB space and names it there), or with none, which OpenEXR defines as BT.709 with D65;
//! and channels named X, Y, Z (Mitsuba 3's XYZ films). The header's whiteLuminance scales
//! the values to cd/m², and only the display window is returned; `exr_header` interprets
//! every attribute that changes what a pixel means, for every caller.
//!
//! Every reader refuses what would make the rest of the chain lie or stall: sizes whose
//! pixel count overflows or exceeds [`MAX_PIXELS`], an OpenEXR file whose header, offset
//! table or chunk sizes do not fit its length (checked before the `exr` crate decodes, see
//! `exr_layout`), and NaN or infinite pixels.

use std::io::{BufRead, BufReader, Read};
use std::path::Path;

use super::chromaticities;
use super::error::ImageError;
use super::exr_header::{self, ExrChannels, Frame};
use super::exr_layout;
use super::xyz::{XyzImage, MAX_PIXELS};
use crate::color::{srgb_encode, xyz_to_linear_srgb};
use crate::output::OutputPolicy;

/// Largest EXR file read: [`MAX_PIXELS`] of four float channels uncompressed, and room for
/// the header and offset table.
const MAX_EXR_BYTES: u64 = (MAX_PIXELS as u64) * 16 + (1 << 20);

/// XYZ stored in R, G, B (see the module comment).
fn xyz_chromaticities() -> exr::meta::attribute::Chromaticities {
    use exr::math::Vec2;
    exr::meta::attribute::Chromaticities {
        red: Vec2(1.0, 0.0),
        green: Vec2(0.0, 1.0),
        blue: Vec2(0.0, 0.0),
        white: Vec2(1.0 / 3.0, 1.0 / 3.0),
    }
}

/// The size's pixel count, if it can be held.
fn pixel_count(file: &Path, width: usize, height: usize) -> Result<usize, ImageError> {
    width
        .checked_mul(height)
        .filter(|&n| n <= MAX_PIXELS)
        .ok_or_else(|| ImageError::TooLarge {
            file: file.to_path_buf(),
            width,
            height,
        })
}

fn check_finite(file: &Path, img: &XyzImage) -> Result<(), ImageError> {
    match img
        .pixels
        .iter()
        .position(|p| p.iter().any(|v| !v.is_finite()))
    {
        None => Ok(()),
        Some(i) => Err(ImageError::NotFinite {
            file: file.to_path_buf(),
            x: i % img.width.max(1),
            y: i / img.width.max(1),
            value: img.pixels[i],
        }),
    }
}

/// An `exr` crate error in terms of what is wrong with the file.
fn exr_error(file: &Path, e: exr::error::Error) -> ImageError {
    use exr::error::Error;
    let message = match e {
        Error::Io(io) if io.kind() == std::io::ErrorKind::UnexpectedEof => {
            "the file ends early (truncated OpenEXR file)".to_string()
        }
        Error::Io(io) => {
            return ImageError::Io {
                file: file.to_path_buf(),
                source: io,
            }
        }
        // The crate's words for an offset table pointing past the end of the data.
        Error::Invalid(m) if m.contains("missing bytes") => {
            "the file is truncated or corrupt: its table of pixel blocks points past the end of \
             the file"
                .to_string()
        }
        Error::Invalid(m) => format!(
            "not a valid OpenEXR file ({})",
            metamer_color::text::echo(&m)
        ),
        Error::NotSupported(m) => format!(
            "uses an OpenEXR feature this reader does not support ({})",
            metamer_color::text::echo(&m)
        ),
        Error::Aborted => "reading was aborted".to_string(),
    };
    ImageError::Exr {
        file: file.to_path_buf(),
        message,
    }
}

fn io(file: &Path) -> impl Fn(std::io::Error) -> ImageError + '_ {
    move |source| ImageError::Io {
        file: file.to_path_buf(),
        source,
    }
}

fn ext(path: &Path) -> String {
    path.extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase()
}

/// Writes `.pfm` or `.exr` by extension, under the output policy `out`. The image is
/// encoded in memory first, so an encoding error never touches the file.
pub fn write_xyz_image(path: &Path, img: &XyzImage, out: &OutputPolicy) -> Result<(), ImageError> {
    let bytes = match ext(path).as_str() {
        "pfm" => pfm_bytes(img),
        "exr" => {
            use exr::prelude::*;
            let channels = SpecificChannels::rgb(|Vec2(x, y)| {
                let p = img.at(x, y);
                (p[0], p[1], p[2])
            });
            let mut buf = std::io::Cursor::new(Vec::new());
            let mut image = Image::from_channels((img.width, img.height), channels);
            image.attributes.chromaticities = Some(xyz_chromaticities());
            image.layer_data.attributes.white_luminance = Some(1.0);
            // The encoder compresses chunks on several threads; with the default unspecified
            // order it writes them as they finish, so one image gave other bytes from run to
            // run (and another digest in the experiment's stage records). In increasing order
            // the file is the same every time.
            image.layer_data.encoding.line_order = LineOrder::Increasing;
            image
                .write()
                .to_buffered(&mut buf)
                .map_err(|e| exr_error(path, e))?;
            buf.into_inner()
        }
        _ => {
            return Err(ImageError::UnknownType {
                file: path.to_path_buf(),
            })
        }
    };
    Ok(out.write(path, &bytes)?)
}

/// Reads `.pfm` or `.exr` by extension.
pub fn read_xyz_image(path: &Path) -> Result<XyzImage, ImageError> {
    match ext(path).as_str() {
        "pfm" => read_pfm(path),
        "exr" => read_exr(path),
        _ => Err(ImageError::UnknownType {
            file: path.to_path_buf(),
        }),
    }
}

/// Reads an OpenEXR file whose layout [`exr_layout::check`] found safe to decode.
fn read_exr(path: &Path) -> Result<XyzImage, ImageError> {
    use exr::prelude::*;
    let bad = |message: String| ImageError::Exr {
        file: path.to_path_buf(),
        message,
    };
    let file_len = std::fs::metadata(path).map_err(io(path))?.len();
    if file_len > MAX_EXR_BYTES {
        return Err(bad(format!(
            "{file_len} bytes is more than an image this reader accepts can take \
             ({MAX_EXR_BYTES} bytes)"
        )));
    }
    let bytes = metamer_color::text::read_bytes_at_most(path, MAX_EXR_BYTES).map_err(io(path))?;
    // Our own reading of the layout first: the crate sizes buffers by what the file says.
    exr_layout::check(&bytes).map_err(bad)?;
    let meta = MetaData::read_from_buffered(std::io::Cursor::new(&bytes), false)
        .map_err(|e| exr_error(path, e))?;
    let mut meaning = None;
    for header in meta.headers.iter() {
        let size = header.layer_size;
        pixel_count(path, size.width(), size.height())?;
        if meaning.is_none() {
            meaning = Some(exr_header::meaning(header).map_err(bad)?);
        }
    }
    let meaning = meaning.ok_or_else(|| bad("holds no image".into()))?;
    fn create(res: exr::math::Vec2<usize>) -> XyzImage {
        XyzImage {
            width: res.width(),
            height: res.height(),
            pixels: vec![[0.0; 3]; res.width() * res.height()],
        }
    }
    fn set(img: &mut XyzImage, pos: exr::math::Vec2<usize>, v: [f32; 3]) {
        let w = img.width;
        img.pixels[pos.y() * w + pos.x()] = v;
    }
    let stored = match meaning.channels {
        ExrChannels::Xyz => {
            read()
                .no_deep_data()
                .largest_resolution_level()
                .specific_channels()
                .required("X")
                .required("Y")
                .required("Z")
                .collect_pixels(
                    |res, _| create(res),
                    |img: &mut XyzImage, pos, (x, y, z): (f32, f32, f32)| set(img, pos, [x, y, z]),
                )
                .first_valid_layer()
                .all_attributes()
                .from_buffered(std::io::Cursor::new(&bytes))
                .map_err(|e| exr_error(path, e))?
                .layer_data
                .channel_data
                .pixels
        }
        ExrChannels::Rgb(_) => {
            read()
                .no_deep_data()
                .largest_resolution_level()
                .rgba_channels(
                    |res, _| create(res),
                    |img: &mut XyzImage, pos, (r, g, b, _a): (f32, f32, f32, f32)| {
                        set(img, pos, [r, g, b])
                    },
                )
                .first_valid_layer()
                .all_attributes()
                .from_buffered(std::io::Cursor::new(&bytes))
                .map_err(|e| exr_error(path, e))?
                .layer_data
                .channel_data
                .pixels
        }
    };
    let mut img = in_frame(stored, meaning.frame).ok_or_else(|| {
        bad("its first image part is not the one its first header describes".into())
    })?;
    if let ExrChannels::Rgb(Some(m)) = meaning.channels {
        for p in &mut img.pixels {
            *p = chromaticities::apply(&m, *p);
        }
    }
    if meaning.scale != 1.0 {
        for p in &mut img.pixels {
            *p = p.map(|v| (f64::from(v) * meaning.scale) as f32);
        }
    }
    check_finite(path, &img)?;
    Ok(img)
}

/// The display window's pixels out of the data window's; None if the frame is not inside
/// them.
fn in_frame(stored: XyzImage, frame: Frame) -> Option<XyzImage> {
    if (frame.x, frame.y, frame.width, frame.height) == (0, 0, stored.width, stored.height) {
        return Some(stored);
    }
    if frame.x + frame.width > stored.width || frame.y + frame.height > stored.height {
        return None;
    }
    let pixels = (frame.y..frame.y + frame.height)
        .flat_map(|y| {
            let row = y * stored.width + frame.x;
            stored.pixels[row..row + frame.width].iter().copied()
        })
        .collect();
    Some(XyzImage {
        width: frame.width,
        height: frame.height,
        pixels,
    })
}

fn pfm_bytes(img: &XyzImage) -> Vec<u8> {
    let mut out = Vec::with_capacity(img.pixels.len() * 12 + 32);
    out.extend_from_slice(format!("PF\n{} {}\n-1.0\n", img.width, img.height).as_bytes());
    for y in (0..img.height).rev() {
        for x in 0..img.width {
            for c in img.at(x, y) {
                out.extend_from_slice(&c.to_le_bytes());
            }
        }
    }
    out
}

fn read_pfm(path: &Path) -> Result<XyzImage, ImageError> {
    let bad = |message: String| ImageError::Pfm {
        file: path.to_path_buf(),
        message: metamer_color::text::echo_message(&message),
    };
    let f = std::fs::File::open(path).map_err(io(path))?;
    let mut r = BufReader::new(f);
    // A PFM header is three short text lines; reading more is not reading a PFM.
    const MAX_HEADER: u64 = 256;
    let mut tokens = Vec::new();
    let mut header_bytes = 0;
    while tokens.len() < 4 {
        let mut line = Vec::new();
        let n = r
            .by_ref()
            .take(MAX_HEADER - header_bytes)
            .read_until(b'\n', &mut line)
            .map_err(io(path))?;
        if n == 0 {
            return Err(bad(if header_bytes >= MAX_HEADER {
                format!("no PF header within its first {MAX_HEADER} bytes")
            } else {
                "header ends early".into()
            }));
        }
        header_bytes += n as u64;
        let line = std::str::from_utf8(&line).map_err(|_| bad("the header is not text".into()))?;
        tokens.extend(line.split_whitespace().map(str::to_string));
    }
    if tokens[0] != "PF" {
        return Err(bad(format!("magic is '{}', expected 'PF'", tokens[0])));
    }
    let num = |s: &str| {
        s.parse::<usize>()
            .map_err(|_| bad(format!("bad size '{s}'")))
    };
    let (w, h) = (num(&tokens[1])?, num(&tokens[2])?);
    let count = pixel_count(path, w, h)?;
    let scale: f32 = tokens[3]
        .parse()
        .map_err(|_| bad(format!("bad scale '{}'", tokens[3])))?;
    if !scale.is_finite() || scale == 0.0 {
        return Err(bad(format!(
            "scale {scale} is not a finite, non-zero number"
        )));
    }
    // Read one byte more than the pixels need, so a file with trailing data is told apart
    // without reading all of it.
    let expected = count * 12;
    let mut data = Vec::new();
    r.take(expected as u64 + 1)
        .read_to_end(&mut data)
        .map_err(io(path))?;
    if data.len() != expected {
        let found = if data.len() > expected {
            "more".to_string()
        } else {
            data.len().to_string()
        };
        return Err(bad(format!(
            "{found} data bytes for {w}×{h} pixels (expected {expected})"
        )));
    }
    let mut pixels = vec![[0.0f32; 3]; count];
    for (i, chunk) in data.chunks_exact(4).enumerate() {
        let b = [chunk[0], chunk[1], chunk[2], chunk[3]];
        let v = if scale < 0.0 {
            f32::from_le_bytes(b)
        } else {
            f32::from_be_bytes(b)
        };
        let (p, c) = (i / 3, i % 3);
        let (x, yb) = (p % w, p / w);
        pixels[(h - 1 - yb) * w + x][c] = v;
    }
    let img = XyzImage {
        width: w,
        height: h,
        pixels,
    };
    check_finite(path, &img)?;
    Ok(img)
}

/// An sRGB (IEC 61966-2-1) 8-bit preview, exposed so that `white_y` maps to 1.
pub fn write_srgb_preview(
    path: &Path,
    img: &XyzImage,
    white_y: f64,
    out: &OutputPolicy,
) -> Result<(), ImageError> {
    let enc = |v: f64| (srgb_encode(v.clamp(0.0, 1.0)) * 255.0 + 0.5) as u8;
    let mut data = Vec::with_capacity(img.pixels.len() * 3);
    for p in &img.pixels {
        let linear = xyz_to_linear_srgb(p.map(|v| v as f64 / white_y));
        data.extend(linear.map(enc));
    }
    let png_err = |e: png::EncodingError| ImageError::Png {
        file: path.to_path_buf(),
        message: e.to_string(),
    };
    // Encoded in memory first: a failed encoding never leaves a partial PNG in place.
    let mut png_bytes = Vec::new();
    let mut enc = png::Encoder::new(&mut png_bytes, img.width as u32, img.height as u32);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    let mut w = enc.write_header().map_err(png_err)?;
    w.write_image_data(&data).map_err(png_err)?;
    w.finish().map_err(png_err)?;
    Ok(out.write(path, &png_bytes)?)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pfm_and_exr_round_trip() {
        let img = XyzImage {
            width: 3,
            height: 2,
            pixels: (0..6)
                .map(|i| [i as f32, 0.5 * i as f32, 100.0 + i as f32])
                .collect(),
        };
        let dir = std::env::temp_dir().join(format!("metamer-imgio-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        for name in ["a.pfm", "a.exr"] {
            let p = dir.join(name);
            write_xyz_image(&p, &img, &OutputPolicy::new(true)).unwrap();
            assert_eq!(read_xyz_image(&p).unwrap(), img, "{name}");
        }
        std::fs::remove_dir_all(&dir).ok();
    }

    /// The EXR's chunks stand in increasing order and its header says so, whatever order
    /// the encoder's threads finish them in: the same image is the same file.
    #[test]
    fn exr_chunks_are_written_in_increasing_order() {
        let (w, h) = (300, 260);
        let img = XyzImage {
            width: w,
            height: h,
            pixels: (0..w * h)
                .map(|i| [(i % 97) as f32, (i % 13) as f32 * 0.5, (i / w) as f32])
                .collect(),
        };
        let dir = std::env::temp_dir().join(format!("metamer-exrorder-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("a.exr");
        write_xyz_image(&p, &img, &OutputPolicy::new(true)).unwrap();
        let b = std::fs::read(&p).unwrap();
        std::fs::remove_dir_all(&dir).ok();
        // OpenEXR's layout: magic and version (8 bytes), then attributes (name NUL, type
        // NUL, u32 size, value) up to an empty name, then one u64 offset per chunk.
        let mut at = 8;
        let mut line_order = None;
        let cstr = |at: &mut usize| {
            let end = *at + b[*at..].iter().position(|&c| c == 0).unwrap();
            let s = String::from_utf8_lossy(&b[*at..end]).into_owned();
            *at = end + 1;
            s
        };
        loop {
            let name = cstr(&mut at);
            if name.is_empty() {
                break;
            }
            cstr(&mut at);
            let size = u32::from_le_bytes(b[at..at + 4].try_into().unwrap()) as usize;
            at += 4;
            if name == "lineOrder" {
                line_order = Some(b[at]);
            }
            at += size;
        }
        // 0 is INCREASING_Y, 2 RANDOM_Y.
        assert_eq!(line_order, Some(0));
        let chunks = w.div_ceil(64) * h.div_ceil(64);
        let offsets: Vec<u64> = (0..chunks)
            .map(|i| u64::from_le_bytes(b[at + 8 * i..at + 8 * i + 8].try_into().unwrap()))
            .collect();
        assert!(offsets.windows(2).all(|o| o[0] < o[1]), "{offsets:?}");
        // Each tile chunk starts with its tile's x and y: y never goes back.
        let ys: Vec<i32> = offsets
            .iter()
            .map(|&o| i32::from_le_bytes(b[o as usize + 4..o as usize + 8].try_into().unwrap()))
            .collect();
        assert!(ys.windows(2).all(|y| y[0] <= y[1]), "{ys:?}");
    }

    /// An encoding that fails half-way (here: fewer pixels than the size says) leaves the
    /// file it would have replaced as it was, and nothing beside it.
    #[test]
    fn a_failed_encoding_leaves_the_existing_file() {
        let dir = std::env::temp_dir().join(format!("metamer-imgfail-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("preview.png");
        std::fs::write(&p, "the earlier preview").unwrap();
        let short = XyzImage {
            width: 4,
            height: 4,
            pixels: vec![[1.0; 3]; 3],
        };
        let e = write_srgb_preview(&p, &short, 1.0, &OutputPolicy::new(true)).unwrap_err();
        assert!(matches!(e, ImageError::Png { .. }), "{e}");
        assert_eq!(std::fs::read_to_string(&p).unwrap(), "the earlier preview");
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 1);
        std::fs::remove_dir_all(&dir).ok();
    }
}
