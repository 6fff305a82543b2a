//! The layout of an OpenEXR file, read far enough to know that decoding it is safe.
//!
//! The `exr` crate trusts sizes it finds in the file: it sizes its offset table by the
//! header's chunk count, and each chunk's buffer by the byte count the chunk states, before
//! it reads the bytes. A corrupt file of a few hundred bytes can so ask for gigabytes. This
//! reader checks, before the crate sees the file, everything such an allocation is taken
//! from: the data window, the channels, compression and line order, the chunk count, the
//! offset table, and every chunk's stated size — all against the file's length. What it
//! accepts cannot make the decoder allocate much more than the file's size times the
//! largest expansion a compression allows.
//!
//! Layout (OpenEXR "File Layout" and "Technical Introduction"): the magic number
//! 76 2f 31 01, a version field (version 2 in the low byte; flag bits 0x200 single-part
//! tiled, 0x400 long names, 0x800 deep data, 0x1000 multi-part), one header per part (a
//! sequence of attributes — name, type name, i32 size, value — ended by an empty name; a
//! multi-part file ends its list of headers with one more empty name), one offset table per
//! part (one u64 file offset per chunk), then the chunks. A chunk starts with its part
//! number (multi-part files only), then its y coordinate (scan lines) or four tile
//! coordinates (tiles), then an i32 byte count of its pixel data.

/// The most a compressed byte can expand to: deflate's ceiling is about 1032 : 1 and every
/// other OpenEXR compression stays below it; the rest is room.
const MAX_EXPANSION: u64 = 2048;

/// Files this small may still decode to this many bytes (a tiny image with large tiles).
const MIN_DECODED_BUDGET: u64 = 1 << 20;

/// More channels than any image metamer reads or writes could use.
const MAX_CHANNELS: usize = 1024;

/// One part's layout as far as the decoder's allocations depend on it.
#[derive(Debug)]
struct Part {
    width: u64,
    height: u64,
    /// Bytes of one pixel over all channels (before subsampling).
    pixel_bytes: u64,
    compression: u8,
    tiles: Option<Tiles>,
    /// The `chunkCount` attribute (required in multi-part files).
    chunk_count: Option<u64>,
}

#[derive(Clone, Copy, Debug)]
struct Tiles {
    width: u64,
    height: u64,
    /// 0 one level, 1 mipmap, 2 ripmap.
    levels: u8,
    round_up: bool,
}

struct Bytes<'a> {
    data: &'a [u8],
    at: usize,
}

impl<'a> Bytes<'a> {
    fn take(&mut self, n: usize, what: &str) -> Result<&'a [u8], String> {
        if self.data.len() - self.at < n {
            return Err(format!(
                "the file ends inside {what} (byte {} of {}): it is truncated",
                self.at,
                self.data.len()
            ));
        }
        let s = &self.data[self.at..self.at + n];
        self.at += n;
        Ok(s)
    }

    fn i32(&mut self, what: &str) -> Result<i32, String> {
        let b = self.take(4, what)?;
        Ok(i32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }

    fn u64(&mut self, what: &str) -> Result<u64, String> {
        let b = self.take(8, what)?;
        Ok(u64::from_le_bytes(std::array::from_fn(|i| b[i])))
    }

    /// A null-terminated name of at most `max` bytes.
    fn name(&mut self, max: usize, what: &str) -> Result<&'a [u8], String> {
        let rest = &self.data[self.at..];
        let Some(len) = rest.iter().take(max + 1).position(|&b| b == 0) else {
            return Err(if rest.len() <= max {
                format!("the file ends inside {what}: it is truncated")
            } else {
                format!("{what} is longer than {max} bytes: the header is corrupt")
            });
        };
        self.at += len + 1;
        Ok(&rest[..len])
    }
}

fn shown(name: &[u8]) -> String {
    metamer_color::text::echo(&String::from_utf8_lossy(name))
}

