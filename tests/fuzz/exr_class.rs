//! Corrupt OpenEXR files of the class the fuzz harness found (a few hundred bytes whose
//! header or chunk table states sizes the file cannot hold), made from a valid file the
//! program writes, each with the words its error must contain.

use std::path::Path;

use metamer::image::{write_xyz_image, XyzImage};

/// A valid w × h XYZ image as the program writes it.
pub fn valid(dir: &Path, w: usize, h: usize) -> Vec<u8> {
    let img = XyzImage {
        width: w,
        height: h,
        pixels: (0..w * h).map(|i| [i as f32, 1.0, 2.0]).collect(),
    };
    let p = dir.join("valid.exr");
    write_xyz_image(&p, &img, &metamer::output::OutputPolicy::new(true)).unwrap();
    std::fs::read(p).unwrap()
}

/// Where each attribute's value starts (by name), and where the header ends (the offset
/// table's start), walking the single-part header: name, type, i32 size, value.
fn layout(bytes: &[u8]) -> (Vec<(String, usize, usize)>, usize) {
    let cstr = |at: usize| {
        let end = at + bytes[at..].iter().position(|&b| b == 0).unwrap();
        (
            String::from_utf8_lossy(&bytes[at..end]).into_owned(),
            end + 1,
        )
    };
    let mut at = 8;
    let mut attributes = Vec::new();
    loop {
        let (name, next) = cstr(at);
        if name.is_empty() {
            return (attributes, next);
        }
        let (_, next) = cstr(next);
        let size = i32::from_le_bytes(bytes[next..next + 4].try_into().unwrap()) as usize;
        attributes.push((name, next + 4, size));
        at = next + 4 + size;
    }
}

fn value_at(bytes: &[u8], name: &str) -> usize {
    let (attributes, _) = layout(bytes);
    attributes
        .iter()
        .find(|(n, _, _)| n == name)
        .unwrap_or_else(|| panic!("no {name} attribute"))
        .1
}

fn put(bytes: &mut [u8], at: usize, v: &[u8]) {
    bytes[at..at + v.len()].copy_from_slice(v);
}

/// (what is wrong, the file, words its error must contain).
pub fn corrupt(valid: &[u8]) -> Vec<(&'static str, Vec<u8>, &'static str)> {
    let (_, table) = layout(valid);
    let first_offset = u64::from_le_bytes(valid[table..table + 8].try_into().unwrap()) as usize;
    let len = valid.len() as u64;
    // A chunk's byte count follows its tile's four coordinates (tiled files, flag 0x200 of
    // the version field, as the program writes) or its y coordinate (scan lines).
    let size_at = first_offset + if valid[5] & 0x02 != 0 { 16 } else { 4 };
    let mut out = Vec::new();
    let mut with = |what, edit: &dyn Fn(&mut Vec<u8>), words| {
        let mut b = valid.to_vec();
        edit(&mut b);
        out.push((what, b, words));
    };
    // The fuzz finding: a chunk stating 1 120 403 456 bytes (the bits of 100.0f32).
    with(
        "a chunk's byte count far past the end",
        &|b| put(b, size_at, &1_120_403_456i32.to_le_bytes()),
        "states 1120403456 bytes of pixel data, but only",
    );
    with(
        "a negative chunk byte count",
        &|b| put(b, size_at, &(-5i32).to_le_bytes()),
        "states -5 bytes of pixel data",
    );
    with(
        "an offset past the end of the file",
        &|b| put(b, table, &(len + 1000).to_le_bytes()),
        "outside the pixel data",
    );
    with(
        "an offset into the header",
        &|b| put(b, table, &8u64.to_le_bytes()),
        "outside the pixel data",
    );
    with(
        "the file cut inside the offset table",
        &|b| b.truncate(table + 4),
        "offset table of",
    );
    with(
        "a data window of 8192 × 8192 pixels",
        &|b| {
            let at = value_at(b, "dataWindow");
            put(b, at + 8, &8191i32.to_le_bytes());
            put(b, at + 12, &8191i32.to_le_bytes());
        },
        "8192×8192 pixels, more than a file of",
    );
    with(
        "an inverted data window",
        &|b| {
            let at = value_at(b, "dataWindow");
            put(b, at + 8, &(-3i32).to_le_bytes());
        },
        "is empty or inverted",
    );
    with(
        "an unknown compression",
        &|b| {
            let at = value_at(b, "compression");
            b[at] = 200;
        },
        "unknown compression 200",
    );
    with(
        "an unknown line order",
        &|b| {
            let at = value_at(b, "lineOrder");
            b[at] = 9;
        },
        "unknown line order 9",
    );
    with(
        "a channel of unknown pixel type",
        &|b| {
            // The first channel's name is one letter and its null: its type follows.
            let at = value_at(b, "channels") + 2;
            put(b, at, &7i32.to_le_bytes());
        },
        "unknown pixel type 7",
    );
    with(
        "an attribute size past the end of the file",
        &|b| {
            let at = value_at(b, "channels") - 4;
            put(b, at, &0x7fff_0000i32.to_le_bytes());
        },
        "bytes are left in the file",
    );
    with("the deep-data flag", &|b| b[5] |= 0x08, "deep data");
    out
}
