//! The two things every text reader of the workspace does to its input: a UTF-8 byte-order
//! mark (which spreadsheet programs put at the start of CSV files they save) is not part of
//! the first field, and input echoed in an error message is cut to a readable length, so a
//! one-megabyte field does not become a one-megabyte message.

/// Largest file a reader of text (measurements, profiles, scenes, plans, journals,
/// photometric files) takes: a hundred times the largest such file a session writes.
pub const MAX_INPUT_BYTES: u64 = 256 << 20;

/// The bytes of `path`, at most `limit` of them: a device that never ends (`/dev/zero`
/// given as a file) is an error, not a read that fills the memory. Pipes and devices are
/// still read, so `<(command)` and `/dev/stdin` work.
pub fn read_bytes_at_most(path: &std::path::Path, limit: u64) -> std::io::Result<Vec<u8>> {
    use std::io::Read;
    let mut bytes = Vec::new();
    std::fs::File::open(path)?
        .take(limit.saturating_add(1))
        .read_to_end(&mut bytes)?;
    if bytes.len() as u64 > limit {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!(
                "more than {} MB, larger than any file of this kind (is it a device?)",
                limit >> 20
            ),
        ));
    }
    Ok(bytes)
}

/// [`read_bytes_at_most`] of [`MAX_INPUT_BYTES`].
pub fn read_bytes(path: &std::path::Path) -> std::io::Result<Vec<u8>> {
    read_bytes_at_most(path, MAX_INPUT_BYTES)
}

/// [`read_bytes`] as UTF-8 text, with the error `std::fs::read_to_string` gives.
pub fn read_text(path: &std::path::Path) -> std::io::Result<String> {
    String::from_utf8(read_bytes(path)?).map_err(|_| {
        std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            "stream did not contain valid UTF-8",
        )
    })
}

/// How many characters of a user's input an error message quotes.
pub const ECHO_CHARS: usize = 80;

/// The text without a leading UTF-8 byte-order mark.
pub fn strip_bom(text: &str) -> &str {
    text.strip_prefix('\u{feff}').unwrap_or(text)
}

/// Input quoted in an error: at most [`ECHO_CHARS`] characters, and when it was cut, an
/// ellipsis and the full length, so the reader knows there was more.
pub fn echo(input: &str) -> String {
    let mut chars = input.char_indices();
    match chars.nth(ECHO_CHARS) {
        None => input.to_string(),
        Some((cut, _)) => format!(
            "{}… ({} characters in all)",
            &input[..cut],
            input.chars().count()
        ),
    }
}

/// A parser's message that may quote the input (serde's "invalid type: string \"…\"" does),
/// cut in the middle so both its start and its end (serde's "at line L column C") remain.
pub fn echo_message(message: &str) -> String {
    const TAIL: usize = 40;
    let count = message.chars().count();
    if count <= ECHO_CHARS + TAIL {
        return message.to_string();
    }
    let head: String = message.chars().take(ECHO_CHARS).collect();
    let tail: String = message.chars().skip(count - TAIL).collect();
    format!("{head}…{tail}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_read_stops_at_its_limit() {
        // /dev/zero never ends: read_to_string would fill the memory.
        let e = read_bytes_at_most(std::path::Path::new("/dev/zero"), 1 << 20).unwrap_err();
        assert_eq!(e.kind(), std::io::ErrorKind::InvalidData);
        assert!(e.to_string().starts_with("more than 1 MB"), "{e}");
        let p = std::env::temp_dir().join(format!("metamer-text-{}", std::process::id()));
        std::fs::write(&p, b"nm,a\n\xff").unwrap();
        assert_eq!(read_bytes(&p).unwrap(), b"nm,a\n\xff");
        assert_eq!(
            read_text(&p).unwrap_err().to_string(),
            std::fs::read_to_string(&p).unwrap_err().to_string()
        );
        std::fs::remove_file(&p).unwrap();
    }

    #[test]
    fn a_bom_is_removed_once_and_only_at_the_start() {
        assert_eq!(strip_bom("\u{feff}nm,a"), "nm,a");
        assert_eq!(strip_bom("nm,\u{feff}a"), "nm,\u{feff}a");
        assert_eq!(strip_bom("\u{feff}\u{feff}x"), "\u{feff}x");
    }

    #[test]
    fn a_long_message_keeps_its_start_and_its_position() {
        let m = format!(
            "invalid type: string \"{}\", expected f64 at line 3 column 9",
            "y".repeat(5000)
        );
        let shown = echo_message(&m);
        assert_eq!(shown.chars().count(), 80 + 1 + 40);
        assert!(shown.starts_with("invalid type: string \"yyy"));
        assert!(shown.ends_with("expected f64 at line 3 column 9"));
        assert_eq!(echo_message("short"), "short");
    }

    #[test]
    fn long_input_is_cut_to_80_characters_with_its_length() {
        assert_eq!(echo("short"), "short");
        let exactly = "é".repeat(80);
        assert_eq!(echo(&exactly), exactly);
        let long = "x".repeat(1_000_000);
        let shown = echo(&long);
        assert_eq!(
            shown,
            format!("{}… (1000000 characters in all)", "x".repeat(80))
        );
    }
}
