//! The diagnostics' verdict: each assumption's check judged against the tolerance and the
//! measurement noise, in plain words with what the profile rests on.

use super::super::mixture_advice::mixture_advice;
use super::super::model::ModelKind;
use super::Diagnostics;

impl Diagnostics {
    pub(super) fn judge(&mut self, additivity_weight: f64, drift_weights: &[f64]) {
        let mut checks = self.sort_checks(additivity_weight, drift_weights);
        let power_law_model = matches!(self.model, ModelKind::PlccGamma);
        if power_law_model {
            checks.failures.append(&mut checks.power_notes);
        }
        let mut verdict = self.assumptions_verdict(&checks);
        if let Some(n) = self.noise.as_ref().filter(|n| !n.disagreeing.is_empty()) {
            verdict = format!(
                "Warning: repeated readings disagree beyond the instrument's repeatability \
                 ({}); that is a reading gone wrong, not noise, and it inflates the noise \
                 figure this verdict allows for: re-measure those patches. {verdict}",
                n.disagreeing.join("; ")
            );
        }
        if !power_law_model && !checks.power_notes.is_empty() {
            verdict.push_str(&format!(
                " Note: {} (plcc-gamma would not cope; measured-ramp TRCs do).",
                checks.power_notes.join("; ")
            ));
        }
        if let Some(mixed) = self.few_mixtures {
            verdict.push(' ');
            verdict.push_str(&self.mixture_note(mixed));
        }
        if let Some([folded, total]) = self.folded_tetrahedra {
            verdict.push(' ');
            verdict.push_str(&fold_note(folded, total));
        }
        let r = &self.residuals;
        verdict.push_str(&format!(
            " The fitted {} reproduces the {} readings it was fitted to with mean ΔE00 {:.2}, \
             95th percentile {:.2}, max {:.2}.",
            self.model, r.patches, r.mean_de00, r.p95_de00, r.max_de00
        ));
        self.failures = checks.failures;
        self.verdict = verdict;
    }

    /// Each assumption's check sorted into failed, within the noise, passed (its short
    /// figure) and not checked, with the TRCs that are no power law aside.
    fn sort_checks(&self, additivity_weight: f64, drift_weights: &[f64]) -> Checks {
        let tol = self.tolerance_de00;
        let sigma = self.noise.as_ref().map(|n| n.de00);
        // A check combining patches averaged over n₁, n₂, … readings scatters by about
        // σ·√(Σ 1/nᵢ); beyond tolerance + twice that the display, not the meter, is to blame.
        let margin = |weight: f64| sigma.map_or(0.0, |s| 2.0 * s * weight.sqrt());
        let judge = |c: &mut Checks, value: f64, readings: f64, failure: String, short: String| {
            if value <= tol {
                c.largest.push(short);
            } else if value <= tol + margin(readings) {
                c.in_noise.push(short);
            } else {
                c.failures.push(failure);
            }
        };
        let mut c = Checks::default();
        match &self.additivity {
            Some(a) => judge(
                &mut c,
                a.de00,
                additivity_weight,
                format!(
                    "the channels are not additive: white differs from black + red + green + \
                     blue by ΔE00 {:.2} (luminance {:+.1} %)",
                    a.de00, a.luminance_error_percent
                ),
                format!("additivity {:.2}", a.de00),
            ),
            None => c
                .unchecked
                .push("additivity (needs black, the three primaries and white)"),
        }
        if self.channels.is_empty() {
            c.unchecked
                .push("chromaticity constancy (needs black and the three primaries)");
        }
        for (i, ch) in self.channels.iter().enumerate() {
            match (ch.chromaticity_drift_de00, ch.levels) {
                (Some(e), n) if n > 0 => judge(
                    &mut c,
                    e,
                    drift_weights.get(i).copied().unwrap_or(2.0),
                    format!(
                        "the {} channel's chromaticity drifts along its ramp: ΔE00 {:.2} at \
                         drive {:.3}{}",
                        ch.channel,
                        e,
                        ch.drift_at_drive.unwrap_or(f64::NAN),
                        ch.chromaticity_drift_xy
                            .map(|v| format!(" (Δxy up to {v:.4})"))
                            .unwrap_or_default()
                    ),
                    format!("{} drift {:.2}", ch.channel, e),
                ),
                _ => c
                    .unchecked
                    .push("chromaticity constancy of a channel without a ramp"),
            }
            if let (Some(e), Some(g)) = (ch.power_law_de00, ch.gamma) {
                if e > tol + margin(1.0) {
                    c.power_notes.push(format!(
                        "the {} TRC is not a power law: it deviates from γ = {:.2} by up to \
                         ΔE00 {:.2}",
                        ch.channel, g, e
                    ));
                }
            }
        }
        c.unchecked.dedup();
        c
    }