/// Checks the file `data` (all of it) and returns why it must not be decoded, in words
/// about the file.
pub(super) fn check(data: &[u8]) -> Result<(), String> {
    let len = data.len() as u64;
    let mut b = Bytes { data, at: 0 };
    if data.len() < 8 || data[..4] != [0x76, 0x2f, 0x31, 0x01] {
        return Err("not an OpenEXR file (it does not start with the OpenEXR magic number)".into());
    }
    b.at = 4;
    let version = b.i32("the version field")? as u32;
    if version & 0xff != 2 {
        return Err(format!(
            "OpenEXR version {} (this reader knows version 2)",
            version & 0xff
        ));
    }
    let flags = version & !0xff;
    if flags & !0x1e00 != 0 {
        return Err(format!("unknown flags {flags:#x} in the version field"));
    }
    if flags & 0x800 != 0 {
        return Err("holds deep data, not an image".into());
    }
    let (tiled, long_names, multi) = (flags & 0x200 != 0, flags & 0x400 != 0, flags & 0x1000 != 0);
    let max_name = if long_names { 255 } else { 31 };
    let mut parts = Vec::new();
    loop {
        if multi && !parts.is_empty() && b.data.get(b.at) == Some(&0) {
            b.at += 1;
            break;
        }
        parts.push(header(&mut b, max_name, tiled, multi, parts.len())?);
        if !multi {
            break;
        }
    }
    let budget = len.saturating_mul(MAX_EXPANSION).max(MIN_DECODED_BUDGET);
    let mut counts = Vec::with_capacity(parts.len());
    for (i, p) in parts.iter().enumerate() {
        counts.push(check_part(p, i, multi, len, budget)?);
    }
    // The offset tables: each as long as its part's chunk count, inside the file.
    let total: u64 = counts.iter().sum();
    let table_end = (b.at as u64).saturating_add(total.saturating_mul(8));
    if table_end > len {
        return Err(format!(
            "its offset table of {total} chunks needs {} bytes, more than the {} bytes left in \
             the file: the file is truncated or its header is corrupt",
            total.saturating_mul(8),
            len - b.at as u64
        ));
    }
    for (part, &count) in counts.iter().enumerate() {
        for chunk in 0..count {
            let offset = b.u64("the offset table")?;
            check_chunk(data, offset, table_end, part, chunk, multi, &parts[part])?;
        }
    }
    Ok(())
}

/// One chunk's start and its stated byte count, against the file.
fn check_chunk(
    data: &[u8],
    offset: u64,
    table_end: u64,
    part: usize,
    chunk: u64,
    multi: bool,
    p: &Part,
) -> Result<(), String> {
    let len = data.len() as u64;
    let which = if multi {
        format!("chunk {chunk} of part {part}")
    } else {
        format!("chunk {chunk}")
    };
    let coordinates = if p.tiles.is_some() { 16 } else { 4 };
    let head = u64::from(multi) * 4 + coordinates + 4;
    if offset < table_end || offset > len.saturating_sub(head) {
        return Err(format!(
            "its offset table puts {which} at byte {offset}, outside the pixel data (bytes \
             {table_end}–{len}): the file is truncated or corrupt"
        ));
    }
    let mut b = Bytes {
        data,
        at: offset as usize,
    };
    if multi {
        let n = b.i32("a chunk")?;
        if n as i64 != part as i64 {
            return Err(format!(
                "{which} says it belongs to part {n}: the file is corrupt"
            ));
        }
    }
    b.take(coordinates as usize, "a chunk")?;
    let size = b.i32("a chunk")?;
    let left = len - offset - head;
    if size < 0 || size as u64 > left {
        return Err(format!(
            "{which} at byte {offset} states {size} bytes of pixel data, but only {left} bytes \
             follow it: the file is truncated or corrupt"
        ));
    }
    Ok(())
}

