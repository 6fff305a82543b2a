//! The light distribution curve (LDC) fit: from readings of the light source's luminance in
//! the horizontal and vertical plane to the emitter's relative luminance f(C, γ).
//!
//! Each of the four half-planes (C0, C90, C180, C270) gets its own parameters of one model
//! family, since a panel seen from the left need not look like one seen from the right.
//! Between the half-planes f is blended with the weights of an ellipse:
//!
//! f(C, γ) = cos²C · f_h(γ) + sin²C · f_v(γ)
//!
//! where f_h is the C0 fit for cos C ≥ 0 and the C180 fit otherwise, f_v the C90 fit for
//! sin C ≥ 0 and the C270 fit otherwise. The blend is exact in the measured planes, smooth
//! across them (no kink at C = 0°, 90°, …) and, to second order in γ, what any smooth
//! distribution symmetric about both planes is. The [`CGammaTable`] written holds this f
//! every 5° in C and every 1° in γ (values rounded to 10⁻⁶, clamped at 0).

pub mod cv;
pub mod error;
pub mod half;
pub mod models;
pub mod planes;
pub mod search;
pub mod series;
pub mod spline;

use serde::{Deserialize, Serialize};

pub use error::LdcError;
pub use half::{HalfPlane, Plane};
pub use models::{LdcModel, Params};
pub use planes::{Falloff, PlaneData};

use super::cgamma::{CGammaError, CGammaTable};

/// Which model to fit.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ModelChoice {
    /// The model with the best leave-one-out score (see [`cv::choose`]).
    Auto,
    Named(LdcModel),
}

impl std::str::FromStr for ModelChoice {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        if s.trim().eq_ignore_ascii_case("auto") {
            return Ok(ModelChoice::Auto);
        }
        s.parse::<LdcModel>()
            .map(ModelChoice::Named)
            .map_err(|e| format!("{e}, or auto"))
    }
}

/// One half-plane's fit.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct HalfFit {
    pub half: HalfPlane,
    pub params: Params,
    /// RMS of the fit's residuals at this half's off-normal angles (relative luminance).
    pub rms: f64,
}

/// One model's fit and score, whether chosen or not.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Candidate {
    pub model: LdcModel,
    /// Free parameters over both planes (what `auto` counts to prefer the smaller model).
    #[serde(default)]
    pub parameters: usize,
    /// Per half-plane in C0, C90, C180, C270 order; empty when the model could not be
    /// fitted (see `note`).
    pub halves: Vec<HalfFit>,
    /// RMS of the residuals over every off-normal angle.
    pub rms: Option<f64>,
    /// RMS and largest magnitude of the leave-one-out errors over every off-normal angle.
    pub cv_rms: Option<f64>,
    pub cv_max: Option<f64>,
    pub note: Option<String>,
}

/// One reading against the chosen model.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Residual {
    pub plane: Plane,
    pub angle_deg: f64,
    /// The reading divided by the normal luminance.
    pub measured: f64,
    pub fitted: f64,
    /// measured − fitted.
    pub residual: f64,
}

/// The fit: the chosen model, its parameters, residuals, every model's scores, and the
/// table the renderers and the IES/LDT writers use.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LdcFit {
    pub model: LdcModel,
    /// The chosen model per half-plane, C0, C90, C180, C270.
    pub halves: Vec<HalfFit>,
    pub residuals: Vec<Residual>,
    pub candidates: Vec<Candidate>,
    /// Why this model: the named one, or `auto`'s reason.
    pub why: String,
    /// The mean of both planes' readings at 0°, in the readings' unit.
    pub normal_luminance: f64,
    /// Each plane's reading at 0° (horizontal, vertical).
    pub normal_readings: [f64; 2],
    /// The largest angle read in each half-plane, C0, C90, C180, C270 (degrees): beyond it
    /// the table is the model's extrapolation (None in a fit written before this was kept).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub measured_to_deg: Option<[f64; 4]>,
    pub table: CGammaTable,
}

