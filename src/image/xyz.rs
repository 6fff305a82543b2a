//! The renderer's XYZ image: absolute cd/m² per pixel, as 32-bit floats.

/// An XYZ image, rows top to bottom.
#[derive(Clone, Debug, PartialEq)]
pub struct XyzImage {
    pub width: usize,
    pub height: usize,
    pub pixels: Vec<[f32; 3]>,
}

impl XyzImage {
    pub fn at(&self, x: usize, y: usize) -> [f32; 3] {
        self.pixels[y * self.width + x]
    }
}

/// Largest image read, in pixels (12 bytes each in memory): 2²⁶, 8192 × 8192, far above
/// the camera's 1014 × 1014, so a corrupt header cannot ask for an unbounded allocation.
pub const MAX_PIXELS: usize = 1 << 26;
