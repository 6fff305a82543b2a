//! A whole image in the window: scaled to fit the monitor (nearest pixel, aspect ratio
//! kept, black around it) and made the window's background pixmap, so the server repaints
//! it by itself whenever the window is exposed.

use x11rb::connection::{Connection, RequestConnection};
use x11rb::protocol::xproto::{
    ChangeWindowAttributesAux, ConfigureWindowAux, ConnectionExt as _, CreateGCAux, ImageFormat,
    StackMode,
};

use super::{perr, WindowDisplay, WindowError};
use crate::image::Drive8Image;
use crate::rig::Placement;

/// Where an image of `iw × ih` lands on a monitor of `mw × mh` when scaled to fit: left,
/// top, width and height in monitor pixels.
pub fn fit(iw: usize, ih: usize, mw: usize, mh: usize) -> (usize, usize, usize, usize) {
    let scale = (mw as f64 / iw as f64).min(mh as f64 / ih as f64);
    let w = ((iw as f64 * scale).round() as usize).clamp(1, mw);
    let h = ((ih as f64 * scale).round() as usize).clamp(1, mh);
    ((mw - w) / 2, (mh - h) / 2, w, h)
}

/// The monitor's pixels showing `image` fitted as [`fit`] says, black elsewhere.
pub fn fitted(image: &Drive8Image, mw: usize, mh: usize) -> Vec<[u8; 3]> {
    let (left, top, w, h) = fit(image.width, image.height, mw, mh);
    let mut out = vec![[0u8; 3]; mw * mh];
    for y in 0..h {
        let sy = (y * image.height / h).min(image.height - 1);
        for x in 0..w {
            let sx = (x * image.width / w).min(image.width - 1);
            out[(top + y) * mw + left + x] = image.at(sx, sy);
        }
    }
    out
}

impl WindowDisplay {
    /// Shows `image` scaled to fit and returns once the server has painted it.
    pub fn show_scaled(&mut self, image: &Drive8Image) -> Result<Placement, WindowError> {
        let (mw, mh) = (
            usize::from(self.monitor.width),
            usize::from(self.monitor.height),
        );
        let d = &self.display;
        let data = self
            .format
            .encode_image(&fitted(image, mw, mh), mw)
            .ok_or_else(|| WindowError::Protocol {
                display: d.clone(),
                what: "PutImage",
                message: format!(
                    "{} bits per pixel is not a whole number of bytes",
                    self.format.bits_per_pixel
                ),
            })?;
        let pixmap = self
            .conn
            .generate_id()
            .map_err(perr(d, "allocating an id"))?;
        self.conn
            .create_pixmap(
                self.depth,
                pixmap,
                self.root,
                self.monitor.width,
                self.monitor.height,
            )
            .map_err(perr(d, "CreatePixmap"))?;
        let gc = self
            .conn
            .generate_id()
            .map_err(perr(d, "allocating an id"))?;
        self.conn
            .create_gc(gc, pixmap, &CreateGCAux::new())
            .map_err(perr(d, "CreateGC"))?;
        // One request holds at most the server's maximum: send the image in bands of rows.
        let stride = self.format.stride(mw);
        let max_bytes = self
            .conn
            .maximum_request_bytes()
            .saturating_sub(64)
            .max(stride);
        let rows = (max_bytes / stride).clamp(1, mh);
        for (band, chunk) in data.chunks(rows * stride).enumerate() {
            let y = band * rows;
            self.conn
                .put_image(
                    ImageFormat::Z_PIXMAP,
                    pixmap,
                    gc,
                    self.monitor.width,
                    (chunk.len() / stride) as u16,
                    0,
                    y as i16,
                    0,
                    self.depth,
                    chunk,
                )
                .map_err(perr(d, "PutImage"))?;
        }
        self.conn
            .change_window_attributes(
                self.window,
                &ChangeWindowAttributesAux::new().background_pixmap(pixmap),
            )
            .map_err(perr(d, "ChangeWindowAttributes"))?;
        // The window holds the pixmap as its background; our handles can go.
        self.conn.free_gc(gc).map_err(perr(d, "FreeGC"))?;
        self.conn
            .free_pixmap(pixmap)
            .map_err(perr(d, "FreePixmap"))?;
        self.conn
            .configure_window(
                self.window,
                &ConfigureWindowAux::new().stack_mode(StackMode::ABOVE),
            )
            .map_err(perr(d, "ConfigureWindow"))?;
        self.conn
            .clear_area(false, self.window, 0, 0, 0, 0)
            .map_err(perr(d, "ClearArea"))?
            .check()
            .map_err(perr(d, "ClearArea"))?;
        let (left, top, w, h) = fit(image.width, image.height, mw, mh);
        Ok(Placement {
            left: left as f64 / mw as f64,
            top: top as f64 / mh as f64,
            width: w as f64 / mw as f64,
            height: h as f64 / mh as f64,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A square image on a 1920×1080 monitor: 1080 high, (1920 − 1080)/2 = 420 from the
    /// left; a 2×1 image on a 4×4 monitor: 4×2 at the vertical middle.
    #[test]
    fn images_fit_with_their_aspect_ratio() {
        assert_eq!(fit(1014, 1014, 1920, 1080), (420, 0, 1080, 1080));
        assert_eq!(fit(2, 1, 4, 4), (0, 1, 4, 2));
        let img = Drive8Image::new(2, 1, vec![[1, 1, 1], [2, 2, 2]]).unwrap();
        let px = fitted(&img, 4, 4);
        let row = |y: usize| px[y * 4..y * 4 + 4].to_vec();
        assert_eq!(row(0), vec![[0; 3]; 4]);
        assert_eq!(row(1), vec![[1; 3], [1; 3], [2; 3], [2; 3]]);
        assert_eq!(row(2), row(1));
        assert_eq!(row(3), vec![[0; 3]; 4]);
    }
}