/// Where a fitted table is not measured: the angles past the last reading, up to 90°,
/// which the model extrapolates. Said wherever the table goes (the command's output, the
/// IES and EULUMDAT files), since a reader of those files cannot tell a measured candela
/// value from an extrapolated one.
#[derive(Clone, Debug, PartialEq)]
pub struct Extrapolation {
    /// The smallest of the half-planes' last angles: past it at least one half-plane is
    /// extrapolated.
    pub beyond_deg: f64,
    /// The last angle read in C0, C90, C180, C270.
    pub measured_to_deg: [f64; 4],
    pub model: LdcModel,
}

impl Extrapolation {
    /// One line in ASCII (for the files): what is measured and what extrapolated.
    pub fn sentence(&self) -> String {
        let m = self.measured_to_deg;
        let reach = if m.iter().all(|&x| x == m[0]) {
            format!("readings reach {} deg in C0, C90, C180 and C270", m[0])
        } else {
            format!(
                "readings reach C0 {} deg, C90 {} deg, C180 {} deg, C270 {} deg",
                m[0], m[1], m[2], m[3]
            )
        };
        format!(
            "gamma above {} deg up to 90 deg is not measured: there the table is the {} \
             model's extrapolation ({reach})",
            self.beyond_deg, self.model
        )
    }
}

/// C-plane step of the table written, degrees.
pub const TABLE_C_STEP: f64 = 5.0;
/// γ step of the table written, degrees.
pub const TABLE_GAMMA_STEP: f64 = 1.0;

/// Fits `falloff` with the chosen model (or picks one by cross-validation).
pub fn fit(falloff: &Falloff, choice: ModelChoice) -> Result<LdcFit, LdcError> {
    let normal_readings = falloff.validate()?;
    let l0 = (normal_readings[0] + normal_readings[1]) / 2.0;
    falloff.check_relative(l0)?;
    let halves: Vec<(Vec<f64>, Vec<f64>)> = HalfPlane::ALL
        .iter()
        .map(|&h| {
            let (g, l) = falloff.half(h);
            (g, l.into_iter().map(|v| v / l0).collect())
        })
        .collect();
    if let ModelChoice::Named(m) = choice {
        if let Some(e) = unmet(m, &halves) {
            return Err(e);
        }
    }
    let candidates: Vec<Candidate> = LdcModel::ALL
        .iter()
        .map(|&m| candidate(m, &halves))
        .collect();
    let (chosen, why) = match choice {
        ModelChoice::Named(m) => {
            let i = LdcModel::ALL.iter().position(|&x| x == m).unwrap_or(0);
            (i, format!("{m}: named"))
        }
        ModelChoice::Auto => {
            let scores: Vec<cv::Score> = candidates
                .iter()
                .map(|c| cv::Score {
                    model: c.model,
                    parameters: c.parameters,
                    cv_rms: c.cv_rms,
                })
                .collect();
            cv::choose(&scores).ok_or(LdcError::NothingToChoose)?
        }
    };
    let chosen_halves = candidates[chosen].halves.clone();
    let model = candidates[chosen].model;
    let mut residuals = Vec::new();
    for plane in [Plane::Horizontal, Plane::Vertical] {
        let data = falloff.plane(plane);
        for (&a, &l) in data.angles_deg.iter().zip(&data.luminance) {
            let fitted = eval_halves(&chosen_halves, plane_c(plane, a), a.abs());
            let measured = l / l0;
            residuals.push(Residual {
                plane,
                angle_deg: a,
                measured,
                fitted,
                residual: measured - fitted,
            });
        }
    }
    let table = build_table(&chosen_halves)?;
    let measured_to_deg = std::array::from_fn(|k| halves[k].0.iter().copied().fold(0.0, f64::max));
    let fit = LdcFit {
        model,
        halves: chosen_halves,
        residuals,
        candidates,
        why,
        normal_luminance: l0,
        normal_readings,
        measured_to_deg: Some(measured_to_deg),
        table,
    };
    fit.check_finite()?;
    Ok(fit)
}

impl LdcFit {
    /// f(C, γ) from the fitted parameters (the table holds this on its grid).
    pub fn relative(&self, c_deg: f64, gamma_deg: f64) -> f64 {
        eval_halves(&self.halves, c_deg, gamma_deg)
    }

    /// The chosen model's candidate entry (its RMS and CV scores).
    pub fn chosen(&self) -> Option<&Candidate> {
        self.candidates.iter().find(|c| c.model == self.model)
    }

