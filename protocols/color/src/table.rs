//! The spectral CSV form used for every table in `data/`: '#' comment lines (the first names
//! the source), a header whose first column is `nm`, then rows of wavelength and one or more
//! value columns, wavelengths strictly increasing.

use std::path::{Path, PathBuf};

use crate::{ColorError, Outside, Spectrum};

/// A parsed spectral table: a shared wavelength column and named value columns.
#[derive(Clone, Debug, PartialEq)]
pub struct SpectralTable {
    /// Where the table came from (a path, or a name for embedded tables).
    pub source: PathBuf,
    /// Comment lines, without the leading '#', in file order (provenance).
    pub comments: Vec<String>,
    /// Names of the value columns (the header without its `nm` column).
    pub columns: Vec<String>,
    /// Wavelengths in nm.
    pub wavelengths_nm: Vec<f64>,
    /// `data[c][i]` is column `c` at `wavelengths_nm[i]`.
    pub data: Vec<Vec<f64>>,
    /// `lines[i]` is the line of the file (1-based) that holds row `i`, for errors about
    /// a row found after parsing.
    pub lines: Vec<usize>,
}

impl SpectralTable {
    /// Reads and parses a file.
    pub fn read(path: &Path) -> Result<Self, ColorError> {
        let text = crate::text::read_text(path).map_err(|source| ColorError::Io {
            file: path.to_path_buf(),
            source,
        })?;
        Self::parse(&text, path)
    }

    /// Parses CSV text; `source` names it in errors.
    pub fn parse(text: &str, source: impl AsRef<Path>) -> Result<Self, ColorError> {
        let file = source.as_ref().to_path_buf();
        let mut comments = Vec::new();
        let mut header: Option<Vec<String>> = None;
        let mut wavelengths_nm = Vec::new();
        let mut data: Vec<Vec<f64>> = Vec::new();
        let mut lines = Vec::new();
        for (index, raw) in crate::text::strip_bom(text).lines().enumerate() {
            let line = index + 1;
            let trimmed = raw.trim();
            if trimmed.is_empty() {
                continue;
            }
            if let Some(c) = trimmed.strip_prefix('#') {
                comments.push(c.trim().to_string());
                continue;
            }
            let cells: Vec<&str> = trimmed.split(',').map(str::trim).collect();
            let Some(names) = &header else {
                let first = cells[0].to_ascii_lowercase();
                if !(first == "nm" || first.starts_with("wavelength")) || cells.len() < 2 {
                    return Err(ColorError::MissingHeader {
                        file,
                        line,
                        found: crate::text::echo(trimmed),
                    });
                }
                let names: Vec<String> = cells[1..].iter().map(|s| s.to_string()).collect();
                data = vec![Vec::new(); names.len()];
                header = Some(names);
                continue;
            };
            if cells.len() != names.len() + 1 {
                return Err(ColorError::ColumnCount {
                    file,
                    line,
                    expected: names.len() + 1,
                    found: cells.len(),
                });
            }
            let mut row = Vec::with_capacity(cells.len());
            for (column, cell) in cells.iter().enumerate() {
                match cell.parse::<f64>() {
                    Ok(v) if v.is_finite() => row.push(v),
                    _ => {
                        return Err(ColorError::BadNumber {
                            file,
                            line,
                            column: column + 1,
                            name: if column == 0 {
                                "nm".into()
                            } else {
                                names[column - 1].clone()
                            },
                            cell: crate::text::echo(cell),
                        })
                    }
                }
            }
            // No light has a wavelength of zero or less: such a row is a wrong column or unit.
            if row[0] <= 0.0 {
                return Err(ColorError::NotPositive {
                    file,
                    line,
                    nm: row[0],
                });
            }
            if let Some(&previous) = wavelengths_nm.last() {
                if row[0] <= previous {
                    return Err(ColorError::NotIncreasing {
                        file,
                        line,
                        nm: row[0],
                        previous,
                    });
                }
            }
            wavelengths_nm.push(row[0]);
            lines.push(line);
            for (c, v) in row[1..].iter().enumerate() {
                data[c].push(*v);
            }
        }
        let Some(columns) = header else {
            return Err(ColorError::Empty { file });
        };
        if wavelengths_nm.is_empty() {
            return Err(ColorError::NoData { file });
        }
        Ok(SpectralTable {
            source: file,
            comments,
            columns,
            wavelengths_nm,
            data,
            lines,
        })
    }

