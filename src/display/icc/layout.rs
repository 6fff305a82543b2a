//! The tag table laid out as ICC.1:2010 §7 asks: every tag's data starts on a 4-byte
//! boundary (offsets from the start of the profile), the gaps and the end are padded with
//! zeros, so the profile's size is a multiple of 4, and the header's size field says it.
//! The encoder writes tags back to back whatever their length; this rewrites its output,
//! optionally replacing some tags' data (version 2's text types).

pub const HEADER: usize = 128;
const ENTRY: usize = 12;

fn be32(bytes: &[u8], at: usize) -> Option<u32> {
    Some(u32::from_be_bytes(bytes.get(at..at + 4)?.try_into().ok()?))
}

/// One tag: its signature and its data.
pub type Tag = ([u8; 4], Vec<u8>);

/// The tags of a profile in table order.
pub fn tags(profile: &[u8]) -> Result<Vec<Tag>, String> {
    let count = be32(profile, HEADER).ok_or("the encoded profile has no tag table")? as usize;
    let mut out = Vec::with_capacity(count);
    for t in 0..count {
        let at = HEADER + 4 + t * ENTRY;
        let (Some(sig), Some(offset), Some(size)) = (
            profile.get(at..at + 4),
            be32(profile, at + 4),
            be32(profile, at + 8),
        ) else {
            return Err(format!("tag {t} of the encoded profile is cut off"));
        };
        let sig: [u8; 4] = sig.try_into().expect("four bytes");
        let data = profile
            .get(offset as usize..offset as usize + size as usize)
            .ok_or_else(|| {
                format!(
                    "tag {} lies beyond the profile's end",
                    String::from_utf8_lossy(&sig)
                )
            })?;
        out.push((sig, data.to_vec()));
    }
    Ok(out)
}

/// `profile` with its tags aligned and padded, each tag's data replaced by `replace(sig)`
/// where that gives some, and the header's version set to `version`.
pub fn relayout(
    profile: &[u8],
    version: u32,
    replace: impl Fn(&[u8; 4]) -> Option<Vec<u8>>,
) -> Result<Vec<u8>, String> {
    let header = profile
        .get(..HEADER)
        .ok_or("the encoded profile has no header")?;
    let tags = tags(profile)?;
    let start = HEADER + 4 + tags.len() * ENTRY;
    let mut table = Vec::with_capacity(4 + tags.len() * ENTRY);
    table.extend((tags.len() as u32).to_be_bytes());
    let mut data = Vec::new();
    for (sig, bytes) in &tags {
        let bytes = replace(sig).unwrap_or_else(|| bytes.clone());
        while (start + data.len()) % 4 != 0 {
            data.push(0);
        }
        table.extend(sig);
        table.extend(((start + data.len()) as u32).to_be_bytes());
        table.extend((bytes.len() as u32).to_be_bytes());
        data.extend(bytes);
    }
    while (start + data.len()) % 4 != 0 {
        data.push(0);
    }
    let mut out = header.to_vec();
    out.extend(table);
    out.extend(data);
    let size = out.len() as u32;
    out[0..4].copy_from_slice(&size.to_be_bytes());
    out[8..12].copy_from_slice(&version.to_be_bytes());
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A header and a table of two tags of 5 and 3 bytes, written back to back.
    fn packed() -> Vec<u8> {
        let mut p = vec![0u8; HEADER];
        p.extend(2u32.to_be_bytes());
        let start = (HEADER + 4 + 2 * ENTRY) as u32;
        p.extend(b"aaaa");
        p.extend(start.to_be_bytes());
        p.extend(5u32.to_be_bytes());
        p.extend(b"bbbb");
        p.extend((start + 5).to_be_bytes());
        p.extend(3u32.to_be_bytes());
        p.extend(b"12345xyz");
        p
    }

    #[test]
    fn tags_start_on_4_byte_boundaries_and_the_size_is_a_multiple_of_4() {
        let out = relayout(&packed(), 0x0430_0000, |_| None).unwrap();
        let t = tags(&out).unwrap();
        assert_eq!(t[0], (*b"aaaa", b"12345".to_vec()));
        assert_eq!(t[1], (*b"bbbb", b"xyz".to_vec()));
        for i in 0..2 {
            assert_eq!(be32(&out, HEADER + 4 + i * ENTRY + 4).unwrap() % 4, 0);
        }
        assert_eq!(out.len() % 4, 0);
        assert_eq!(be32(&out, 0).unwrap() as usize, out.len());
        assert_eq!(be32(&out, 8).unwrap(), 0x0430_0000);
        let replaced = relayout(&packed(), 0x0240_0000, |s| {
            (s == b"bbbb").then(|| b"new!".to_vec())
        })
        .unwrap();
        assert_eq!(tags(&replaced).unwrap()[1].1, b"new!");
    }

    #[test]
    fn a_truncated_table_is_an_error() {
        let p = packed();
        assert!(relayout(&p[..HEADER + 10], 0, |_| None).is_err());
        assert!(relayout(&p[..p.len() - 2], 0, |_| None).is_err());
    }
}