    /// Where the table is the model's extrapolation. Readings stop short of 90° (the light
    /// is seen from the front), so every fit has one; None only for a fit written before
    /// it kept how far it was read.
    pub fn extrapolation(&self) -> Option<Extrapolation> {
        let measured_to_deg = self.measured_to_deg?;
        let beyond_deg = measured_to_deg.iter().copied().fold(90.0, f64::min);
        (beyond_deg < 90.0).then_some(Extrapolation {
            beyond_deg,
            measured_to_deg,
            model: self.model,
        })
    }

    /// Every number of the fit is finite: JSON has no infinity (serde writes `null`), and
    /// a table or a score of inf is of no use to anyone. The readings' checks make this
    /// hold; this says which number if they ever do not.
    fn check_finite(&self) -> Result<(), LdcError> {
        let params = |p: &Params| -> Vec<f64> {
            match p {
                Params::Lambertian => vec![],
                Params::CosPower { n } => vec![*n],
                Params::CosPoly { coeffs } => coeffs.to_vec(),
                Params::Lobes { a, n, m } => vec![*a, *n, *m],
                Params::Series { n, b } => std::iter::once(*n).chain(b.iter().copied()).collect(),
                Params::Spline {
                    a,
                    n,
                    m,
                    knots_deg,
                    residuals,
                    curvature,
                } => [*a, *n, *m]
                    .into_iter()
                    .chain(knots_deg.iter().chain(residuals).chain(curvature).copied())
                    .collect(),
            }
        };
        let bad = |what: String, v: f64| LdcError::NotFinite { what, value: v };
        for c in &self.candidates {
            for (what, v) in [
                ("RMS", c.rms),
                ("leave-one-out RMS", c.cv_rms),
                ("leave-one-out max", c.cv_max),
            ] {
                if let Some(v) = v.filter(|v| !v.is_finite()) {
                    return Err(bad(format!("the {} model's {what}", c.model), v));
                }
            }
            for h in &c.halves {
                for v in params(&h.params).into_iter().chain([h.rms]) {
                    if !v.is_finite() {
                        return Err(bad(
                            format!("the {} model's fit of half-plane {}", c.model, h.half),
                            v,
                        ));
                    }
                }
            }
        }
        for r in &self.residuals {
            for v in [r.measured, r.fitted, r.residual] {
                if !v.is_finite() {
                    return Err(bad(
                        format!("the residual at {}° in the {} plane", r.angle_deg, r.plane),
                        v,
                    ));
                }
            }
        }
        if !self.normal_luminance.is_finite() {
            return Err(bad("the normal luminance".into(), self.normal_luminance));
        }
        Ok(())
    }
}

/// Why `model` cannot be fitted to `halves` (C0, C90, C180, C270), if it cannot.
fn unmet(model: LdcModel, halves: &[(Vec<f64>, Vec<f64>)]) -> Option<LdcError> {
    let (half, plane) = model.min_angles();
    let need = half.max(1);
    for (&h, (g, _)) in HalfPlane::ALL.iter().zip(halves) {
        if g.len() < need {
            return Some(LdcError::TooFewAngles {
                half: h,
                model,
                got: g.len(),
                need,
            });
        }
    }
    for (p, (pos, neg)) in [Plane::Horizontal, Plane::Vertical]
        .into_iter()
        .zip([(0, 2), (1, 3)])
    {
        let got = halves[pos].0.len() + halves[neg].0.len();
        if got < plane {
            return Some(LdcError::TooFewPlaneAngles {
                plane: p,
                model,
                got,
                need: plane,
            });
        }
    }
    None
}

/// The C of a signed angle in a measured plane.
pub fn plane_c(plane: Plane, angle_deg: f64) -> f64 {
    plane.c_gamma(angle_deg).0
}

