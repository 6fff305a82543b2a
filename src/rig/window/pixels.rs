//! 8-bit RGB to X11 TrueColor pixel values and back (X Window System Protocol, X11R7.7,
//! §8 "Connection Setup": a TrueColor visual's red/green/blue masks give each channel's
//! bits; ZPixmap images are scanlines of `bits_per_pixel` units padded to `scanline_pad`
//! bits, in the server's `image_byte_order`).

/// How the server packs colours into pixels and images.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PixelFormat {
    pub masks: [u32; 3],
    /// Bits per pixel of ZPixmap images of the visual's depth (8, 16, 24 or 32).
    pub bits_per_pixel: u8,
    /// Scanlines are padded to a multiple of this many bits.
    pub scanline_pad: u8,
    /// Multi-byte pixels are most significant byte first.
    pub big_endian: bool,
}

/// One channel's field in a mask: its shift and the largest value it holds.
fn field(mask: u32) -> (u32, u32) {
    if mask == 0 {
        return (0, 0);
    }
    let shift = mask.trailing_zeros();
    (shift, mask >> shift)
}

impl PixelFormat {
    /// The pixel value showing 8-bit `rgb`. With 8-bit channels this is the value itself;
    /// deeper channels (10-bit panels) get the code scaled to their range, rounded.
    pub fn encode(&self, rgb: [u8; 3]) -> u32 {
        let mut pixel = 0;
        for (mask, v) in self.masks.into_iter().zip(rgb) {
            let (shift, max) = field(mask);
            let scaled = (u64::from(v) * u64::from(max) + 127) / 255;
            pixel |= (scaled as u32) << shift;
        }
        pixel
    }

    /// The 8-bit RGB of a pixel value (inverse of [`PixelFormat::encode`]).
    pub fn decode(&self, pixel: u32) -> [u8; 3] {
        self.masks.map(|mask| {
            let (shift, max) = field(mask);
            if max == 0 {
                return 0;
            }
            let v = (pixel & mask) >> shift;
            ((u64::from(v) * 255 + u64::from(max) / 2) / u64::from(max)) as u8
        })
    }

    /// Bytes per scanline of a `width`-pixel ZPixmap image.
    pub fn stride(&self, width: usize) -> usize {
        let pad = usize::from(self.scanline_pad.max(8));
        (width * usize::from(self.bits_per_pixel)).div_ceil(pad) * pad / 8
    }

    /// A ZPixmap image of `pixels` (rows of `width`), the inverse of
    /// [`PixelFormat::decode_image`]; None when the pixel size is not a whole number of
    /// bytes.
    pub fn encode_image(&self, pixels: &[[u8; 3]], width: usize) -> Option<Vec<u8>> {
        if self.bits_per_pixel % 8 != 0 || self.bits_per_pixel > 32 || width == 0 {
            return None;
        }
        let bytes = usize::from(self.bits_per_pixel / 8);
        let stride = self.stride(width);
        let mut out = Vec::with_capacity(stride * pixels.len().div_ceil(width));
        for row in pixels.chunks(width) {
            let start = out.len();
            for &p in row {
                let v = self.encode(p);
                for k in 0..bytes {
                    let shift = if self.big_endian { bytes - 1 - k } else { k } * 8;
                    out.push((v >> shift) as u8);
                }
            }
            out.resize(start + stride, 0);
        }
        Some(out)
    }

    /// The 8-bit RGB of every pixel of a `width × height` ZPixmap image, row by row.
    /// None if `data` is too short or the pixel size is not a whole number of bytes.
    pub fn decode_image(&self, data: &[u8], width: usize, height: usize) -> Option<Vec<[u8; 3]>> {
        if self.bits_per_pixel % 8 != 0 || self.bits_per_pixel > 32 {
            return None;
        }
        let bytes = usize::from(self.bits_per_pixel / 8);
        let stride = self.stride(width);
        if data.len() < stride * height {
            return None;
        }
        let mut out = Vec::with_capacity(width * height);
        for row in data.chunks(stride).take(height) {
            for px in row[..width * bytes].chunks(bytes) {
                let value = if self.big_endian {
                    px.iter().fold(0u32, |acc, &b| (acc << 8) | u32::from(b))
                } else {
                    px.iter()
                        .rev()
                        .fold(0u32, |acc, &b| (acc << 8) | u32::from(b))
                };
                out.push(self.decode(value));
            }
        }
        Some(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const RGB888: PixelFormat = PixelFormat {
        masks: [0xff0000, 0x00ff00, 0x0000ff],
        bits_per_pixel: 32,
        scanline_pad: 32,
        big_endian: false,
    };

    #[test]
    fn eight_bit_channels_pack_without_change() {
        assert_eq!(RGB888.encode([0x12, 0x34, 0x56]), 0x123456);
        for v in 0..=255u8 {
            let rgb = [v, 255 - v, v / 3];
            assert_eq!(RGB888.decode(RGB888.encode(rgb)), rgb);
        }
    }

    #[test]
    fn ten_bit_channels_round_trip_every_code() {
        // A 30-bit visual (x2r10g10b10): 8-bit v is shown as round(v·1023/255).
        let deep = PixelFormat {
            masks: [0x3ff0_0000, 0x000f_fc00, 0x0000_03ff],
            ..RGB888
        };
        assert_eq!(deep.encode([255, 0, 128]), (1023 << 20) | 514);
        for v in 0..=255u8 {
            assert_eq!(deep.decode(deep.encode([v, v, v])), [v, v, v]);
        }
    }

    #[test]
    fn images_are_read_with_padding_and_byte_order() {
        // Two pixels per row, 24 bits each, rows padded to 32 bits: 8 bytes a row.
        let packed24 = PixelFormat {
            bits_per_pixel: 24,
            ..RGB888
        };
        assert_eq!(packed24.stride(2), 8);
        let data = [
            0x03, 0x02, 0x01, 0x06, 0x05, 0x04, 0xee, 0xee, //
            0x09, 0x08, 0x07, 0x0c, 0x0b, 0x0a, 0xee, 0xee,
        ];
        assert_eq!(
            packed24.decode_image(&data, 2, 2).unwrap(),
            vec![[1, 2, 3], [4, 5, 6], [7, 8, 9], [10, 11, 12]]
        );
        let msb = PixelFormat {
            big_endian: true,
            ..RGB888
        };
        assert_eq!(
            msb.decode_image(&[0, 1, 2, 3], 1, 1).unwrap(),
            vec![[1, 2, 3]]
        );
        assert!(RGB888.decode_image(&[0; 7], 2, 1).is_none());
        // Encoding is the inverse, padding included (the same bytes with zero padding).
        let pixels = [[1, 2, 3], [4, 5, 6], [7, 8, 9], [10, 11, 12]];
        let encoded = packed24.encode_image(&pixels, 2).unwrap();
        assert_eq!(encoded.len(), 16);
        assert_eq!(&encoded[..6], &data[..6]);
        assert_eq!(packed24.decode_image(&encoded, 2, 2).unwrap(), pixels);
        assert_eq!(msb.encode_image(&[[1, 2, 3]], 1).unwrap(), vec![0, 1, 2, 3]);
    }
}
