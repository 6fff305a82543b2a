//! The two things every text reader of the workspace does to its input: a UTF-8 byte-order
//! mark (which spreadsheet programs put at the start of CSV files they save) is not part of
//! the first field, and input echoed in an error message is cut to a readable length, so a
//! one-megabyte field does not become a one-megabyte message.

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
