//! The CSV form of readings `validate` takes: `patch,X,Y,Z` and optional columns, in any
//! order, names matched without regard to case:
//!
//! - `sd_X,sd_Y,sd_Z`: standard deviation of one reading. With `n` ≥ 2 it is taken as the
//!   sample's of those n readings (n − 1 degrees of freedom); with n = 1 as a stated,
//!   known repeatability.
//! - `cov_XY,cov_XZ,cov_YZ`: the covariances of one reading that go with the sd columns
//!   (all three or none; without them the axes are independent).
//! - `n`: readings the row averages (default 1).
//! - `u_lab`: a renderer's standard uncertainty per CIELAB axis.
//! - `out_of_gamut`: 1 where the display cannot show the colour.
//! - `dof`: the degrees of freedom of the sd and cov columns where they are not the row's
//!   own sample's: a repeatability pooled across the patches one instrument read in one
//!   mode ([`crate::validation::sequential::pool`]); an empty cell states them known.
//!   Without the column they are n − 1 for n ≥ 2, known for n = 1.
//! - `most`: the most readings the rule that read the patch could have taken, where it
//!   stopped on what the readings said (a verdict rule); its comparisons then take the
//!   repeated interval, valid at whatever count it stopped ([`crate::validation::assess`]).
//!
//! The experiment's stages write `patch,X,Y,Z,sd_X,sd_Y,sd_Z,n,cov_XY,cov_XZ,cov_YZ,u_lab`,
//! followed by `dof` and `most` where a stage's repeats were read by a rule.

use super::*;
use crate::validation::sequential::MOST_LOOKS;

/// The most degrees of freedom a `dof` cell states: 3 per reading beyond each patch's
/// first, for far more readings than any session takes.
const MAX_DOF: usize = 1_000_000;

/// Where each column of a CSV header is.
struct Columns {
    names: Vec<String>,
    patch: usize,
    xyz: [usize; 3],
    sd: Option<[usize; 3]>,
    cov: Option<[usize; 3]>,
    n: Option<usize>,
    out_of_gamut: Option<usize>,
    u_lab: Option<usize>,
    dof: Option<usize>,
    most: Option<usize>,
}

impl Parsed {
    /// `patch,X,Y,Z` and the optional columns above.
    pub(super) fn csv(&mut self, text: &str) -> Result<(), ReadingsError> {
        let mut lines = text
            .lines()
            .enumerate()
            .map(|(i, l)| (i + 1, l.trim()))
            .filter(|(_, l)| !l.is_empty() && !l.starts_with('#'));
        let (hline, header) = lines.next().expect("sniffed a first line");
        let columns = self.csv_header(hline, header)?;
        for (line, l) in lines {
            let row = self.csv_row(&columns, line, l)?;
            self.rows.push(row);
        }
        Ok(())
    }

    /// The header's columns: the four required, each optional group whole or absent.
    fn csv_header(&self, hline: usize, header: &str) -> Result<Columns, ReadingsError> {
        let names: Vec<String> = header.split(',').map(|c| c.trim().to_string()).collect();
        let col = |name: &str| names.iter().position(|n| n.eq_ignore_ascii_case(name));
        let need = |name: &str| {
            col(name).ok_or_else(|| {
                self.bad(
                    hline,
                    format!(
                        "the header '{}' lacks the column '{name}' (expected patch,X,Y,Z with optional sd_X,sd_Y,sd_Z, cov_XY,cov_XZ,cov_YZ, n, u_lab, out_of_gamut, dof, most)",
                        echo(header)
                    ),
                )
            })
        };
        let (patch, x, y, z) = (need("patch")?, need("X")?, need("Y")?, need("Z")?);
        let sd = match (col("sd_X"), col("sd_Y"), col("sd_Z")) {
            (Some(a), Some(b), Some(c)) => Some([a, b, c]),
            (None, None, None) => None,
            _ => return Err(self.bad(hline, "give all three of sd_X, sd_Y, sd_Z or none")),
        };
        let cov = match (col("cov_XY"), col("cov_XZ"), col("cov_YZ")) {
            (Some(a), Some(b), Some(c)) if sd.is_some() => Some([a, b, c]),
            (None, None, None) => None,
            (Some(_), Some(_), Some(_)) => {
                return Err(self.bad(
                    hline,
                    "cov_XY, cov_XZ, cov_YZ need the sd_X, sd_Y, sd_Z they go with",
                ))
            }
            _ => return Err(self.bad(hline, "give all three of cov_XY, cov_XZ, cov_YZ or none")),
        };
        let (n, out_of_gamut, u_lab) = (col("n"), col("out_of_gamut"), col("u_lab"));
        let (dof, most) = (col("dof"), col("most"));
        if dof.is_some() && sd.is_none() {
            return Err(self.bad(
                hline,
                "dof needs the sd_X, sd_Y, sd_Z whose degrees of freedom it gives",
            ));
        }
        Ok(Columns {
            names,
            patch,
            xyz: [x, y, z],
            sd,
            cov,
            n,
            out_of_gamut,
            u_lab,
            dof,
            most,
        })
    }

