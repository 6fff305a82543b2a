//! Version 2.4 from the encoder's version 4 output: the tag types of a matrix/TRC or lut16
//! display profile are the same in both versions except the text tags, so the header's
//! version is set to 2.4 and `desc` / `cprt` are replaced by `textDescriptionType` and
//! `textType` (ICC.1:2001-04 6.5.17 and 6.5.18); the tag table is laid out again.

const HEADER: usize = 128;
const ENTRY: usize = 12;

fn be32(bytes: &[u8], at: usize) -> Option<u32> {
    Some(u32::from_be_bytes(bytes.get(at..at + 4)?.try_into().ok()?))
}

/// `textDescriptionType`: ASCII with its count, then empty Unicode and ScriptCode parts.
fn text_description(text: &str) -> Vec<u8> {
    let ascii: Vec<u8> = text
        .chars()
        .map(|c| if c.is_ascii() { c as u8 } else { b'?' })
        .collect();
    let mut out = b"desc".to_vec();
    out.extend([0; 4]);
    out.extend((ascii.len() as u32 + 1).to_be_bytes());
    out.extend(&ascii);
    out.push(0);
    out.extend([0; 4]); // Unicode language code
    out.extend([0; 4]); // Unicode count
    out.extend([0; 2]); // ScriptCode code
    out.push(0); // ScriptCode count
    out.extend([0; 67]);
    out
}

/// `textType`: NUL-terminated ASCII.
fn text(text: &str) -> Vec<u8> {
    let mut out = b"text".to_vec();
    out.extend([0; 4]);
    out.extend(
        text.chars()
            .map(|c| if c.is_ascii() { c as u8 } else { b'?' }),
    );
    out.push(0);
    out
}

/// The version 2.4 form of an encoded version 4 profile.
pub fn to_version_2(v4: &[u8], description: &str, copyright: &str) -> Result<Vec<u8>, String> {
    let count = be32(v4, HEADER).ok_or("the encoded profile has no tag table")? as usize;
    let mut tags: Vec<([u8; 4], Vec<u8>)> = Vec::with_capacity(count);
    for t in 0..count {
        let at = HEADER + 4 + t * ENTRY;
        let (Some(sig), Some(offset), Some(size)) =
            (v4.get(at..at + 4), be32(v4, at + 4), be32(v4, at + 8))
        else {
            return Err(format!("tag {t} of the encoded profile is cut off"));
        };
        let sig: [u8; 4] = sig.try_into().expect("four bytes");
        let data = match &sig {
            b"desc" => text_description(description),
            b"cprt" => text(copyright),
            _ => v4
                .get(offset as usize..(offset + size) as usize)
                .ok_or_else(|| {
                    format!(
                        "tag {} lies beyond the profile's end",
                        String::from_utf8_lossy(&sig)
                    )
                })?
                .to_vec(),
        };
        tags.push((sig, data));
    }
    let mut table = Vec::with_capacity(4 + count * ENTRY);
    table.extend((count as u32).to_be_bytes());
    let mut data = Vec::new();
    let start = HEADER + 4 + count * ENTRY;
    for (sig, bytes) in &tags {
        while (start + data.len()) % 4 != 0 {
            data.push(0);
        }
        table.extend(sig);
        table.extend(((start + data.len()) as u32).to_be_bytes());
        table.extend((bytes.len() as u32).to_be_bytes());
        data.extend(bytes);
    }
    let mut out = v4[..HEADER].to_vec();
    out.extend(table);
    out.extend(data);
    let size = out.len() as u32;
    out[0..4].copy_from_slice(&size.to_be_bytes());
    out[8..12].copy_from_slice(&0x0240_0000u32.to_be_bytes());
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn text_description_has_the_layout_of_icc_2001_04() {
        let d = text_description("ab");
        // sig, reserved, count, "ab\0", language, count, script code, count, 67 bytes.
        assert_eq!(d.len(), 4 + 4 + 4 + 3 + 4 + 4 + 2 + 1 + 67);
        assert_eq!(&d[8..12], &3u32.to_be_bytes());
        assert_eq!(&d[12..15], b"ab\0");
    }
}
