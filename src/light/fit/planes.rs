//! The measured fall-off: two planes of signed angles, their CSV form, their checks, and
//! their split into the four half-planes the fit treats separately.
//!
//! The horizontal plane is the C0–C180 plane (positive angles towards the emitter's
//! `edge_u`, C = 0°), the vertical plane the C90–C270 plane (positive towards `edge_v`,
//! C = 90°). A half-plane's γ is the angle's magnitude.

use std::path::{Path, PathBuf};

use metamer_color::text::{echo, strip_bom};
use serde::{Deserialize, Serialize};

use super::error::LdcError;
use super::half::{HalfPlane, Plane};

/// One plane's readings at signed angles off the normal (degrees).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PlaneData {
    pub angles_deg: Vec<f64>,
    pub luminance: Vec<f64>,
}

/// The readings of both planes, relative or absolute luminance (any unit: the fit divides
/// by the normal luminance).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Falloff {
    pub horizontal: PlaneData,
    pub vertical: PlaneData,
}

impl Falloff {
    /// Reads `angle_deg,horizontal,vertical` (either plane column may be left out, columns
    /// in any order after the angle; an empty cell is no reading at that angle). A plane
    /// given alone stands for both: the source is then taken to fall off alike in both
    /// planes. '#' lines are comments.
    pub fn read_csv(path: &Path) -> Result<Falloff, LdcError> {
        let text = metamer_color::text::read_text(path).map_err(|source| LdcError::Io {
            file: path.to_path_buf(),
            source,
        })?;
        Falloff::parse_csv(&text, path)
    }

    /// [`Falloff::read_csv`] on text; `source` names it in errors.
    pub fn parse_csv(text: &str, source: &Path) -> Result<Falloff, LdcError> {
        let err = |line: usize, message: String| LdcError::Csv {
            file: PathBuf::from(source),
            line,
            message,
        };
        let mut columns: Option<Vec<Option<Plane>>> = None;
        let mut out = Falloff::default();
        let mut last_line = 0;
        for (index, raw) in strip_bom(text).lines().enumerate() {
            let line = index + 1;
            last_line = line;
            let trimmed = raw.trim();
            if trimmed.is_empty() || trimmed.starts_with('#') {
                continue;
            }
            let cells: Vec<&str> = trimmed.split(',').map(str::trim).collect();
            let Some(cols) = &columns else {
                columns = Some(header(&cells).map_err(|m| err(line, m))?);
                continue;
            };
            if cells.len() != cols.len() + 1 {
                return Err(err(
                    line,
                    format!("expected {} cells, found {}", cols.len() + 1, cells.len()),
                ));
            }
            let number = |cell: &str, what: &str| -> Result<f64, LdcError> {
                cell.parse::<f64>()
                    .map_err(|_| err(line, format!("{what}: '{}' is not a number", echo(cell))))
            };
            let angle = number(cells[0], "angle_deg")?;
            for (cell, plane) in cells[1..].iter().zip(cols) {
                let Some(plane) = plane else { continue };
                if cell.is_empty() {
                    continue;
                }
                let value = number(cell, plane.name())?;
                let data = match plane {
                    Plane::Horizontal => &mut out.horizontal,
                    Plane::Vertical => &mut out.vertical,
                };
                data.angles_deg.push(angle);
                data.luminance.push(value);
            }
        }
        let Some(cols) = columns else {
            return Err(err(
                last_line.max(1),
                "no header: expected 'angle_deg,horizontal,vertical'".into(),
            ));
        };
        let has = |p: Plane| cols.contains(&Some(p));
        if !has(Plane::Vertical) {
            out.vertical = out.horizontal.clone();
        } else if !has(Plane::Horizontal) {
            out.horizontal = out.vertical.clone();
        }
        Ok(out)
    }

    pub fn plane(&self, plane: Plane) -> &PlaneData {
        match plane {
            Plane::Horizontal => &self.horizontal,
            Plane::Vertical => &self.vertical,
        }
    }

    /// Checks both planes and returns their readings at the normal (horizontal, vertical).
    pub fn validate(&self) -> Result<[f64; 2], LdcError> {
        let mut normal = [0.0; 2];
        for (k, plane) in [Plane::Horizontal, Plane::Vertical].into_iter().enumerate() {
            normal[k] = validate_plane(plane, self.plane(plane))?;
        }
        Ok(normal)
    }

    /// Checks the readings against the normal luminance `l0` (the mean of the planes' 0°
    /// readings): the two 0° readings look along one direction and must agree within a
    /// factor of [`MAX_NORMAL_RATIO`], and no reading may exceed [`MAX_RELATIVE`] times
    /// `l0` (a 0° reading of 1e-300 made every ratio overflow into an infinite fit).
    pub fn check_relative(&self, l0: f64) -> Result<(), LdcError> {
        let [h, v] = [
            self.horizontal.luminance_at(0.0),
            self.vertical.luminance_at(0.0),
        ];
        if let (Some(h), Some(v)) = (h, v) {
            let ratio = h.max(v) / h.min(v);
            if ratio.is_nan() || ratio > MAX_NORMAL_RATIO {
                return Err(LdcError::NormalsDisagree {
                    horizontal: h,
                    vertical: v,
                    ratio,
                });
            }
        }
        for plane in [Plane::Horizontal, Plane::Vertical] {
            let data = self.plane(plane);
            for (&angle, &value) in data.angles_deg.iter().zip(&data.luminance) {
                let ratio = value / l0;
                if ratio.is_nan() || ratio > MAX_RELATIVE {
                    return Err(LdcError::FarAboveNormal {
                        plane,
                        angle,
                        value,
                        normal: l0,
                        ratio,
                        max: MAX_RELATIVE,
                    });
                }
            }
        }
        Ok(())
    }

