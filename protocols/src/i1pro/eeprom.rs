//! The EEPROM's key/value container: a directory of `{u16 key, u32 address}` entries at
//! 0x1000 (and a second one at 0x2000 on Rev E) whose items are arrays of big-endian i32,
//! IEEE-754 float32 or i16, or raw bytes. Parsing yields every item by key; building lays
//! out an image a simulated instrument can serve.

use std::collections::BTreeMap;

use super::Revision;

/// Address of the first directory (block id 1).
pub const DIRECTORY: usize = 0x1000;
/// Address of Rev E's second directory (block id 2).
pub const DIRECTORY_E: usize = 0x2000;
/// Size of a Rev A–D EEPROM.
pub const SIZE_A_TO_D: usize = 0x2000;
/// Size a built Rev E image gets (the real size is asked with 0xD9).
pub const SIZE_E: usize = 0x4000;
/// Byte counts a sane directory has (header included), per table.
const DIRECTORY_BYTES: [(usize, usize); 2] = [(300, 512), (200, 512)];
/// Every key below this is a section marker, whose address ends the items before it.
const MARKER_LIMIT: u16 = 0x100;

/// Element type of an item, fixed by its key.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ItemKind {
    Int,
    Float,
    Short,
    Bytes,
}

impl ItemKind {
    fn width(self) -> usize {
        match self {
            ItemKind::Int | ItemKind::Float => 4,
            ItemKind::Short => 2,
            ItemKind::Bytes => 1,
        }
    }
}

/// The known keys: name and element type. Keys not listed are kept as raw bytes.
const KEYS: &[(u16, &str, ItemKind)] = &[
    (0x03E8, "normal-gain linearisation", ItemKind::Float),
    (0x03E9, "high-gain linearisation", ItemKind::Float),
    (0x03EA, "resampling filter start cells", ItemKind::Int),
    (
        0x03EB,
        "resampling filter coefficient counts",
        ItemKind::Int,
    ),
    (0x03EC, "resampling filter coefficients", ItemKind::Float),
    (0x044C, "white tile reflectance", ItemKind::Float),
    (0x044D, "emissive calibration factors", ItemKind::Float),
    (0x044E, "ambient calibration factors", ItemKind::Float),
    (0x04B4, "sensor target", ItemKind::Int),
    (0x04B5, "sensor dark threshold", ItemKind::Int),
    (0x04B7, "normal-gain saturation", ItemKind::Int),
    (0x04B8, "high-gain saturation", ItemKind::Int),
    (0x04BB, "serial number", ItemKind::Int),
    (0x04BC, "manufacture date", ItemKind::Int),
    (0x04BD, "high-gain factor", ItemKind::Float),
    (0x04C5, "minimum integration time", ItemKind::Float),
    (0x04C6, "maximum integration time", ItemKind::Float),
    (0x0BB9, "unknown 0x0BB9", ItemKind::Int),
    (0x0BBA, "unknown 0x0BBA", ItemKind::Int),
    (0x0BBF, "unknown 0x0BBF", ItemKind::Int),
    (0x0BC0, "CPLD revision", ItemKind::Int),
    (0x0BC1, "unknown 0x0BC1", ItemKind::Int),
    (0x0BC2, "capabilities", ItemKind::Int),
    (0x0BC3, "unknown 0x0BC3", ItemKind::Int),
    (0x0BC4, "physical filter", ItemKind::Int),
    (0x0BC5, "unknown 0x0BC5", ItemKind::Int),
    (0x0BC6, "unknown 0x0BC6", ItemKind::Float),
    (0x0FA0, "unknown 0x0FA0", ItemKind::Int),
    (0x2710, "log checksum", ItemKind::Int),
    (
        0x2711,
        "log last reflective integration time",
        ItemKind::Float,
    ),
    (0x2712, "log reflective spot count", ItemKind::Int),
    (0x2713, "log reflective scan count", ItemKind::Int),
    (0x2714, "log lamp age", ItemKind::Float),
    (0x2715, "log measurement count", ItemKind::Int),
    (0x271A, "log reflective dark reading", ItemKind::Int),
    (0x271B, "log reflective white reading", ItemKind::Int),
    (0x271C, "log reflective gain mode", ItemKind::Int),
    (0x271D, "log reflective integration time", ItemKind::Float),
    (0x2724, "log calibration date", ItemKind::Int),
    (0x2725, "log calibration count", ItemKind::Int),
    (0x2EE1, "chip id", ItemKind::Bytes),
    (0x2EE2, "Rev E capabilities", ItemKind::Int),
    (0x2EEB, "Rev E sensor target", ItemKind::Int),
    (0x2EEC, "Rev E saturation", ItemKind::Int),
    (0x2EF9, "UV calibration integration time", ItemKind::Float),
    (
        0x2EFA,
        "wavelength calibration integration time",
        ItemKind::Float,
    ),
    (
        0x2EFE,
        "wavelength calibration minimum level",
        ItemKind::Int,
    ),
    (
        0x2F44,
        "wavelength calibration reference spectrum",
        ItemKind::Float,
    ),
    (
        0x2F45,
        "wavelength calibration reference offset",
        ItemKind::Int,
    ),
    (
        0x2F46,
        "wavelength calibration maximum error",
        ItemKind::Float,
    ),
    (0x2F4E, "wavelength calibration FWHM", ItemKind::Float),
    (
        0x2F4F,
        "wavelength calibration FWHM tolerance",
        ItemKind::Float,
    ),
    (0x2F58, "stray-light matrix", ItemKind::Short),
    (0x2F59, "stray-light scale", ItemKind::Float),
    (
        0x2F62,
        "reflective cell-to-wavelength polynomial",
        ItemKind::Float,
    ),
    (
        0x2F63,
        "emissive cell-to-wavelength polynomial",
        ItemKind::Float,
    ),
];

