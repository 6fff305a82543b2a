//! From the rows every format's parser yields to the patches of a reading set: the checks
//! every row passes, and each patch's mean with its uncertainty.

use super::*;
use crate::validation::repeatability;

/// Largest 95 % ΔE*ab bound a renderer may state: CIELAB's whole gamut spans a few hundred.
const MAX_DE95: f64 = 1000.0;

impl Parsed {
    /// A row no instrument or renderer can have produced (X = −1e308, a spread of 1e308)
    /// is refused where it enters: downstream it becomes an infinite CIELAB and a figure
    /// whose axis never ends.
    fn plausible(&self, r: &Row) -> Result<(), ReadingsError> {
        metamer_color::check_xyz(r.xyz.into())
            .map_err(|e| self.bad(r.line, format!("not a measurement: {e}")))?;
        for (what, spread) in [("standard deviation", r.sd), ("standard error", r.stderr)] {
            if let Some(v) = spread {
                if !metamer_color::plausible_spread(v) {
                    return Err(self.bad(
                        r.line,
                        format!(
                            "a {what} of {v:?}: must be ≥ 0 and at most {:e}",
                            metamer_color::MAX_CD_M2
                        ),
                    ));
                }
            }
        }
        if let Some(c) = r.covariance() {
            covariance::check(&c).map_err(|e| self.bad(r.line, e))?;
        }
        if let Some(u) = r.u_lab {
            if !(0.0..=MAX_DE95).contains(&u) {
                return Err(self.bad(
                    r.line,
                    format!("u_lab {u:?}: must be ≥ 0 and at most {MAX_DE95}"),
                ));
            }
        }
        if let Some(de) = r.de95.map(|u| u.de_ab()) {
            if !(0.0..=MAX_DE95).contains(&de) {
                return Err(self.bad(
                    r.line,
                    format!("a 95 % ΔE*ab bound of {de:?}: must be ≥ 0 and at most {MAX_DE95}"),
                ));
            }
        }
        Ok(())
    }

    pub(super) fn finish(self, format: Format) -> Result<ReadingSet, ReadingsError> {
        if self.rows.is_empty() {
            return Err(ReadingsError::Empty {
                file: self.file,
                message: format!(
                    "no readings of ColorChecker patches found ({}); journal entries need a patch number in their step data",
                    format.name()
                ),
            });
        }
        for r in &self.rows {
            self.plausible(r)?;
        }
        let mut groups: BTreeMap<usize, Vec<&Row>> = BTreeMap::new();
        let mut white = Vec::new();
        for r in &self.rows {
            match r.patch {
                PatchId::Number(k) => groups.entry(k).or_default().push(r),
                PatchId::White => white.push(r),
            }
        }
        let patches = groups
            .into_iter()
            .map(|(k, rows)| (k, combine(&rows)))
            .collect();
        Ok(ReadingSet {
            file: self.file,
            format,
            patches,
            white: (!white.is_empty()).then(|| combine(&white)),
            instruments: self.instruments,
            notes: self.notes,
            measured_as: None,
        })
    }
}

