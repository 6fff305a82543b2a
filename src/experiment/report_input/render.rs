//! The renders' confidence from `simulation/simulation.json`: the method, its per-patch
//! ΔE*ab statement (the path tracer's 95 % half-width, the radiosity solver's bound), the
//! time, and the same statement as a CIELAB standard uncertainty for the comparisons.

use std::path::Path;

use super::files::{read_json, unusable};
use crate::experiment::simulation::{SimulationMethod, SimulationSummary, SUMMARY_FILE};
use crate::validation::propagate::render_lab_sigma;
use crate::validation::report::RenderConfidenceSection;
pub use crate::validation::report::RenderUncertainty;

const WHAT: &str = "render confidence";

/// The section and the uncertainty, or the note saying why there are none.
pub fn section(dir: &Path) -> Result<(RenderConfidenceSection, RenderUncertainty), String> {
    let file = dir.join(SUMMARY_FILE);
    let v = read_json(&file).map_err(|why| unusable(WHAT, &file, why))?;
    let s: SimulationSummary = serde_json::from_value(v)
        .map_err(|e| unusable(WHAT, &file, format!("is not a render summary: {e}")))?;
    let bound = s.method == SimulationMethod::Radiosity;
    let (measure, method) = if bound {
        (
            "ΔE*ab error bound (the mesh levels' extrapolation against its alternatives)",
            "deterministic radiosity solver".to_string(),
        )
    } else if let Some(src) = &s.source {
        (
            "95 % ΔE*ab half-width (from the pixels' spread in each meter cone)",
            format!(
                "{}: the image {} (sha256 {}), read back",
                src.renderer,
                src.image.display(),
                src.sha256
            ),
        )
    } else {
        ("95 % ΔE*ab half-width", "spectral path tracer".to_string())
    };
    if let Some(bad) = s
        .spots
        .iter()
        .find(|p| !(p.uncertainty.de_ab().is_finite() && p.uncertainty.de_ab() >= 0.0))
    {
        return Err(unusable(
            WHAT,
            &file,
            format!(
                "gives patch {} the uncertainty {}",
                bad.patch,
                bad.uncertainty.de_ab()
            ),
        ));
    }
    let per_patch: Vec<(usize, f64)> = s
        .spots
        .iter()
        .map(|p| (p.patch, p.uncertainty.de_ab()))
        .collect();
    let sigma_lab = s
        .spots
        .iter()
        .map(|p| (p.patch, render_lab_sigma(p.uncertainty)))
        .collect();
    let worst = per_patch.iter().map(|p| p.1).fold(0.0, f64::max);
    let description = if bound {
        format!(
            "the radiosity solver's per-patch error bound b (largest {worst:.3} ΔE*ab), taken as the 95th percentile of an isotropic CIELAB error: σ = b/2.795 per axis"
        )
    } else {
        format!(
            "the {}'s per-patch 95 % half-width h (largest {worst:.3} ΔE*ab), as isotropic CIELAB noise: σ = h/(1.96·√3) per axis",
            if s.source.is_some() { "read-back" } else { "path tracer" }
        )
    };
    Ok((
        RenderConfidenceSection {
            method: format!("{method} ({})", s.method),
            target_de: None,
            per_patch,
            measure: measure.into(),
            converged: Some(s.converged),
            seconds: Some(s.seconds),
        },
        RenderUncertainty {
            sigma_lab,
            description,
        },
    ))
}

#[cfg(test)]
mod tests {
    use super::super::files::testdir;
    use super::*;

    #[test]
    fn half_widths_and_bounds_become_cielab_sigmas() {
        let dir = testdir::fresh("render");
        let summary = |method: &str| {
            format!(
                r#"{{"method":"{method}","white":[17.4,15.6,4.2],"converged":true,"seconds":21.1,
                "spots":[{{"patch":1,"XYZ":[2.26,1.62,0.24],"de_uncertainty":0.5}},{{"patch":2,"XYZ":[8.0,5.9,1.0],"de_uncertainty":0.0}}],"image":null}}"#
            )
        };
        testdir::write(&dir, SUMMARY_FILE, &summary("path tracer"));
        let (r, u) = section(&dir).unwrap();
        assert_eq!(r.per_patch, vec![(1, 0.5), (2, 0.0)]);
        assert_eq!((r.converged, r.seconds), (Some(true), Some(21.1)));
        // 0.5 / (1.959964 · 1.7320508) = 0.1472859.
        assert!((u.sigma_lab[&1] - 0.147_285_9).abs() < 1e-6, "{u:?}");
        testdir::write(&dir, SUMMARY_FILE, &summary("radiosity"));
        let (r, u) = section(&dir).unwrap();
        assert!(r.measure.contains("bound"));
        // 0.5 / √7.81473 = 0.1788600.
        assert!((u.sigma_lab[&1] - 0.178_860_0).abs() < 1e-6, "{u:?}");
        testdir::write(&dir, SUMMARY_FILE, "{\"method\":\"radiosity\"}");
        let e = section(&dir).unwrap_err();
        assert!(e.contains("is not a render summary"), "{e}");
        std::fs::remove_dir_all(&dir).ok();
    }
}