/// The log keys exist twice, the second copy 1000 keys higher.
const LOG_KEYS: std::ops::RangeInclusive<u16> = 0x2710..=0x2725;
const LOG_COPY: u16 = 1000;
/// Keys Rev E keeps in its second table.
const TABLE_2_KEYS: std::ops::RangeInclusive<u16> = 0x2EE0..=0x2FFF;

fn lookup(key: u16) -> Option<(&'static str, ItemKind)> {
    let base = if (LOG_KEYS.start() + LOG_COPY..=LOG_KEYS.end() + LOG_COPY).contains(&key) {
        key - LOG_COPY
    } else {
        key
    };
    KEYS.iter()
        .find(|(k, _, _)| *k == base)
        .map(|(_, name, kind)| (*name, *kind))
}

/// The element type of a key's item (raw bytes for keys this codec does not know).
pub fn kind_of(key: u16) -> ItemKind {
    lookup(key).map_or(ItemKind::Bytes, |(_, kind)| kind)
}

/// A readable name of a key for messages.
pub fn key_name(key: u16) -> &'static str {
    lookup(key).map_or("unknown key", |(name, _)| name)
}

/// One item's contents.
#[derive(Clone, Debug, PartialEq)]
pub enum Value {
    Ints(Vec<i32>),
    Floats(Vec<f32>),
    Shorts(Vec<i16>),
    Bytes(Vec<u8>),
}

impl Value {
    fn kind(&self) -> ItemKind {
        match self {
            Value::Ints(_) => ItemKind::Int,
            Value::Floats(_) => ItemKind::Float,
            Value::Shorts(_) => ItemKind::Short,
            Value::Bytes(_) => ItemKind::Bytes,
        }
    }

    fn decode(kind: ItemKind, b: &[u8]) -> Value {
        match kind {
            ItemKind::Int => Value::Ints(
                b.chunks_exact(4)
                    .map(|c| i32::from_be_bytes([c[0], c[1], c[2], c[3]]))
                    .collect(),
            ),
            ItemKind::Float => Value::Floats(
                b.chunks_exact(4)
                    .map(|c| f32::from_be_bytes([c[0], c[1], c[2], c[3]]))
                    .collect(),
            ),
            ItemKind::Short => Value::Shorts(
                b.chunks_exact(2)
                    .map(|c| i16::from_be_bytes([c[0], c[1]]))
                    .collect(),
            ),
            ItemKind::Bytes => Value::Bytes(b.to_vec()),
        }
    }

    fn encode(&self) -> Vec<u8> {
        match self {
            Value::Ints(v) => v.iter().flat_map(|x| x.to_be_bytes()).collect(),
            Value::Floats(v) => v.iter().flat_map(|x| x.to_be_bytes()).collect(),
            Value::Shorts(v) => v.iter().flat_map(|x| x.to_be_bytes()).collect(),
            Value::Bytes(v) => v.clone(),
        }
    }
}

