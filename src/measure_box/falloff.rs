//! The light's angular distribution from the fall-off readings: the mean luminance of one
//! tile at each signed angle of the horizontal and the vertical plane, handed to the
//! library's LDC fit ([`crate::light::fit`]), which picks the model per half-plane and
//! writes the C-γ table the scene, the light files and the chart carry.
//!
//! The plan's planes are the fit's: horizontal = C0–C180 (positive towards the emitter's
//! `edge_u`, the box's back), vertical = C90–C270 (positive towards `edge_v`, down).

use super::plan::{Geometry, Plane};
use crate::light::chart::ldc_chart_svg;
use crate::light::fit::{fit, Falloff, LdcError, LdcFit, ModelChoice, PlaneData};
use crate::light::ies::{self, IesInfo};
use crate::light::ldt::{self, LdtInfo};
use crate::light::{Panel, PhotometryError};

/// The fall-off readings in the fit's form: `readings` are (plane, signed angle, cd/m²) in
/// any order; each plane's angles come out increasing. The normal is one direction
/// whatever the plane: a plane without a reading at 0° takes the other plane's (the
/// adaptive plan reads it once), so each half-plane's curve is relative to the same
/// normal luminance.
pub fn falloff(readings: &[(Plane, f64, f64)]) -> Falloff {
    let plane = |which: Plane| {
        let own = readings.iter().any(|r| r.0 == which && r.1 == 0.0);
        let mut points: Vec<(f64, f64)> = readings
            .iter()
            .filter(|r| r.0 == which || (!own && r.1 == 0.0))
            .map(|r| (r.1, r.2))
            .collect();
        points.sort_by(|a, b| a.0.total_cmp(&b.0));
        PlaneData {
            angles_deg: points.iter().map(|p| p.0).collect(),
            luminance: points.iter().map(|p| p.1).collect(),
        }
    };
    Falloff {
        horizontal: plane(Plane::Horizontal),
        vertical: plane(Plane::Vertical),
    }
}

/// The LDC fitted to `readings` with the model chosen by cross-validation.
pub fn fit_light(readings: &[(Plane, f64, f64)]) -> Result<LdcFit, LdcError> {
    fit(&falloff(readings), ModelChoice::Auto)
}