    /// One data row under `c`; its cells are checked in the order of the columns' rules
    /// (count, patch, spread, n, gamut flag, covariances, u_lab, X Y Z).
    fn csv_row(&self, c: &Columns, line: usize, l: &str) -> Result<Row, ReadingsError> {
        let cells: Vec<&str> = l.split(',').map(str::trim).collect();
        if cells.len() != c.names.len() {
            return Err(self.bad(
                line,
                format!(
                    "expected {} cells as in the header, found {}",
                    c.names.len(),
                    cells.len()
                ),
            ));
        }
        let num = |k: usize| -> Result<f64, ReadingsError> {
            cells[k]
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| {
                    self.bad(
                        line,
                        format!("{}: '{}' is not a number", c.names[k], echo(cells[k])),
                    )
                })
        };
        let three = |k: [usize; 3]| -> Result<[f64; 3], ReadingsError> {
            Ok([num(k[0])?, num(k[1])?, num(k[2])?])
        };
        let patch = patch_id(&Value::String(cells[c.patch].to_string())).ok_or_else(|| {
            self.bad(
                line,
                format!(
                    "patch '{}' is not 1–24, a ColorChecker name or 'white'",
                    echo(cells[c.patch])
                ),
            )
        })?;
        let sd = c.sd.map(three).transpose()?;
        if sd.is_some_and(|v| v.iter().any(|s| *s < 0.0)) {
            return Err(self.bad(line, "a standard deviation must be ≥ 0"));
        }
        let n = match c.n {
            Some(k) => self.csv_count(line, num(k)?, cells[k])?,
            None => 1,
        };
        let out_of_gamut = match c.out_of_gamut {
            Some(k) => self.csv_flag(line, cells[k])?,
            None => false,
        };
        let cov = c.cov.map(three).transpose()?.unwrap_or([0.0; 3]);
        let u_lab = c.u_lab.map(num).transpose()?;
        let dof = match c.dof {
            Some(k) if cells[k].is_empty() => Some(None),
            Some(k) => Some(Some(self.csv_whole(
                line,
                "dof",
                MAX_DOF,
                (num(k)?, cells[k]),
            )?)),
            None => None,
        };
        let most = match c.most {
            Some(k) if cells[k].is_empty() => None,
            Some(k) => Some(self.csv_whole(line, "most", MOST_LOOKS, (num(k)?, cells[k]))?),
            None => None,
        };
        Ok(Row {
            sd,
            cov,
            n,
            u_lab,
            dof,
            most,
            out_of_gamut,
            ..Row::reading(line, patch, three(c.xyz)?)
        })
    }

    /// The `n` cell: a whole number of readings, at least one.
    fn csv_count(&self, line: usize, v: f64, cell: &str) -> Result<usize, ReadingsError> {
        if v < 1.0 || v.fract() != 0.0 {
            return Err(self.bad(
                line,
                format!("n: '{}' must be a whole number ≥ 1", echo(cell)),
            ));
        }
        Ok(v as usize)
    }

    /// A `dof` or `most` cell: a whole number from 1 to `largest` (bounded before the
    /// boundary of `most` looks is computed).
    fn csv_whole(
        &self,
        line: usize,
        name: &str,
        largest: usize,
        (v, cell): (f64, &str),
    ) -> Result<usize, ReadingsError> {
        if !(1.0..=largest as f64).contains(&v) || v.fract() != 0.0 {
            return Err(self.bad(
                line,
                format!(
                    "{name}: '{}' must be a whole number from 1 to {largest}",
                    echo(cell)
                ),
            ));
        }
        Ok(v as usize)
    }

    /// The `out_of_gamut` cell: 1 / true / yes, or 0 / false / no / empty.
    fn csv_flag(&self, line: usize, cell: &str) -> Result<bool, ReadingsError> {
        match cell {
            "1" | "true" | "yes" => Ok(true),
            "0" | "false" | "no" | "" => Ok(false),
            other => Err(self.bad(
                line,
                format!("out_of_gamut: '{}' is not 0 or 1", echo(other)),
            )),
        }
    }
}