/// An EEPROM image that is not a well-formed container.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum EepromError {
    #[error("the EEPROM image has {len} bytes, too few for directory {table} at {address:#06x}")]
    TooSmall {
        table: usize,
        address: usize,
        len: usize,
    },
    #[error("EEPROM directory {table} has block id {found}, expected {table}")]
    BlockId { table: usize, found: u16 },
    #[error(
        "EEPROM directory {table} claims {bytes} bytes; a sane one has {min} to {max} \
         (corrupt image or wrong revision)"
    )]
    DirectorySize {
        table: usize,
        bytes: usize,
        min: usize,
        max: usize,
    },
    #[error("EEPROM directory {table} does not end with a section marker")]
    NoEndMarker { table: usize },
    #[error(
        "EEPROM key {key:#06x} ({name}) spans {start:#06x}..{end:#06x}, outside the \
         {len}-byte image"
    )]
    OutOfRange {
        key: u16,
        name: &'static str,
        start: usize,
        end: usize,
        len: usize,
    },
    #[error("EEPROM key {key:#06x} ({name}) has {bytes} bytes, not a whole number of {width}-byte values")]
    Ragged {
        key: u16,
        name: &'static str,
        bytes: usize,
        width: usize,
    },
    #[error("EEPROM key {key:#06x} ({name}) must hold {expected:?} values, not {found:?}")]
    WrongKind {
        key: u16,
        name: &'static str,
        expected: ItemKind,
        found: ItemKind,
    },
    #[error("EEPROM key {key:#06x} is a section marker and cannot hold an item")]
    MarkerKey { key: u16 },
    #[error("EEPROM directory {table} would need {entries} entries, more than fit in 512 bytes")]
    TooManyItems { table: usize, entries: usize },
    #[error("the items of EEPROM table {table} need {needed} bytes up to {limit:#06x}; the image is too small")]
    Overflow {
        table: usize,
        needed: usize,
        limit: usize,
    },
}

/// Every item of an EEPROM image, by key.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Eeprom {
    items: BTreeMap<u16, Value>,
}

impl Eeprom {
    pub fn new() -> Eeprom {
        Eeprom::default()
    }

    /// Parses the directory at 0x1000 and, on Rev E, the one at 0x2000. Items of keys this
    /// codec does not know are kept as bytes; a key listed twice keeps its last item.
    pub fn parse(image: &[u8], revision: Revision) -> Result<Eeprom, EepromError> {
        let mut e = Eeprom::new();
        e.parse_table(image, 1)?;
        if revision == Revision::E {
            e.parse_table(image, 2)?;
        }
        Ok(e)
    }

    fn parse_table(&mut self, image: &[u8], table: usize) -> Result<(), EepromError> {
        let dir = if table == 1 { DIRECTORY } else { DIRECTORY_E };
        let (min, max) = DIRECTORY_BYTES[table - 1];
        if image.len() < dir + min {
            return Err(EepromError::TooSmall {
                table,
                address: dir,
                len: image.len(),
            });
        }
        let u16_at = |a: usize| u16::from_be_bytes([image[a], image[a + 1]]);
        let u32_at =
            |a: usize| u32::from_be_bytes([image[a], image[a + 1], image[a + 2], image[a + 3]]);
        let id = u16_at(dir);
        if usize::from(id) != table {
            return Err(EepromError::BlockId { table, found: id });
        }
        let bytes = usize::from(u16_at(dir + 2));
        if !(min..=max).contains(&bytes) || dir + bytes > image.len() {
            return Err(EepromError::DirectorySize {
                table,
                bytes,
                min,
                max,
            });
        }
        let entries: Vec<(u16, usize)> = (0..(bytes - 4) / 6)
            .map(|i| {
                let a = dir + 4 + 6 * i;
                (u16_at(a), u32_at(a + 2) as usize)
            })
            .collect();
        match entries.last() {
            Some((key, _)) if *key < MARKER_LIMIT => {}
            _ => return Err(EepromError::NoEndMarker { table }),
        }
        for pair in entries.windows(2) {
            let ((key, start), (_, end)) = (pair[0], pair[1]);
            if key < MARKER_LIMIT {
                continue;
            }
            let (name, kind) = (key_name(key), kind_of(key));
            if end < start || end > image.len() {
                return Err(EepromError::OutOfRange {
                    key,
                    name,
                    start,
                    end,
                    len: image.len(),
                });
            }
            let b = &image[start..end];
            if b.len() % kind.width() != 0 {
                return Err(EepromError::Ragged {
                    key,
                    name,
                    bytes: b.len(),
                    width: kind.width(),
                });
            }
            self.items.insert(key, Value::decode(kind, b));
        }
        Ok(())
    }

    /// Sets an item; its values must be of the key's element type.
    pub fn insert(&mut self, key: u16, value: Value) -> Result<(), EepromError> {
        if key < MARKER_LIMIT {
            return Err(EepromError::MarkerKey { key });
        }
        let expected = kind_of(key);
        if value.kind() != expected {
            return Err(EepromError::WrongKind {
                key,
                name: key_name(key),
                expected,
                found: value.kind(),
            });
        }
        self.items.insert(key, value);
        Ok(())
    }

    pub fn remove(&mut self, key: u16) -> Option<Value> {
        self.items.remove(&key)
    }

