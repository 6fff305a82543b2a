//! Whether readings and a white make sense together before anything is compared: CIELAB
//! of readings in other units than their white is a number, not a colour (`--white
//! 0.95,1,1.09` against readings in cd/m² gave L* 290; a white of 1e-300 made every ΔE
//! infinite), and a reflectance is no light from the scene.
//!
//! What the files say is refused where it is certain: a journal records each reading's
//! mode, and readings taken on the instrument's lamp (reflective, Y = 100 for white) or
//! through its diffuser (ambient, lux) are not luminances. What only the numbers suggest
//! (a display whose readings are ten times the box's) is said as a note, since a display
//! that far off is also a result.

use super::readings::ReadingSet;
use crate::color::{Xyz, COLORCHECKER_NAMES};

/// A white against which some set's brightest reading lies above this L* is in other
/// units than the readings: L* 100 is the white itself, and a scene ten times brighter
/// than its white (Y ratio 10, L* 234) is no scene measured against it.
pub const MAX_LSTAR: f64 = 234.0;
/// …and below this L* (Y ratio 10⁻³) every reading of a set is black against it.
pub const MIN_LSTAR: f64 = 0.9;
/// Box and display readings this many times apart on the median patch get a note.
pub const SCALE_NOTE_RATIO: f64 = 3.0;

/// Why readings or a white cannot be compared.
#[derive(Debug, thiserror::Error)]
pub enum Incomparable {
    #[error("{}: its readings were taken {how}: they are not luminances of the scene (cd/m²), which is what validate compares; measure the box and the display as light (emissive mode)", file.display())]
    NotLuminance {
        file: std::path::PathBuf,
        how: String,
    },
    #[error("X, Y, Z = {xyz:?} is not a white: {why}")]
    NotAWhite { xyz: [f64; 3], why: String },
    #[error("the white's Y = {white_y:e} and the {which} reading of {} (patch {patch}, {name}) has Y = {y:e}, L* {lstar:.0} against it: {hint}", file.display())]
    Scale {
        white_y: f64,
        which: &'static str,
        file: std::path::PathBuf,
        patch: usize,
        name: &'static str,
        y: f64,
        lstar: f64,
        hint: &'static str,
    },
}

/// Refuses a set whose file says its readings are not luminances.
pub fn check_luminance(set: &ReadingSet) -> Result<(), Incomparable> {
    match &set.measured_as {
        Some(how) => Err(Incomparable::NotLuminance {
            file: set.file.clone(),
            how: how.clone(),
        }),
        None => Ok(()),
    }
}

/// Checks a white given by the user: every component above 0, and a chromaticity a white
/// light has (near the Planckian locus: CIE 015 puts it between x = 0.24, y = 0.23 at
/// infinite temperature and x = 0.65, y = 0.34 at 1000 K, y at most 0.42).
pub fn check_given_white(white: Xyz) -> Result<(), Incomparable> {
    let xyz = white.to_array();
    let not = |why: String| Incomparable::NotAWhite { xyz, why };
    if !xyz.iter().all(|v| v.is_finite() && *v > 0.0) {
        return Err(not("each of X, Y and Z must be above 0".into()));
    }
    let sum: f64 = xyz.iter().sum();
    let (x, y) = (xyz[0] / sum, xyz[1] / sum);
    if !((0.2..=0.7).contains(&x) && (0.2..=0.5).contains(&y)) {
        return Err(not(format!(
            "its chromaticity x = {x:.3}, y = {y:.3} is not that of a white light (whites lie near the Planckian locus, x 0.24–0.65, y 0.23–0.42)"
        )));
    }
    Ok(())
}

/// L* of a luminance ratio (CIE 1976).
fn lstar(ratio: f64) -> f64 {
    let e = 216.0 / 24389.0;
    let f = if ratio > e {
        ratio.cbrt()
    } else {
        (24389.0 / 27.0 * ratio + 16.0) / 116.0
    };
    116.0 * f - 16.0
}

/// Checks that `white` is in the units of every set: each set's brightest reading lies
/// between L* [`MIN_LSTAR`] and [`MAX_LSTAR`] against it.
pub fn check_white_against(white: Xyz, sets: &[&ReadingSet]) -> Result<(), Incomparable> {
    let white_y = white.y;
    for set in sets {
        let Some((&patch, p)) = set
            .patches
            .iter()
            .max_by(|a, b| a.1.xyz[1].total_cmp(&b.1.xyz[1]))
        else {
            continue;
        };
        let y = p.xyz[1];
        let l = lstar(y / white_y);
        let scale = |which, hint| Incomparable::Scale {
            white_y,
            which,
            file: set.file.clone(),
            patch,
            name: COLORCHECKER_NAMES[patch - 1],
            y,
            lstar: l,
            hint,
        };
        // NaN (a white of Y = 0) fails both.
        if l.is_nan() || l > MAX_LSTAR {
            return Err(scale(
                "brightest",
                "the white and the readings are in different units (a relative white such as 0.95,1,1.09 or Y = 100 against readings in cd/m²?); give the white in the readings' unit, or `test` / `reference` for a file's own white",
            ));
        }
        if l < MIN_LSTAR {
            return Err(scale(
                "brightest",
                "every reading is black against this white: the white and the readings are in different units (a white in cd/m² against readings relative to 1?)",
            ));
        }
    }
    Ok(())
}