    /// The verdict on PLCC's assumptions from the sorted checks, with what the noise
    /// explains.
    fn assumptions_verdict(&self, c: &Checks) -> String {
        let tol = self.tolerance_de00;
        let mut verdict = if c.failures.is_empty() && c.unchecked.is_empty() {
            if c.in_noise.is_empty() {
                format!(
                    "PLCC's assumptions hold within ΔE00 {tol} (largest: {}).",
                    c.largest.join(", ")
                )
            } else {
                format!("PLCC's assumptions hold within ΔE00 {tol} and the measurement noise.")
            }
        } else if c.failures.is_empty() {
            format!(
                "No PLCC assumption fails within ΔE00 {tol} among those checked; not checked: {}.",
                c.unchecked.join("; ")
            )
        } else if self.model == ModelKind::Lut {
            // The fitted model is the answer to these failures, so the verdict says that
            // first rather than opening on assumptions the model does not make.
            format!(
                "The lut assumes neither constant chromaticity nor additivity, so it holds \
                 where PLCC's assumptions fail, as they do here: {}.",
                c.failures.join("; ")
            )
        } else {
            format!(
                "PLCC's assumptions fail: {}. Models that do not assume them: lut (needs a full \
                 grid of patches) or matrix-lsq (fits over all patches).",
                c.failures.join("; ")
            )
        };
        match &self.noise {
            Some(n) if !c.in_noise.is_empty() => verdict.push_str(&format!(
                " Within measurement noise (one reading ±{:.2} ΔE00 1σ, from {}): {}.",
                n.de00,
                n.source,
                c.in_noise.join(", ")
            )),
            Some(_) => {}
            None if !c.failures.is_empty() => verdict.push_str(
                " No patch was measured twice, so measurement noise is not separated from the \
                 display's behaviour: measure repeats to tell them apart.",
            ),
            None => {}
        }
        verdict
    }

    /// What a profile fitted without (enough) mixtures rests on, in a few sentences.
    fn mixture_note(&self, mixed: usize) -> String {
        let measured = match mixed {
            0 => "Mixed colours were not measured (no patch but the white has two channels \
                  on)"
            .to_string(),
            n => format!(
                "Mixed colours were barely measured ({n} patch{} with two or more channels on \
                 besides the white)",
                if n == 1 { "" } else { "es" }
            ),
        };
        let check = match &self.additivity {
            Some(a) => format!(
                "the one check there is, the white against black plus the three primaries \
                 (R + G + B − 2K), differs by ΔE00 {:.2} (luminance {:+.1} %): mixtures near \
                 white may be off by about that much, and further in the midtones, since \
                 crosstalk that vanishes at full drive is invisible to it",
                a.de00, a.luminance_error_percent
            ),
            None => "not even the white against the sum of the primaries could be checked \
                     (black, the three primaries and white are needed)"
                .to_string(),
        };
        format!(
            "{measured}, so between the ramps the profile's colours rest on {}'s assumptions; \
             {check}. {}",
            self.model,
            mixture_advice()
        )
    }
}

/// The verdict's warning for a table that folds in `folded` of its `total` tetrahedra.
fn fold_note(folded: usize, total: usize) -> String {
    format!(
        "Warning: the fitted table folds in {folded} of its {total} tetrahedra ({:.1} %): \
         colours there have more than one drive value (or none), so the model's inverse \
         (reproduce, the ICC profile's B2A0 table) is unreliable there. A display's light \
         rises with every channel, so a fold comes from noise in the readings the table \
         stores (a measured grid keeps every reading as a node; a table fitted to scattered \
         patches is held from folding): measure those patches again, or use shaper-matrix, \
         which cannot fold.",
        100.0 * folded as f64 / total as f64
    )
}

/// The assumptions' checks sorted by how they came out.
#[derive(Default)]
struct Checks {
    failures: Vec<String>,
    /// Beyond the tolerance but within the measurement noise: the short figures.
    in_noise: Vec<String>,
    /// Within the tolerance: the short figures.
    largest: Vec<String>,
    unchecked: Vec<&'static str>,
    /// TRCs that are no power law; a failure only for the model that assumes one.
    power_notes: Vec<String>,
}