fn candidate(model: LdcModel, halves: &[(Vec<f64>, Vec<f64>)]) -> Candidate {
    let per_plane = |h: usize, v: usize| halves[h].0.len() + halves[v].0.len();
    let mut out = Candidate {
        model,
        parameters: model.parameters(per_plane(0, 2)) + model.parameters(per_plane(1, 3)),
        halves: Vec::new(),
        rms: None,
        cv_rms: None,
        cv_max: None,
        note: None,
    };
    if let Some(e) = unmet(model, halves) {
        out.note = Some(match e {
            LdcError::TooFewAngles {
                half, got, need, ..
            } => {
                format!(
                    "not fitted: half-plane {half} has {got} angle(s) off the normal, needs {need}"
                )
            }
            LdcError::TooFewPlaneAngles {
                plane, got, need, ..
            } => {
                format!(
                    "not fitted: the {plane} plane has {got} angle(s) off the normal, needs {need}"
                )
            }
            other => format!("not fitted: {other}"),
        });
        return out;
    }
    // Planes as (positive half, negative half) indices into C0, C90, C180, C270.
    let mut params: Vec<Option<Params>> = vec![None; 4];
    let mut held_out = Some(Vec::new());
    for (pos, neg) in [(0, 2), (1, 3)] {
        let p = (halves[pos].0.as_slice(), halves[pos].1.as_slice());
        let n = (halves[neg].0.as_slice(), halves[neg].1.as_slice());
        let [fp, fn_] = models::fit_plane(model, p, n);
        params[pos] = Some(fp);
        params[neg] = Some(fn_);
        held_out = match (held_out, cv::leave_one_out_plane(model, p, n)) {
            (Some(mut all), Some(e)) => {
                all.extend(e);
                Some(all)
            }
            _ => None,
        };
    }
    let (mut sq, mut count) = (0.0, 0usize);
    for ((&h, (g, y)), p) in HalfPlane::ALL.iter().zip(halves).zip(params) {
        let params = p.unwrap_or(Params::Lambertian);
        let half_sq: f64 = g
            .iter()
            .zip(y)
            .map(|(&gi, &yi)| (yi - params.eval(gi)).powi(2))
            .sum();
        sq += half_sq;
        count += g.len();
        out.halves.push(HalfFit {
            half: h,
            params,
            rms: (half_sq / g.len() as f64).sqrt(),
        });
    }
    out.rms = Some((sq / count as f64).sqrt());
    match held_out {
        Some(e) => {
            out.cv_rms = Some((e.iter().map(|x| x * x).sum::<f64>() / e.len() as f64).sqrt());
            out.cv_max = Some(e.iter().fold(0.0f64, |m, x| m.max(x.abs())));
        }
        None => {
            let (half, plane) = model.min_angles();
            out.note = Some(if model.per_plane() {
                format!(
                    "not cross-validated: every half-plane needs {} angles off the normal and every plane {}",
                    half + 1,
                    plane + 1
                )
            } else {
                format!(
                    "not cross-validated: every half-plane needs {} angles off the normal",
                    half + 1
                )
            })
        }
    }
    out
}

/// The elliptic blend of the four half-plane fits (`halves` in C0, C90, C180, C270 order).
fn eval_halves(halves: &[HalfFit], c_deg: f64, gamma_deg: f64) -> f64 {
    let c = c_deg.to_radians();
    let (cos_c, sin_c) = (c.cos(), c.sin());
    let h = if cos_c >= 0.0 { &halves[0] } else { &halves[2] };
    let v = if sin_c >= 0.0 { &halves[1] } else { &halves[3] };
    let (wh, wv) = (cos_c * cos_c, sin_c * sin_c);
    // Exactly in a measured plane only that plane's fit counts (cos²90° is 4e-33, not 0).
    if wv < 1e-12 {
        return h.params.eval(gamma_deg);
    }
    if wh < 1e-12 {
        return v.params.eval(gamma_deg);
    }
    wh * h.params.eval(gamma_deg) + wv * v.params.eval(gamma_deg)
}

fn build_table(halves: &[HalfFit]) -> Result<CGammaTable, CGammaError> {
    let nc = (360.0 / TABLE_C_STEP).round() as usize;
    let ng = (90.0 / TABLE_GAMMA_STEP).round() as usize;
    let c_deg: Vec<f64> = (0..nc).map(|k| k as f64 * TABLE_C_STEP).collect();
    let gamma_deg: Vec<f64> = (0..=ng).map(|k| k as f64 * TABLE_GAMMA_STEP).collect();
    let values = c_deg
        .iter()
        .map(|&c| {
            gamma_deg
                .iter()
                .map(|&g| (eval_halves(halves, c, g).max(0.0) * 1e6).round() / 1e6)
                .collect()
        })
        .collect();
    CGammaTable::new(c_deg, gamma_deg, values)
}
