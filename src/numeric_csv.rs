//! Plain numeric CSV files with one header line (`L1,a1,b1,…`, `r,g,b,X,Y,Z`, `X,Y,Z`):
//! '#' comment lines and blank lines are skipped, every other cell must be a finite number.
//! Errors name the file, the line and the cell, so a user can fix the file.

use std::path::{Path, PathBuf};

/// A numeric CSV file: header names and rows, each row with its line number.
#[derive(Clone, Debug, PartialEq)]
pub struct NumericCsv {
    pub source: PathBuf,
    pub header: Vec<String>,
    /// `(line number, values)` in file order.
    pub rows: Vec<(usize, Vec<f64>)>,
}

/// What is wrong with a numeric CSV file.
#[derive(Debug, thiserror::Error)]
pub enum CsvError {
    #[error("{file}: cannot read: {source}")]
    Io {
        file: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{file}: the file is empty (expected the header '{expected}' and data rows)")]
    Empty { file: PathBuf, expected: String },
    #[error("{file}:{line}: expected the header '{expected}', found '{found}'")]
    BadHeader {
        file: PathBuf,
        line: usize,
        expected: String,
        found: String,
    },
    #[error("{file}:{line}: expected {expected} values, found {found}")]
    ColumnCount {
        file: PathBuf,
        line: usize,
        expected: usize,
        found: usize,
    },
    #[error("{file}:{line}: column {column} ('{name}'): '{cell}' is not a number")]
    BadNumber {
        file: PathBuf,
        line: usize,
        column: usize,
        name: String,
        cell: String,
    },
    #[error("{file}: no data rows after the header")]
    NoData { file: PathBuf },
}

impl NumericCsv {
    /// Reads a file whose header must be exactly `expected` (case-insensitive, spaces ignored).
    pub fn read(path: &Path, expected: &[&str]) -> Result<Self, CsvError> {
        let text = metamer_color::text::read_text(path).map_err(|source| CsvError::Io {
            file: path.to_path_buf(),
            source,
        })?;
        Self::parse(&text, path, expected)
    }

    /// Parses text; `source` names it in errors.
    pub fn parse(text: &str, source: &Path, expected: &[&str]) -> Result<Self, CsvError> {
        let file = source.to_path_buf();
        let want = expected.join(",");
        let mut header: Option<Vec<String>> = None;
        let mut rows = Vec::new();
        for (index, raw) in metamer_color::text::strip_bom(text).lines().enumerate() {
            let line = index + 1;
            let trimmed = raw.trim();
            if trimmed.is_empty() || trimmed.starts_with('#') {
                continue;
            }
            let cells: Vec<&str> = trimmed.split(',').map(str::trim).collect();
            if header.is_none() {
                let names: Vec<String> = cells.iter().map(|c| c.to_string()).collect();
                let matches = names.len() == expected.len()
                    && names
                        .iter()
                        .zip(expected)
                        .all(|(n, e)| n.eq_ignore_ascii_case(e));
                if !matches {
                    return Err(CsvError::BadHeader {
                        file,
                        line,
                        expected: want,
                        found: metamer_color::text::echo(trimmed),
                    });
                }
                header = Some(names);
                continue;
            }
            if cells.len() != expected.len() {
                return Err(CsvError::ColumnCount {
                    file,
                    line,
                    expected: expected.len(),
                    found: cells.len(),
                });
            }
            let mut values = Vec::with_capacity(cells.len());
            for (column, cell) in cells.iter().enumerate() {
                match cell.parse::<f64>() {
                    Ok(v) if v.is_finite() => values.push(v),
                    _ => {
                        return Err(CsvError::BadNumber {
                            file,
                            line,
                            column: column + 1,
                            name: expected[column].to_string(),
                            cell: metamer_color::text::echo(cell),
                        })
                    }
                }
            }
            rows.push((line, values));
        }
        let Some(header) = header else {
            return Err(CsvError::Empty {
                file,
                expected: want,
            });
        };
        if rows.is_empty() {
            return Err(CsvError::NoData { file });
        }
        Ok(NumericCsv {
            source: file,
            header,
            rows,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_and_reports_line_numbers() {
        let p = Path::new("p.csv");
        let t = NumericCsv::parse("# c\nX,Y,Z\n1,2,3\n\n4,5,6\n", p, &["X", "Y", "Z"]).unwrap();
        assert_eq!(
            t.rows,
            vec![(3, vec![1.0, 2.0, 3.0]), (5, vec![4.0, 5.0, 6.0])]
        );
        let e = NumericCsv::parse("X,Y\n1,2\n", p, &["X", "Y", "Z"]).unwrap_err();
        assert_eq!(
            e.to_string(),
            "p.csv:1: expected the header 'X,Y,Z', found 'X,Y'"
        );
        let e = NumericCsv::parse("X,Y,Z\n1,2,nan\n", p, &["X", "Y", "Z"]).unwrap_err();
        assert_eq!(
            e.to_string(),
            "p.csv:2: column 3 ('Z'): 'nan' is not a number"
        );
        let e = NumericCsv::parse("X,Y,Z\n1,2\n", p, &["X", "Y", "Z"]).unwrap_err();
        assert_eq!(e.to_string(), "p.csv:2: expected 3 values, found 2");
        let e = NumericCsv::parse("", p, &["X", "Y", "Z"]).unwrap_err();
        assert!(e.to_string().contains("empty"));
        let e = NumericCsv::parse("X,Y,Z\n", p, &["X", "Y", "Z"]).unwrap_err();
        assert!(e.to_string().contains("no data rows"));
    }
}