/// The part's chunk count once its sizes are known to be safe.
fn check_part(p: &Part, index: usize, multi: bool, len: u64, budget: u64) -> Result<u64, String> {
    let which = if multi {
        format!("part {index}: ")
    } else {
        String::new()
    };
    let decoded = p
        .width
        .saturating_mul(p.height)
        .saturating_mul(p.pixel_bytes);
    if decoded > budget {
        return Err(format!(
            "{which}the header says {}×{} pixels, more than a file of {len} bytes can hold: \
             the header is corrupt",
            p.width, p.height
        ));
    }
    let computed = match p.tiles {
        None => {
            let lines = match p.compression {
                0..=2 => 1,
                3 | 5 => 16,
                4 | 6 | 7 | 8 | 11 => 32,
                _ => 256,
            };
            p.height.div_ceil(lines)
        }
        Some(t) => {
            let tile_bytes = t
                .width
                .saturating_mul(t.height)
                .saturating_mul(p.pixel_bytes);
            if tile_bytes > budget {
                return Err(format!(
                    "{which}tiles of {}×{} pixels are more than a file of {len} bytes can hold: \
                     the header is corrupt",
                    t.width, t.height
                ));
            }
            tile_count(p.width, p.height, t)
        }
    };
    match p.chunk_count {
        Some(n) if n != computed => Err(format!(
            "{which}its chunkCount attribute says {n} chunks, its data window and {} say \
             {computed}: the header is corrupt",
            if p.tiles.is_some() {
                "tiles"
            } else {
                "compression"
            }
        )),
        None if multi => Err(format!(
            "{which}has no chunkCount attribute, which a multi-part file must have"
        )),
        _ => Ok(computed),
    }
}

/// Tiles over all resolution levels (OpenEXR's level sizes: halved, rounded as the tile
/// description says, never below 1).
fn tile_count(width: u64, height: u64, t: Tiles) -> u64 {
    let levels = |full: u64| {
        let mut n = 1;
        let mut size = full;
        while size > 1 {
            size = if t.round_up {
                size.div_ceil(2)
            } else {
                size / 2
            };
            n += 1;
        }
        n
    };
    let size = |full: u64, level: u32| {
        let d = 1u64 << level;
        (if t.round_up {
            full.div_ceil(d)
        } else {
            full / d
        })
        .max(1)
    };
    let tiles = |w: u64, h: u64| w.div_ceil(t.width).saturating_mul(h.div_ceil(t.height));
    match t.levels {
        0 => tiles(width, height),
        1 => (0..levels(width.max(height)))
            .map(|l| tiles(size(width, l), size(height, l)))
            .fold(0u64, u64::saturating_add),
        _ => (0..levels(height))
            .flat_map(|ly| (0..levels(width)).map(move |lx| (lx, ly)))
            .map(|(lx, ly)| tiles(size(width, lx), size(height, ly)))
            .fold(0u64, u64::saturating_add),
    }
}

/// The attributes of one part's header this check reads; the others are skipped.
#[derive(Default)]
struct Attributes {
    window: Option<[i32; 4]>,
    channels: Option<u64>,
    compression: Option<u8>,
    line_order: Option<u8>,
    tiles: Option<Tiles>,
    chunk_count: Option<u64>,
    kind: Option<Vec<u8>>,
}

impl Attributes {
    /// The attributes up to the empty name that ends a header.
    fn read(b: &mut Bytes<'_>, max_name: usize) -> Result<Attributes, String> {
        let mut attributes = Attributes::default();
        loop {
            let name = b.name(max_name, "an attribute name")?;
            if name.is_empty() {
                return Ok(attributes);
            }
            let type_name = b.name(max_name, "an attribute type")?;
            let size = b.i32("an attribute size")?;
            let left = b.data.len() - b.at;
            if size < 0 || size as usize > left {
                return Err(format!(
                    "attribute '{}' states {size} bytes, but {left} bytes are left in the file: \
                     the file is truncated or corrupt",
                    shown(name)
                ));
            }
            let value = b.take(size as usize, "an attribute")?;
            attributes.set(name, type_name, value)?;
        }
    }

    /// One attribute's value, checked for its size and range where this check reads it.
    fn set(&mut self, name: &[u8], type_name: &[u8], value: &[u8]) -> Result<(), String> {
        let expect = |n: usize| {
            if value.len() == n {
                Ok(())
            } else {
                Err(format!(
                    "attribute '{}' of type {} has {} bytes, not {n}: the header is corrupt",
                    shown(name),
                    shown(type_name),
                    value.len()
                ))
            }
        };
        let int = |at: usize| i32::from_le_bytes(std::array::from_fn(|i| value[at + i]));
        match name {
            b"dataWindow" => {
                expect(16)?;
                self.window = Some([int(0), int(4), int(8), int(12)]);
            }
            b"channels" => self.channels = Some(channel_bytes(value)?),
            b"compression" => {
                expect(1)?;
                if value[0] > 11 {
                    return Err(format!("unknown compression {}", value[0]));
                }
                self.compression = Some(value[0]);
            }
            b"lineOrder" => {
                expect(1)?;
                if value[0] > 2 {
                    return Err(format!("unknown line order {}", value[0]));
                }
                self.line_order = Some(value[0]);
            }
            b"tiles" => {
                expect(9)?;
                self.tiles = Some(tile_description(int(0) as u32, int(4) as u32, value[8])?);
            }
            b"chunkCount" => {
                expect(4)?;
                let n = int(0);
                if n < 0 {
                    return Err(format!("its chunkCount attribute is {n}"));
                }
                self.chunk_count = Some(n as u64);
            }
            b"type" => self.kind = Some(value.strip_suffix(&[0]).unwrap_or(value).to_vec()),
            _ => {}
        }
        Ok(())
    }
}

