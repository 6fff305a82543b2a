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
//!
//! The experiment's stages write `patch,X,Y,Z,sd_X,sd_Y,sd_Z,n,cov_XY,cov_XZ,cov_YZ,u_lab`.

use super::*;

impl Parsed {
    /// `patch,X,Y,Z` and the optional columns above.
    pub(super) fn csv(&mut self, text: &str) -> Result<(), ReadingsError> {
        let mut lines = text
            .lines()
            .enumerate()
            .map(|(i, l)| (i + 1, l.trim()))
            .filter(|(_, l)| !l.is_empty() && !l.starts_with('#'));
        let (hline, header) = lines.next().expect("sniffed a first line");
        let names: Vec<String> = header.split(',').map(|c| c.trim().to_string()).collect();
        let col = |name: &str| names.iter().position(|n| n.eq_ignore_ascii_case(name));
        let need = |name: &str| {
            col(name).ok_or_else(|| {
                self.bad(
                    hline,
                    format!(
                        "the header '{}' lacks the column '{name}' (expected patch,X,Y,Z with optional sd_X,sd_Y,sd_Z, cov_XY,cov_XZ,cov_YZ, n, u_lab, out_of_gamut)",
                        echo(header)
                    ),
                )
            })
        };
        let (cp, cx, cy, cz) = (need("patch")?, need("X")?, need("Y")?, need("Z")?);
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
        let (cn, cg, cu) = (col("n"), col("out_of_gamut"), col("u_lab"));
        for (line, l) in lines {
            let cells: Vec<&str> = l.split(',').map(str::trim).collect();
            if cells.len() != names.len() {
                return Err(self.bad(
                    line,
                    format!(
                        "expected {} cells as in the header, found {}",
                        names.len(),
                        cells.len()
                    ),
                ));
            }
            let num = |c: usize| -> Result<f64, ReadingsError> {
                cells[c]
                    .parse::<f64>()
                    .ok()
                    .filter(|v| v.is_finite())
                    .ok_or_else(|| {
                        self.bad(
                            line,
                            format!("{}: '{}' is not a number", names[c], echo(cells[c])),
                        )
                    })
            };
            let patch = patch_id(&Value::String(cells[cp].to_string())).ok_or_else(|| {
                self.bad(
                    line,
                    format!(
                        "patch '{}' is not 1–24, a ColorChecker name or 'white'",
                        echo(cells[cp])
                    ),
                )
            })?;
            let sd = match sd {
                Some(c) => {
                    let v = [num(c[0])?, num(c[1])?, num(c[2])?];
                    if v.iter().any(|s| *s < 0.0) {
                        return Err(self.bad(line, "a standard deviation must be ≥ 0"));
                    }
                    Some(v)
                }
                None => None,
            };
            let n = match cn {
                Some(c) => {
                    let v = num(c)?;
                    if v < 1.0 || v.fract() != 0.0 {
                        return Err(self.bad(
                            line,
                            format!("n: '{}' must be a whole number ≥ 1", echo(cells[c])),
                        ));
                    }
                    v as usize
                }
                None => 1,
            };
            let out_of_gamut = match cg {
                Some(c) => match cells[c] {
                    "1" | "true" | "yes" => true,
                    "0" | "false" | "no" | "" => false,
                    other => {
                        return Err(self.bad(
                            line,
                            format!("out_of_gamut: '{}' is not 0 or 1", echo(other)),
                        ))
                    }
                },
                None => false,
            };
            let cov = match cov {
                Some(c) => [num(c[0])?, num(c[1])?, num(c[2])?],
                None => [0.0; 3],
            };
            let u_lab = cu.map(num).transpose()?;
            self.rows.push(Row {
                sd,
                cov,
                n,
                u_lab,
                out_of_gamut,
                ..Row::reading(line, patch, [num(cx)?, num(cy)?, num(cz)?])
            });
        }
        Ok(())
    }
}