/// Combines the rows of one patch: the equal-weight mean and the covariance of that mean —
/// from the given covariances where every row has them (each row's over its n; the mean's
/// Σ/k²), else from the scatter of the rows when there are several (their sample
/// covariance over k, with k − 1 degrees of freedom), else from a renderer's confidence,
/// else, for one reading of a named instrument, from its stated repeatability; unknown (0)
/// for one bare reading.
pub(super) fn combine(rows: &[&Row]) -> PatchReading {
    let k = rows.len() as f64;
    let mut mean = [0.0; 3];
    for r in rows {
        for (m, x) in mean.iter_mut().zip(r.xyz) {
            *m += x / k;
        }
    }
    let n: usize = rows.iter().map(|r| r.n).sum();
    let (u_factors, dof, source) = uncertainty_of(rows, mean);
    // One row says what one reading's covariance is; several rows' statements, pooled, no
    // longer would.
    let reading_cov = match (rows, source) {
        ([one], UncertaintySource::Given) => one.covariance(),
        ([one], UncertaintySource::Instrument) => stated_covariance(one),
        _ => None,
    };
    let u_xyz = covariance::sd(&covariance::of_factors(&u_factors));
    // A ΔE statement stands for what the XYZ standard error does not say (a radiosity
    // solver's discretisation); with a standard error it would count the same noise twice.
    let from_de = match rows[0].de95 {
        Some(u) if rows[0].stderr.is_none() && rows.len() == 1 => render_lab_sigma(u),
        _ => 0.0,
    };
    let given_lab = rows.iter().filter_map(|r| r.u_lab).fold(0.0, f64::max);
    let u_lab = from_de.hypot(given_lab);
    let source = if source == UncertaintySource::Given && u_factors.is_empty() && u_lab > 0.0 {
        UncertaintySource::Render
    } else {
        source
    };
    PatchReading {
        xyz: mean.into(),
        u_xyz,
        u_factors,
        dof,
        u_lab,
        render_de95: rows[0].de95.map(|u| u.de_ab()),
        n,
        source,
        out_of_gamut: rows.iter().any(|r| r.out_of_gamut),
        line: rows[0].line,
        reading_cov,
        most: rows.iter().filter_map(|r| r.most).max(),
    }
}

/// The covariance of one emissive reading of `row`'s instrument, from its stated
/// repeatability, where the row names an instrument that has one.
fn stated_covariance(row: &Row) -> Option<Cov3> {
    let rep = repeatability::emissive_of(row.instrument.as_deref()?)?;
    repeatability::covariance(&rep, row.xyz.into())
}

/// The uncertainty of the mean of `rows` (at `mean`) as factors, with its degrees of
/// freedom and its source, in the order of [`combine`]'s rule.
fn uncertainty_of(
    rows: &[&Row],
    mean: [f64; 3],
) -> (Vec<[f64; 3]>, Option<usize>, UncertaintySource) {
    let k = rows.len() as f64;
    let axes = |u: [f64; 3]| -> Vec<[f64; 3]> {
        (0..3)
            .filter(|&i| u[i] > 0.0)
            .map(|i| {
                let mut v = [0.0; 3];
                v[i] = u[i];
                v
            })
            .collect()
    };
    let stated = (rows.len() == 1)
        .then(|| stated_covariance(rows[0]))
        .flatten();
    if let Some(given) = rows
        .iter()
        .map(|r| r.covariance())
        .collect::<Option<Vec<Cov3>>>()
    {
        let mut c = covariance::ZERO;
        for (r, g) in rows.iter().zip(&given) {
            c = covariance::sum(&c, &covariance::scaled(g, 1.0 / (r.n as f64 * k * k)));
        }
        // A standard deviation of one reading is a stated one; of several, their sample's,
        // unless the rows state its degrees of freedom (a figure pooled across patches).
        let dof = match rows.iter().map(|r| r.dof).collect::<Option<Vec<_>>>() {
            Some(stated) => stated.into_iter().flatten().min(),
            None => rows.iter().filter(|r| r.n > 1).map(|r| r.n - 1).min(),
        };
        (covariance::factors(&c), dof, UncertaintySource::Given)
    } else if rows.len() >= 2 {
        let scale = (k * (k - 1.0)).sqrt();
        let factors = rows
            .iter()
            .map(|r| [0, 1, 2].map(|i| (r.xyz[i] - mean[i]) / scale))
            .collect();
        (factors, Some(rows.len() - 1), UncertaintySource::Repeats)
    } else if let Some(se) = rows[0].stderr {
        (axes(se), None, UncertaintySource::Render)
    } else if rows[0].de95.is_some() || rows[0].u_lab.is_some() {
        (Vec::new(), None, UncertaintySource::Render)
    } else if let Some(c) = stated {
        (covariance::factors(&c), None, UncertaintySource::Instrument)
    } else {
        (Vec::new(), None, UncertaintySource::Unknown)
    }
}
