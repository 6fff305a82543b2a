//! Errors of the colour core: every data error names the file (or source) and the line.

use std::path::PathBuf;

/// What went wrong reading or using spectral data.
#[derive(Debug, thiserror::Error)]
pub enum ColorError {
    /// The file could not be read at all.
    #[error("{file}: cannot read: {source}")]
    Io {
        file: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// The file has no lines other than comments and blank lines.
    #[error("{file}: the file is empty (expected a header line such as 'nm,value' and data rows)")]
    Empty { file: PathBuf },
    /// The first non-comment line is not a header starting with `nm`.
    #[error("{file}:{line}: missing header: expected a line like 'nm,value' (first column 'nm'), found '{found}'")]
    MissingHeader {
        file: PathBuf,
        line: usize,
        found: String,
    },
    /// A header was found but no data rows follow it.
    #[error("{file}: no data rows after the header")]
    NoData { file: PathBuf },
    /// A cell does not hold a finite number.
    #[error("{file}:{line}: column {column} ('{name}'): '{cell}' is not a number")]
    BadNumber {
        file: PathBuf,
        line: usize,
        column: usize,
        name: String,
        cell: String,
    },
    /// A row has a different number of cells than the header.
    #[error("{file}:{line}: expected {expected} comma-separated values (as in the header), found {found}")]
    ColumnCount {
        file: PathBuf,
        line: usize,
        expected: usize,
        found: usize,
    },
    /// A wavelength of zero or less.
    #[error("{file}:{line}: wavelength {nm} nm: wavelengths are positive numbers of nanometres")]
    NotPositive { file: PathBuf, line: usize, nm: f64 },
    /// Wavelengths must rise strictly from row to row.
    #[error("{file}:{line}: wavelengths must increase: {nm} nm follows {previous} nm")]
    NotIncreasing {
        file: PathBuf,
        line: usize,
        nm: f64,
        previous: f64,
    },
    /// A column requested by name or index is not in the table.
    #[error("{file}: no column '{column}' (columns: {available})")]
    NoSuchColumn {
        file: PathBuf,
        column: String,
        available: String,
    },
    /// A spectrum built in code is malformed.
    #[error("invalid spectrum: {0}")]
    InvalidSpectrum(String),
    /// A named table (illuminant, observer) is not known.
    #[error("unknown {kind} '{name}' (known: {known})")]
    UnknownName {
        kind: &'static str,
        name: String,
        known: &'static str,
    },
}