/// A note when the display's (`test`) readings are [`SCALE_NOTE_RATIO`] or more times the
/// box's (`reference`) or less than its inverse on the median patch both have.
pub fn scale_note(reference: &ReadingSet, test: &ReadingSet) -> Option<String> {
    let mut ratios: Vec<f64> = reference
        .patches
        .iter()
        .filter_map(|(k, r)| {
            let t = test.patches.get(k)?;
            (r.xyz[1] > 0.0 && t.xyz[1] > 0.0).then(|| t.xyz[1] / r.xyz[1])
        })
        .collect();
    if ratios.is_empty() {
        return None;
    }
    ratios.sort_by(f64::total_cmp);
    let median = ratios[ratios.len() / 2];
    (!(1.0 / SCALE_NOTE_RATIO..=SCALE_NOTE_RATIO).contains(&median)).then(|| {
        format!(
            "on the median patch the readings of {} are {median:.3} times those of {}: if they were not taken in the same unit (reflectance with white = 100, or relative to 1, against cd/m²), every difference below is one of units, not of colour",
            test.file.display(),
            reference.file.display()
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::validation::readings::{not_luminance, parse_readings, Format};
    use std::path::Path;

    fn csv(rows: &[(usize, f64)]) -> ReadingSet {
        let mut text = String::from("patch,X,Y,Z\n");
        for (k, y) in rows {
            text += &format!("{k},{},{y},{}\n", y * 0.95, y * 1.09);
        }
        parse_readings(&text, Path::new("r.csv")).unwrap()
    }

    /// CIE 1976: Y/Yn = 1 is L* 100, 0.18 is L* 49.5 (116·0.5646 − 16), and the linear
    /// part below (6/29)³: 0.001 is 903.3·0.001 = 0.903.
    #[test]
    fn lstar_follows_the_cie_formula() {
        assert!((lstar(1.0) - 100.0).abs() < 1e-12);
        assert!((lstar(0.18) - 49.496).abs() < 1e-3);
        assert!((lstar(0.001) - 0.9033).abs() < 1e-4);
        // The bounds' ratios: 10 and 10⁻³.
        assert!((lstar(10.0) - MAX_LSTAR).abs() < 0.1);
    }

    #[test]
    fn a_white_in_other_units_than_the_readings_is_refused() {
        let set = csv(&[(19, 90.0), (24, 3.0)]);
        let ok = Xyz::from_array([95.0, 100.0, 109.0]);
        check_white_against(ok, &[&set]).unwrap();
        for (white, words) in [
            ([0.95, 1.0, 1.09], "different units (a relative white"),
            ([1e-300, 1e-300, 1e-300], "different units"),
            ([9.5e6, 1e7, 1.09e7], "every reading is black"),
        ] {
            let e = check_white_against(Xyz::from_array(white), &[&set])
                .unwrap_err()
                .to_string();
            assert!(
                e.contains(words) && e.contains("patch 19"),
                "{white:?}: {e}"
            );
        }
    }

    #[test]
    fn a_given_white_must_be_a_white() {
        check_given_white(Xyz::from_array([95.047, 100.0, 108.883])).unwrap();
        for white in [[1e-300, 1.0, 1.0], [0.0, 1.0, 1.0], [10.0, 1.0, 1.0]] {
            let e = check_given_white(Xyz::from_array(white)).unwrap_err();
            assert!(e.to_string().contains("is not a white"), "{e}");
        }
    }

    #[test]
    fn readings_ten_times_apart_get_a_note_and_close_ones_none() {
        let a = csv(&[(1, 10.0), (2, 20.0), (19, 90.0)]);
        let b = csv(&[(1, 11.0), (2, 19.0), (19, 95.0)]);
        assert_eq!(scale_note(&a, &b), None);
        let c = csv(&[(1, 100.0), (2, 200.0), (19, 900.0)]);
        let n = scale_note(&a, &c).unwrap();
        assert!(n.contains("10.000 times"), "{n}");
    }

    #[test]
    fn a_journal_in_reflective_mode_says_so() {
        let entry = |mode: &str| {
            format!(
                r#"{{"type":"entry","index":0,"label":"p","role":"spectral","mode":"{mode}","data":{{"patch":1}},"reading":{{"xyz":[1,1,1],"xyy":[0,0,0],"spectrum":null,"flags":[],"integration_s":null,"instrument":"i1pro","timestamp_s":0}}}}"#
            )
        };
        let text = format!("{{\"type\":\"header\"}}\n{}\n", entry("reflective"));
        let how = not_luminance(&text, Format::Journal).unwrap();
        assert!(
            how.contains("reflective mode") && how.contains("line 2"),
            "{how}"
        );
        let text = format!("{{\"type\":\"header\"}}\n{}\n", entry("emissive"));
        assert_eq!(not_luminance(&text, Format::Journal), None);
    }
}