    /// The off-normal points of one half-plane: (γ, reading), γ increasing.
    pub fn half(&self, half: HalfPlane) -> (Vec<f64>, Vec<f64>) {
        let (plane, sign) = half.plane();
        let data = self.plane(plane);
        let mut pts: Vec<(f64, f64)> = data
            .angles_deg
            .iter()
            .zip(&data.luminance)
            .filter(|(a, _)| **a * sign > 0.0)
            .map(|(a, l)| (a.abs(), *l))
            .collect();
        pts.sort_by(|a, b| a.0.total_cmp(&b.0));
        pts.into_iter().unzip()
    }
}

/// The largest factor between the two planes' 0° readings.
pub const MAX_NORMAL_RATIO: f64 = 2.0;
/// The largest reading, relative to the normal luminance: a panel brighter off its normal
/// than this is not described by a distribution relative to it.
pub const MAX_RELATIVE: f64 = 100.0;

impl PlaneData {
    /// The reading at `angle_deg`, if there is one.
    pub fn luminance_at(&self, angle_deg: f64) -> Option<f64> {
        self.angles_deg
            .iter()
            .position(|&a| a == angle_deg)
            .and_then(|i| self.luminance.get(i).copied())
    }
}

/// The header's plane columns after `angle_deg`; a column of another name is an error.
fn header(cells: &[&str]) -> Result<Vec<Option<Plane>>, String> {
    let expected =
        "expected the header 'angle_deg,horizontal,vertical' (either plane may be left out)";
    if cells.len() < 2 || !cells[0].eq_ignore_ascii_case("angle_deg") {
        return Err(format!("{expected}, found '{}'", echo(&cells.join(","))));
    }
    let mut cols = Vec::new();
    for c in &cells[1..] {
        let p = if c.eq_ignore_ascii_case("horizontal") {
            Plane::Horizontal
        } else if c.eq_ignore_ascii_case("vertical") {
            Plane::Vertical
        } else {
            return Err(format!("{expected}, found column '{}'", echo(c)));
        };
        if cols.contains(&Some(p)) {
            return Err(format!("column '{}' appears twice", echo(c)));
        }
        cols.push(Some(p));
    }
    Ok(cols)
}

fn validate_plane(plane: Plane, data: &PlaneData) -> Result<f64, LdcError> {
    if data.angles_deg.len() != data.luminance.len() {
        return Err(LdcError::LengthMismatch {
            plane,
            angles: data.angles_deg.len(),
            readings: data.luminance.len(),
        });
    }
    if data.angles_deg.is_empty() {
        return Err(LdcError::EmptyPlane { plane });
    }
    let mut normal = None;
    for (i, (&angle, &value)) in data.angles_deg.iter().zip(&data.luminance).enumerate() {
        if !angle.is_finite() || angle.abs() >= 90.0 {
            return Err(LdcError::AngleOutOfRange { plane, angle });
        }
        if i > 0 && angle <= data.angles_deg[i - 1] {
            return Err(LdcError::AnglesNotIncreasing {
                plane,
                previous: data.angles_deg[i - 1],
                angle,
            });
        }
        // Any unit, but no reading in any unit is brighter than the sun's disc in cd/m²:
        // 1e300 was fitted and written as a 300-digit candela table.
        if !(0.0..=metamer_color::MAX_CD_M2).contains(&value) {
            return Err(LdcError::BadLuminance {
                plane,
                angle,
                value,
            });
        }
        if angle == 0.0 {
            normal = Some(value);
        }
    }
    match normal {
        None => Err(LdcError::NoNormalReading { plane }),
        Some(v) => {
            if v == 0.0 {
                Err(LdcError::ZeroNormalReading { plane })
            } else {
                Ok(v)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_both_planes_and_single_planes() {
        let p = Path::new("f.csv");
        let f = Falloff::parse_csv(
            "# c\nangle_deg,horizontal,vertical\n-30,0.9,\n0,1,1\n30,0.8,0.7\n",
            p,
        )
        .unwrap();
        assert_eq!(f.horizontal.angles_deg, vec![-30.0, 0.0, 30.0]);
        assert_eq!(f.vertical.angles_deg, vec![0.0, 30.0]);
        assert_eq!(f.vertical.luminance, vec![1.0, 0.7]);
        let f = Falloff::parse_csv("angle_deg,vertical\n0,5\n20,4\n", p).unwrap();
        assert_eq!(f.horizontal, f.vertical);
        assert_eq!(f.horizontal.luminance, vec![5.0, 4.0]);
        let e = Falloff::parse_csv("angle,h\n", p).unwrap_err();
        assert!(e.to_string().starts_with("f.csv:1:"), "{e}");
        let e = Falloff::parse_csv("angle_deg,horizontal\n0,x\n", p).unwrap_err();
        assert!(e.to_string().contains("f.csv:2: horizontal: 'x'"), "{e}");
    }

    #[test]
    fn halves_take_the_sign_of_the_angle() {
        let f = Falloff {
            horizontal: PlaneData {
                angles_deg: vec![-40.0, -20.0, 0.0, 20.0],
                luminance: vec![0.5, 0.8, 1.0, 0.9],
            },
            vertical: PlaneData::default(),
        };
        assert_eq!(f.half(HalfPlane::C180), (vec![20.0, 40.0], vec![0.8, 0.5]));
        assert_eq!(f.half(HalfPlane::C0), (vec![20.0], vec![0.9]));
    }
}