    /// Column `index` (0 = first value column) as a spectrum.
    pub fn spectrum(&self, index: usize) -> Spectrum {
        Spectrum::new(self.wavelengths_nm.clone(), self.data[index].clone())
            .expect("validated while parsing")
    }

    /// The column whose header equals `name` (case-insensitive) or, for ColorChecker-style
    /// headers like `3:blue sky`, whose part before ':' equals `name`.
    pub fn column(&self, name: &str) -> Result<Spectrum, ColorError> {
        let want = name.trim().to_ascii_lowercase();
        self.columns
            .iter()
            .position(|c| {
                let c = c.to_ascii_lowercase();
                c == want || c.split(':').next() == Some(want.as_str())
            })
            .map(|i| self.spectrum(i))
            .ok_or_else(|| ColorError::NoSuchColumn {
                file: self.source.clone(),
                column: crate::text::echo(name),
                available: self.columns.join(", "),
            })
    }

    /// The only value column, or the first when there are several.
    pub fn first(&self) -> Spectrum {
        self.spectrum(0)
    }

    /// Every column as a spectrum with the given rule outside the table.
    pub fn all(&self, outside: Outside) -> Vec<Spectrum> {
        (0..self.columns.len())
            .map(|i| self.spectrum(i).with_outside(outside))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_comments_header_and_columns() {
        let t =
            SpectralTable::parse("# source: test\nnm,a,b\n400,1,2\n410, 3 ,4\n", "t.csv").unwrap();
        assert_eq!(t.comments, vec!["source: test"]);
        assert_eq!(t.columns, vec!["a", "b"]);
        assert_eq!(t.wavelengths_nm, vec![400.0, 410.0]);
        assert_eq!(t.column("b").unwrap().values(), &[2.0, 4.0]);
    }

    #[test]
    fn rows_keep_their_lines_and_wavelengths_are_positive() {
        let t = SpectralTable::parse("# c\nnm,a\n\n400,1\n# mid\n410,2\n", "t.csv").unwrap();
        assert_eq!(t.lines, vec![4, 6]);
        for (text, line, nm) in [
            ("nm,a\n-5,1\n400,1\n", 2, "-5"),
            ("nm,a\n400,1\n# x\n0,1\n", 4, "0"),
        ] {
            let e = SpectralTable::parse(text, "w.csv").unwrap_err().to_string();
            assert_eq!(
                e,
                format!(
                    "w.csv:{line}: wavelength {nm} nm: wavelengths are positive numbers of nanometres"
                )
            );
        }
    }

    #[test]
    fn each_malformation_names_file_and_line() {
        let e = SpectralTable::parse("", "e.csv").unwrap_err().to_string();
        assert!(e.contains("e.csv") && e.contains("empty"), "{e}");
        let e = SpectralTable::parse("# only a comment\n", "e.csv")
            .unwrap_err()
            .to_string();
        assert!(e.contains("empty"), "{e}");
        let e = SpectralTable::parse("400,1\n410,2\n", "h.csv")
            .unwrap_err()
            .to_string();
        assert_eq!(
            e,
            "h.csv:1: missing header: expected a line like 'nm,value' (first column 'nm'), found '400,1'"
        );
        let e = SpectralTable::parse("nm,v\n400,1\n410,abc\n", "n.csv")
            .unwrap_err()
            .to_string();
        assert_eq!(e, "n.csv:3: column 2 ('v'): 'abc' is not a number");
        let e = SpectralTable::parse("nm,v\n400,1\n400,2\n", "i.csv")
            .unwrap_err()
            .to_string();
        assert_eq!(
            e,
            "i.csv:3: wavelengths must increase: 400 nm follows 400 nm"
        );
        let e = SpectralTable::parse("nm,v\n400,1,2\n", "c.csv")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("c.csv:2: expected 2"), "{e}");
        let e = SpectralTable::parse("nm,v\n", "d.csv")
            .unwrap_err()
            .to_string();
        assert!(e.contains("no data rows"), "{e}");
    }
}