    pub fn get(&self, key: u16) -> Option<&Value> {
        self.items.get(&key)
    }

    pub fn keys(&self) -> impl Iterator<Item = u16> + '_ {
        self.items.keys().copied()
    }

    /// Lays the items out in an image of `size` bytes: the log keys from address 0 (where
    /// the instrument keeps them) up to a section marker, the directory at 0x1000 followed by
    /// the other items and a closing marker; on Rev E the keys 0x2EE0–0x2FFF go to the second
    /// directory at 0x2000. Directories too short to pass the parser's sanity check are
    /// padded with extra closing markers. Unused bytes are 0xFF, as in an erased EEPROM.
    pub fn build(&self, revision: Revision, size: usize) -> Result<Vec<u8>, EepromError> {
        let (table, dir) = match revision {
            Revision::AToD => (1, DIRECTORY),
            Revision::E => (2, DIRECTORY_E),
        };
        if size < dir + DIRECTORY_BYTES[table - 1].1 {
            return Err(EepromError::TooSmall {
                table,
                address: dir,
                len: size,
            });
        }
        let mut image = vec![0xFFu8; size];
        let in_table_2 = |k: u16| revision == Revision::E && TABLE_2_KEYS.contains(&k);
        let is_log = |k: u16| {
            LOG_KEYS.contains(&k)
                || (LOG_KEYS.start() + LOG_COPY..=LOG_KEYS.end() + LOG_COPY).contains(&k)
        };
        let log: Vec<u16> = self.keys().filter(|&k| is_log(k)).collect();
        let main: Vec<u16> = self
            .keys()
            .filter(|&k| !is_log(k) && !in_table_2(k))
            .collect();
        let extra: Vec<u16> = self.keys().filter(|&k| in_table_2(k)).collect();

        let mut entries = Vec::new();
        if !log.is_empty() {
            let end = self.place(&mut image, &log, 0, DIRECTORY, 1, &mut entries)?;
            entries.push((1u16, end));
        }
        let data_1 = DIRECTORY + DIRECTORY_BYTES[0].1;
        let limit_1 = if revision == Revision::E {
            DIRECTORY_E
        } else {
            size
        };
        let end = self.place(&mut image, &main, data_1, limit_1, 1, &mut entries)?;
        entries.push((2u16, end));
        write_directory(&mut image, DIRECTORY, 1, entries, DIRECTORY_BYTES[0].0)?;

        if revision == Revision::E {
            let mut entries = Vec::new();
            let data_2 = DIRECTORY_E + DIRECTORY_BYTES[1].1;
            let end = self.place(&mut image, &extra, data_2, size, 2, &mut entries)?;
            entries.push((3u16, end));
            write_directory(&mut image, DIRECTORY_E, 2, entries, DIRECTORY_BYTES[1].0)?;
        }
        Ok(image)
    }

    /// Writes `keys`' items one after another from `start`; returns the end address.
    fn place(
        &self,
        image: &mut [u8],
        keys: &[u16],
        start: usize,
        limit: usize,
        table: usize,
        entries: &mut Vec<(u16, usize)>,
    ) -> Result<usize, EepromError> {
        let mut at = start;
        for &k in keys {
            let bytes = self.items[&k].encode();
            let end = at + bytes.len();
            if end > limit.min(image.len()) {
                return Err(EepromError::Overflow {
                    table,
                    needed: end - start,
                    limit,
                });
            }
            image[at..end].copy_from_slice(&bytes);
            entries.push((k, at));
            at = end;
        }
        Ok(at)
    }
}

fn write_directory(
    image: &mut [u8],
    dir: usize,
    table: usize,
    mut entries: Vec<(u16, usize)>,
    min_bytes: usize,
) -> Result<(), EepromError> {
    let end = entries.last().map_or(dir, |e| e.1);
    while 4 + 6 * entries.len() < min_bytes {
        entries.push((0x00FF, end));
    }
    let bytes = 4 + 6 * entries.len();
    if bytes > DIRECTORY_BYTES[table - 1].1 || dir + bytes > image.len() {
        return Err(EepromError::TooManyItems {
            table,
            entries: entries.len(),
        });
    }
    image[dir..dir + 2].copy_from_slice(&(table as u16).to_be_bytes());
    image[dir + 2..dir + 4].copy_from_slice(&(bytes as u16).to_be_bytes());
    for (i, (key, addr)) in entries.iter().enumerate() {
        let a = dir + 4 + 6 * i;
        image[a..a + 2].copy_from_slice(&key.to_be_bytes());
        image[a + 2..a + 6].copy_from_slice(&(*addr as u32).to_be_bytes());
    }
    Ok(())
}

#[cfg(test)]
mod tests;