/// A `tiles` attribute: the tile's size and the level mode and rounding byte.
fn tile_description(w: u32, h: u32, mode: u8) -> Result<Tiles, String> {
    if w == 0 || h == 0 || mode & 0x0f > 2 || mode >> 4 > 1 {
        return Err(format!(
            "the tile description ({w}×{h}, mode {mode:#x}) is not a valid one"
        ));
    }
    Ok(Tiles {
        width: u64::from(w),
        height: u64::from(h),
        levels: mode & 0x0f,
        round_up: mode >> 4 == 1,
    })
}

/// One part's header: its attributes up to the empty name that ends them, then the
/// attributes every part needs and what they say of its layout.
fn header(
    b: &mut Bytes<'_>,
    max_name: usize,
    tiled: bool,
    multi: bool,
    index: usize,
) -> Result<Part, String> {
    let a = Attributes::read(b, max_name)?;
    let part = if multi {
        format!("part {index} ")
    } else {
        String::new()
    };
    let missing = |what: &str| format!("{part}has no {what} attribute: the header is corrupt");
    let [x0, y0, x1, y1] = a.window.ok_or_else(|| missing("dataWindow"))?;
    if x1 < x0 || y1 < y0 {
        return Err(format!(
            "{part}data window ({x0}, {y0})–({x1}, {y1}) is empty or inverted"
        ));
    }
    let pixel_bytes = a.channels.ok_or_else(|| missing("channels"))?;
    let compression = a.compression.ok_or_else(|| missing("compression"))?;
    a.line_order.ok_or_else(|| missing("lineOrder"))?;
    let is_tiled = match a.kind.as_deref() {
        Some(b"tiledimage") => true,
        Some(b"scanlineimage") | None => tiled && !multi,
        Some(other) => {
            return Err(format!(
                "{part}is of type '{}', not a scan-line or tiled image",
                shown(other)
            ))
        }
    };
    if is_tiled && a.tiles.is_none() {
        return Err(missing("tiles"));
    }
    Ok(Part {
        width: (i64::from(x1) - i64::from(x0) + 1) as u64,
        height: (i64::from(y1) - i64::from(y0) + 1) as u64,
        pixel_bytes,
        compression,
        tiles: if is_tiled { a.tiles } else { None },
        chunk_count: a.chunk_count,
    })
}

/// A channel list's bytes per pixel; each channel must have a known type and sampling ≥ 1.
fn channel_bytes(value: &[u8]) -> Result<u64, String> {
    let mut b = Bytes { data: value, at: 0 };
    let mut total = 0u64;
    let mut n = 0;
    loop {
        let name = b.name(255, "the channel list")?;
        if name.is_empty() {
            if n == 0 {
                return Err("its channel list is empty".into());
            }
            return Ok(total);
        }
        n += 1;
        if n > MAX_CHANNELS {
            return Err(format!("more than {MAX_CHANNELS} channels"));
        }
        let kind = b.i32("the channel list")?;
        b.take(4, "the channel list")?;
        let (sx, sy) = (b.i32("the channel list")?, b.i32("the channel list")?);
        total += match kind {
            0 | 2 => 4,
            1 => 2,
            _ => {
                return Err(format!(
                    "channel '{}' has the unknown pixel type {kind}",
                    shown(name)
                ))
            }
        };
        if sx < 1 || sy < 1 {
            return Err(format!(
                "channel '{}' has the sampling {sx}×{sy} (must be at least 1×1)",
                shown(name)
            ));
        }
    }
}
