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

    /// The image slid `by` of its pixels (right, down) within its own frame: what leaves
    /// the frame is cut off and what the slide uncovers is black, the colour a screen
    /// shows around an image that does not fill it. A slide by whole pixels moves the
    /// drive values without resampling them.
    pub fn shifted(&self, by: [i64; 2]) -> Drive8Image {
        let (w, h) = (self.width as i64, self.height as i64);
        let mut pixels = vec![[0u8; 3]; self.pixels.len()];
        // Only the rows and columns that stay inside the frame are copied: a slide wider
        // than the image leaves it black.
        let (dx, dy) = (by[0].clamp(-w, w), by[1].clamp(-h, h));
        let columns = (dx.max(0) as usize, (w + dx.min(0)) as usize);
        for y in dy.max(0)..h + dy.min(0) {
            let from = ((y - dy) * w) as usize;
            let to = (y * w) as usize;
            let (x0, x1) = columns;
            let src = (x0 as i64 - dx) as usize;
            pixels[to + x0..to + x1]
                .copy_from_slice(&self.pixels[from + src..from + src + x1 - x0]);
        }
        Drive8Image {
            width: self.width,
            height: self.height,
            pixels,
        }
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A 3 × 2 image whose pixels are numbered in reading order, slid by hand-worked
    /// offsets: each pixel lands `by` away, and the uncovered ones are black.
    #[test]
    fn a_slide_moves_pixels_and_uncovers_black() {
        let px = |n: u8| [n, n, n];
        let image = Drive8Image::new(3, 2, (1..=6).map(px).collect()).unwrap();
        let b = px(0);
        assert_eq!(image.shifted([0, 0]), image);
        assert_eq!(
            image.shifted([1, 0]).pixels,
            vec![b, px(1), px(2), b, px(4), px(5)]
        );
        assert_eq!(image.shifted([-2, 1]).pixels, vec![b, b, b, px(3), b, b]);
        assert_eq!(image.shifted([3, 0]).pixels, vec![b; 6]);
        assert_eq!(image.shifted([i64::MIN, i64::MAX]).pixels, vec![b; 6]);
    }
}
