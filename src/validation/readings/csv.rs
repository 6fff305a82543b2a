//! The CSV form of readings `validate` takes: `patch,X,Y,Z` and optional columns.

use super::*;

impl Parsed {
    /// `patch,X,Y,Z[,sd_X,sd_Y,sd_Z][,n][,out_of_gamut]`, columns in any order.
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
                        "the header '{}' lacks the column '{name}' (expected patch,X,Y,Z with optional sd_X,sd_Y,sd_Z, n, out_of_gamut)",
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
        let (cn, cg) = (col("n"), col("out_of_gamut"));
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
            self.rows.push(Row {
                line,
                patch,
                xyz: [num(cx)?, num(cy)?, num(cz)?],
                sd,
                n,
                stderr: None,
                de95: None,
                out_of_gamut,
            });
        }
        Ok(())
    }
}
