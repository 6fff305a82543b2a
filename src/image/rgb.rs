//! An 8-bit RGB image for a screen, read from the PNG the reproduction writes, and where a
//! spot meter is aimed on it.

use std::path::Path;

use super::error::ImageError;

/// Where a spot meter is aimed on a screen (or an image filling it): the centre as
/// fractions of the width and height from the top-left corner, and the spot's radius as a
/// fraction of the height.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ScreenSpot {
    pub x: f64,
    pub y: f64,
    pub radius: f64,
}

/// An image of 8-bit drive values (what a screen shows and the reproduction's PNG holds),
/// rows top to bottom. The reproduction's drive values before quantisation are
/// `display::reproduce::DriveImage` (0–1, 32-bit floats); absolute colour is
/// [`super::XyzImage`].
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Drive8Image {
    pub width: usize,
    pub height: usize,
    pub pixels: Vec<[u8; 3]>,
}

impl Drive8Image {
    pub fn new(
        width: usize,
        height: usize,
        pixels: Vec<[u8; 3]>,
    ) -> Result<Drive8Image, ImageError> {
        if width == 0 || height == 0 || pixels.len() != width * height {
            return Err(ImageError::Size {
                width,
                height,
                need: width * height,
                got: pixels.len(),
            });
        }
        Ok(Drive8Image {
            width,
            height,
            pixels,
        })
    }

    /// An 8-bit RGB PNG (the reproduction's drive values).
    pub fn read_png(path: &Path) -> Result<Drive8Image, ImageError> {
        let bad = |message: String| ImageError::NotShowablePng {
            file: path.to_path_buf(),
            message,
        };
        let file = std::fs::File::open(path).map_err(|source| ImageError::Read {
            file: path.to_path_buf(),
            source,
        })?;
        let mut reader = png::Decoder::new(std::io::BufReader::new(file))
            .read_info()
            .map_err(|e| bad(e.to_string()))?;
        let info = reader.info();
        if info.color_type != png::ColorType::Rgb || info.bit_depth != png::BitDepth::Eight {
            return Err(bad(format!(
                "{:?} at {:?} bits per channel; drive values are 8-bit RGB",
                info.color_type, info.bit_depth
            )));
        }
        let (w, h) = (info.width as usize, info.height as usize);
        let size = reader
            .output_buffer_size()
            .ok_or_else(|| bad(format!("{w}×{h} pixels is too large")))?;
        let mut buf = vec![0; size];
        let frame = reader
            .next_frame(&mut buf)
            .map_err(|e| bad(e.to_string()))?;
        let pixels = buf[..frame.buffer_size()]
            .chunks_exact(3)
            .map(|p| [p[0], p[1], p[2]])
            .collect();
        Drive8Image::new(w, h, pixels)
    }

    pub fn at(&self, x: usize, y: usize) -> [u8; 3] {
        self.pixels[y * self.width + x]
    }

    /// How many pixels of each colour lie inside `spot` (fractions of this image; pixel
    /// centres inside the disc), or of the whole image without one. A spot smaller than a
    /// pixel counts the pixel under its centre.
    pub fn colours_in(&self, spot: Option<ScreenSpot>) -> Vec<([u8; 3], usize)> {
        let mut counts: std::collections::BTreeMap<[u8; 3], usize> = Default::default();
        match spot {
            None => self
                .pixels
                .iter()
                .for_each(|p| *counts.entry(*p).or_default() += 1),
            Some(s) => {
                let (cx, cy) = (s.x * self.width as f64, s.y * self.height as f64);
                let r = s.radius * self.height as f64;
                let (y0, y1) = ((cy - r).floor().max(0.0), (cy + r).ceil());
                let (x0, x1) = ((cx - r).floor().max(0.0), (cx + r).ceil());
                for y in y0 as usize..(y1 as usize).min(self.height) {
                    for x in x0 as usize..(x1 as usize).min(self.width) {
                        let (dx, dy) = (x as f64 + 0.5 - cx, y as f64 + 0.5 - cy);
                        if dx * dx + dy * dy <= r * r {
                            *counts.entry(self.at(x, y)).or_default() += 1;
                        }
                    }
                }
                if counts.is_empty() && (0.0..1.0).contains(&s.x) && (0.0..1.0).contains(&s.y) {
                    counts.insert(self.at(cx as usize, cy as usize), 1);
                }
            }
        }
        counts.into_iter().collect()
    }
}
