//! What every step of building a scene shares: its error (the JSON path of the bad field
//! and what is wrong there) and the loader that reads the spectra a scene names, each file
//! once, onto the 1 nm grid.

use std::collections::HashMap;
use std::path::Path;

use super::super::spectral::{bins, constant_bins};
use super::builtin;
use super::file::SpectrumRef;
use super::model::MAX_REFLECTANCE;
use super::reader::PathError;
use crate::color::{Outside, SpectralTable, Spectrum};

/// A step of the build: its error names the JSON path of the bad field.
pub(super) type R<T> = Result<T, PathError>;

pub(super) fn err<T>(path: impl Into<String>, message: impl Into<String>) -> R<T> {
    Err(PathError {
        path: path.into(),
        message: message.into(),
    })
}

/// Where the spectral CSV files a scene names are found.
#[derive(Clone, Copy)]
pub enum SpectrumFiles<'a> {
    /// Relative to the scene file's directory.
    Dir(&'a Path),
    /// The data files compiled into the binary (the built-in scenes).
    Builtin,
}

/// Spectra read so far: a file named by a thousand tiles is read once.
pub(super) struct Loader<'a> {
    pub(super) files: SpectrumFiles<'a>,
    tables: HashMap<String, SpectralTable>,
}

impl<'a> Loader<'a> {
    pub(super) fn new(files: SpectrumFiles<'a>) -> Loader<'a> {
        Loader {
            files,
            tables: HashMap::new(),
        }
    }

    fn table(&mut self, p: &str, file: &str) -> R<&SpectralTable> {
        if !self.tables.contains_key(file) {
            let t = match self.files {
                SpectrumFiles::Dir(dir) => SpectralTable::read(&dir.join(file)),
                SpectrumFiles::Builtin => match builtin::data_file(file) {
                    Some(text) => SpectralTable::parse(text, file),
                    None => {
                        return err(
                            format!("{p}.file"),
                            format!(
                                "{file} is not one of the data files built into the program ({})",
                                builtin::DATA_FILES.join(", ")
                            ),
                        )
                    }
                },
            }
            .map_err(|e| PathError {
                path: format!("{p}.file"),
                message: e.to_string(),
            })?;
            self.tables.insert(file.to_string(), t);
        }
        Ok(&self.tables[file])
    }

    /// A spectrum on the 1 nm grid; every value finite.
    pub(super) fn spectrum(&mut self, p: &str, s: &SpectrumRef) -> R<Vec<f64>> {
        let sp = match s {
            SpectrumRef::Constant(v) => {
                if !v.is_finite() {
                    return err(p, "must be finite");
                }
                return Ok(constant_bins(*v));
            }
            SpectrumRef::File {
                file,
                column,
                outside,
            } => {
                let table = self.table(p, file)?;
                let col = column.unwrap_or(1);
                if col == 0 || col > table.columns.len() {
                    return err(
                        format!("{p}.column"),
                        format!("must be 1–{}, got {col}", table.columns.len()),
                    );
                }
                table
                    .spectrum(col - 1)
                    .with_outside(outside.unwrap_or(Outside::Zero))
            }
            SpectrumRef::Inline {
                nm,
                values,
                outside,
            } => Spectrum::new(nm.clone(), values.clone())
                .map_err(|e| PathError {
                    path: p.into(),
                    message: e.to_string(),
                })?
                .with_outside(outside.unwrap_or(Outside::Zero)),
        };
        let b = bins(&sp);
        if b.iter().any(|v| !v.is_finite()) {
            return err(p, "must be finite");
        }
        Ok(b)
    }

    /// A reflectance: in [0, 1], or up to [`MAX_REFLECTANCE`] with a warning.
    pub(super) fn reflectance(
        &mut self,
        p: &str,
        s: &SpectrumRef,
        warnings: &mut Vec<String>,
    ) -> R<Vec<f64>> {
        let r = self.spectrum(p, s)?;
        let (i, max) = r
            .iter()
            .cloned()
            .enumerate()
            .fold((0, f64::NEG_INFINITY), |a, b| if b.1 > a.1 { b } else { a });
        if let Some(x) = r.iter().find(|x| **x < 0.0) {
            return err(p, format!("reflectance must be in [0, 1], found {x}"));
        }
        if max > MAX_REFLECTANCE {
            return err(
                p,
                format!(
                    "reflectance must be in [0, 1] (up to {MAX_REFLECTANCE} is accepted as \
                     measurement noise), found {max} at {} nm",
                    380 + i
                ),
            );
        }
        if max > 1.0 {
            warnings.push(format!(
                "{p}: reflectance {max:.4} at {} nm is above 1; accepted as measurement noise \
                 (limit {MAX_REFLECTANCE})",
                380 + i
            ));
        }
        Ok(r)
    }
}
