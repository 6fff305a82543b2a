//! Version 2.4 from the encoder's version 4 output: the tag types of a matrix/TRC or lut16
//! display profile are the same in both versions except the text tags, so the header's
//! version is set to 2.4 and `desc` / `cprt` are replaced by `textDescriptionType` and
//! `textType` (ICC.1:2001-04 6.5.17 and 6.5.18); the tag table is laid out again.

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

/// The version 2.4 form of an encoded version 4 profile, laid out as [`super::layout`] says.
pub fn to_version_2(v4: &[u8], description: &str, copyright: &str) -> Result<Vec<u8>, String> {
    super::layout::relayout(v4, 0x0240_0000, |sig| match sig {
        b"desc" => Some(text_description(description)),
        b"cprt" => Some(text(copyright)),
        _ => None,
    })
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