/// The light files could not be made.
#[derive(Debug, thiserror::Error)]
pub enum LightFilesError {
    #[error("the light's chart: {0}")]
    Chart(#[from] LdcError),
    #[error("the light panel of the plan: {0}")]
    Panel(#[from] PhotometryError),
}

/// The fitted light as files: (`light.svg`, `light.ies`, `light.ldt`) texts, for the plan's
/// light opening (width along the columns, height along the rows) at the measured normal
/// luminance. `date` is `YYYY-MM-DD`.
pub fn light_files(
    fit: &LdcFit,
    g: &Geometry,
    date: &str,
) -> Result<[(&'static str, String); 3], LightFilesError> {
    let [y0, y1, z0, z1] = g.light_m;
    let panel = Panel::new(z1 - z0, y1 - y0, fit.normal_luminance)?;
    let luminaire = format!(
        "validation box light {:.3} m x {:.3} m, {} distribution fitted to measure-box fall-off",
        panel.width_m, panel.height_m, fit.model
    );
    let ies_info = IesInfo {
        test: "metamer measure-box".into(),
        issue_date: date.into(),
        luminaire: luminaire.clone(),
        generation: format!("metamer measure-box, model {}", fit.model),
        extrapolation: fit.extrapolation(),
    };
    let ldt_info = LdtInfo {
        luminaire,
        file_name: "light.ldt".into(),
        date_user: format!("{date} metamer measure-box"),
        extrapolation: fit.extrapolation(),
    };
    Ok([
        ("light.svg", ldc_chart_svg(fit)?),
        ("light.ies", ies::to_string(&fit.table, &panel, &ies_info)),
        ("light.ldt", ldt::to_string(&fit.table, &panel, &ldt_info)),
    ])
}

#[cfg(test)]
mod tests {
    use super::*;

    fn readings(f: impl Fn(Plane, f64) -> f64) -> Vec<(Plane, f64, f64)> {
        let mut out = Vec::new();
        for plane in [Plane::Vertical, Plane::Horizontal] {
            for k in (-4..=4).rev() {
                let a = 20.0 * f64::from(k);
                out.push((plane, a, 80.0 * f(plane, a)));
            }
        }
        out
    }

    #[test]
    fn readings_become_sorted_planes_in_the_fits_convention() {
        let f = falloff(&readings(|p, a| {
            if p == Plane::Horizontal {
                1.0 + a / 1000.0
            } else {
                2.0
            }
        }));
        assert_eq!(f.horizontal.angles_deg[0], -80.0);
        assert_eq!(f.horizontal.angles_deg[8], 80.0);
        assert!((f.horizontal.luminance[8] - 80.0 * 1.08).abs() < 1e-12);
        assert!(f.vertical.luminance.iter().all(|&l| l == 160.0));
    }

    #[test]
    fn asymmetric_cos_power_light_is_recovered_per_half_plane() {
        // cos^0.9 towards C0, cos^1.4 towards C90, cos^0.6 towards C180, cos^1.1 towards
        // C270: each half-plane is one cos power, so the fit reproduces it exactly at the
        // measured angles, and the table at C = 0° (a measured plane) is the curve itself.
        let m = |p: Plane, a: f64| match (p, a >= 0.0) {
            (Plane::Horizontal, true) => 0.9,
            (Plane::Vertical, true) => 1.4,
            (Plane::Horizontal, false) => 0.6,
            (Plane::Vertical, false) => 1.1,
        };
        let fit = fit_light(&readings(|p, a| a.to_radians().cos().powf(m(p, a)))).unwrap();
        assert_eq!(fit.normal_luminance, 80.0);
        for (c, exp) in [(0.0, 0.9), (90.0, 1.4), (180.0, 0.6), (270.0, 1.1)] {
            let want = 40f64.to_radians().cos().powf(exp);
            let got = fit.table.at(c, 40.0);
            assert!((got - want).abs() < 2e-3, "C {c}: {got} vs {want}");
        }
        let worst = fit
            .residuals
            .iter()
            .map(|r| r.residual.abs())
            .fold(0.0, f64::max);
        assert!(worst < 2e-3, "{worst}");
    }

    /// The adaptive plan reads the normal once, in the horizontal plane: both planes get
    /// that reading, so the fit's normal luminance is it and each plane is relative to it.
    /// A light of cos^0.9 horizontally and cos^1.4 vertically at 80 cd/m² on the normal,
    /// read at the adaptive first pass's angles, is recovered in both planes.
    #[test]
    fn the_normal_read_once_is_the_normal_of_both_planes() {
        let m = |p: Plane| if p == Plane::Horizontal { 0.9 } else { 1.4 };
        let mut read = vec![(Plane::Horizontal, 0.0, 80.0)];
        for plane in [Plane::Horizontal, Plane::Vertical] {
            for a in [-80.0, -40.0, 40.0, 80.0] {
                let l = 80.0 * f64::to_radians(a).cos().powf(m(plane));
                read.push((plane, a, l));
            }
        }
        let f = falloff(&read);
        assert_eq!(f.horizontal.angles_deg, [-80.0, -40.0, 0.0, 40.0, 80.0]);
        assert_eq!(f.vertical.angles_deg, [-80.0, -40.0, 0.0, 40.0, 80.0]);
        assert_eq!(f.vertical.luminance[2], 80.0);
        let fit = fit_light(&read).unwrap();
        assert_eq!(fit.normal_luminance, 80.0);
        for (c, exp) in [(0.0, 0.9), (90.0, 1.4), (180.0, 0.9), (270.0, 1.4)] {
            let want = 40f64.to_radians().cos().powf(exp);
            let got = fit.table.at(c, 40.0);
            assert!((got - want).abs() < 2e-3, "C {c}: {got} vs {want}");
        }
        // A plane with its own normal keeps it: the fixed plan's readings are unchanged.
        let mut both = read.clone();
        both.push((Plane::Vertical, 0.0, 79.0));
        assert_eq!(falloff(&both).vertical.luminance[2], 79.0);
        assert_eq!(falloff(&both).horizontal.luminance[2], 80.0);
    }

    #[test]
    fn a_dark_normal_is_refused_by_the_fit() {
        let e = fit_light(&readings(|_, a| if a == 0.0 { 0.0 } else { 1.0 }))
            .unwrap_err()
            .to_string();
        assert!(e.contains("reads 0 at the normal"), "{e}");
    }
}
