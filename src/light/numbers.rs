//! The numeric block of a photometric file read value by value: both IES and EULUMDAT
//! allow values wrapped across lines, so each value keeps the line it came from and every
//! error names that line.

use std::path::{Path, PathBuf};

use metamer_color::text::echo;

use super::photometry::PhotometryError;

/// Splits a photometric file into whitespace/comma separated tokens with their line
/// numbers (both formats allow values wrapped across lines).
pub(crate) fn tokens(text: &str, first_line: usize) -> Vec<(usize, String)> {
    text.lines()
        .enumerate()
        .flat_map(|(i, l)| {
            l.split(|c: char| c.is_whitespace() || c == ',')
                .filter(|t| !t.is_empty())
                .map(move |t| (first_line + i, t.to_string()))
        })
        .collect()
}

/// The values of a file's numeric block, read in order.
pub(crate) struct Numbers {
    toks: Vec<(usize, String)>,
    pos: usize,
    file: PathBuf,
    /// The line a "the file ends before …" error names.
    end_line: usize,
}

impl Numbers {
    pub(crate) fn new(toks: Vec<(usize, String)>, file: &Path, end_line: usize) -> Self {
        Numbers {
            toks,
            pos: 0,
            file: file.to_path_buf(),
            end_line,
        }
    }

    /// A format error at `line` of this file.
    pub(crate) fn error(&self, line: usize, message: String) -> PhotometryError {
        PhotometryError::Format {
            file: self.file.clone(),
            line,
            message,
        }
    }

    /// The next value and its line; `what` names it in errors.
    pub(crate) fn next(&mut self, what: &str) -> Result<(usize, f64), PhotometryError> {
        let Some((line, t)) = self.toks.get(self.pos) else {
            return Err(self.error(self.end_line, format!("the file ends before {what}")));
        };
        self.pos += 1;
        let line = *line;
        t.parse::<f64>()
            .map(|v| (line, v))
            .map_err(|_| self.error(line, format!("{what}: '{}' is not a number", echo(t))))
    }

    /// The next value without its line.
    pub(crate) fn value(&mut self, what: &str) -> Result<f64, PhotometryError> {
        self.next(what).map(|(_, v)| v)
    }

    /// The next `n` values and the line of the first one (0 when `n` is 0). The list grows
    /// with the values actually there, so a count of 4294967296 ends at the end of the
    /// file, not in a 34 GB allocation.
    pub(crate) fn take(
        &mut self,
        n: usize,
        what: &str,
    ) -> Result<(usize, Vec<f64>), PhotometryError> {
        let mut v = Vec::new();
        let mut first_line = 0;
        for k in 0..n {
            let (line, x) = self.next(what)?;
            if k == 0 {
                first_line = line;
            }
            v.push(x);
        }
        Ok((first_line, v))
    }

    /// The token the next call would read, unparsed.
    pub(crate) fn peek(&self) -> Option<&(usize, String)> {
        self.toks.get(self.pos)
    }

    /// The tokens not read yet.
    pub(crate) fn remaining(&self) -> &[(usize, String)] {
        &self.toks[self.pos..]
    }
}
