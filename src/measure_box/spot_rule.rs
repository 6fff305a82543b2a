//! The box's spots read by a rule of [`crate::validation::sequential`]: each spot's repeats
//! end once its 95 % half-width in CIELAB (relative to the plan's white) is reached, the
//! spot meter's stated repeatability scaled by the figure pooled across the spots read
//! before it. Everything it decides follows from the journal's entries, so a resumed
//! session skips exactly what the first run skipped.

use super::plan::{BoxStep, Target};
use super::stats::GroupStats;
use crate::color::Xyz;
use crate::session::{patch_so_far, Entry, Step, Stopping};
use crate::validation::readings::PatchReading;
use crate::validation::repeatability::Repeatability;
use crate::validation::sequential::{width_decided, Pool, RepeatNoise, RepeatRule};

/// Each spot's mean (in the plan's order, as `spot_xyz` and `spots` of the box's summary
/// give them) with one reading's covariance the `stated` repeatability scaled by the
/// figure pooled across every spot's kept readings, and its degrees of freedom: what the
/// width rule's count rests on, so the validation's intervals take it too (Student's t
/// with the pooled ν, not each spot's own k − 1); a fixed count states it the same way.
/// None where nothing pools (no spot read twice).
pub fn pooled_readings(
    spots: &[(usize, Xyz, GroupStats)],
    stated: &Repeatability,
) -> Option<Vec<(usize, PatchReading)>> {
    let kept = |s: &GroupStats| s.n - s.outliers.len().min(s.n);
    let mut pool = Pool::default();
    for (_, xyz, s) in spots {
        pool.add_sample(*xyz, &s.cov, kept(s), stated);
    }
    let noise = pool.noise(*stated);
    let dof = pool.dof;
    if dof == 0 {
        return None;
    }
    spots
        .iter()
        .map(|(patch, xyz, s)| {
            let cov = noise.covariance(*xyz)?;
            Some((*patch, PatchReading::pooled(*xyz, cov, kept(s), dof, None)))
        })
        .collect()
}

/// The spots stage's stopping rule.
pub struct SpotStopping {
    pub rule: RepeatRule,
    /// The spot meter's stated repeatability in its emissive mode.
    pub stated: Repeatability,
    pub white: Xyz,
}

fn spot(step: &Step<BoxStep>) -> Option<usize> {
    match step.data.target {
        Target::Spot { patch } => Some(patch),
        _ => None,
    }
}

impl Stopping<BoxStep> for SpotStopping {
    fn skip(
        &self,
        index: usize,
        steps: &[Step<BoxStep>],
        entries: &[Option<Entry<BoxStep>>],
    ) -> bool {
        let RepeatRule::Width {
            half_width_jnd,
            most,
        } = self.rule
        else {
            return false;
        };
        let Some((_, first, this)) = patch_so_far(index, steps, entries, spot) else {
            return false;
        };
        // The spots before this one, each its readings in plan order.
        let mut pool = Pool::default();
        let mut group: (Option<usize>, Vec<Xyz>) = (None, Vec::new());
        for e in entries[..first].iter().flatten() {
            let p = spot(&steps[e.index]);
            if p != group.0 {
                pool.add(&group.1, &self.stated);
                group = (p, Vec::new());
            }
            group.1.push(e.reading.xyz);
        }
        pool.add(&group.1, &self.stated);
        // The pool's point estimate decides the count; the count only spends readings,
        // the intervals' validity does not rest on it.
        let noise = RepeatNoise {
            dof: None,
            ..pool.noise(self.stated)
        };
        width_decided(half_width_jnd, most, &this, &noise, self.white)
    }
}

#[cfg(test)]
mod tests {
    use metamer_drivers::{MeasureMode, Reading};

    use super::*;
    use crate::measure_box::plan::{BoxPlan, BoxStage};
    use crate::validation::sequential::half_width;

    /// A grey spot at 20 % of the white read by the CS-100A: the rule skips its repeats
    /// from the count at which the stated figure's half-width reaches the target, found by
    /// hand from the half-width of one reading (h₁/√n ≤ target), and a second spot's count
    /// then takes the figure pooled from the first.
    #[test]
    fn a_spots_repeats_end_at_the_count_its_half_width_needs() {
        let white = Xyz::new(15.573, 16.34, 18.356);
        let stated = crate::validation::repeatability::stated("cs100a", MeasureMode::Emissive);
        let grey = Reading::from_yxy(0.2 * 16.34, 0.3127, 0.3290, "CS-100A");
        let h1 = half_width(grey.xyz, &RepeatNoise::stated(stated), white, 1).unwrap();
        // Three readings needed: h₁/√3 just within the target, h₁/√2 not.
        let half_width_jnd = h1 / 3f64.sqrt() * 1.0001 / crate::validation::JND_DE76;
        let plan = BoxPlan {
            patches: vec![19, 22],
            spot_rule: Some(RepeatRule::Width {
                half_width_jnd,
                most: 6,
            }),
            spot_white: Some([white[0], white[1], white[2]]),
            ..BoxPlan::default()
        };
        let steps = plan.steps(BoxStage::Spots);
        assert_eq!(steps.len(), 12);
        let rule = SpotStopping {
            rule: plan.spot_rule.clone().unwrap(),
            stated,
            white,
        };
        let mut entries: Vec<Option<Entry<BoxStep>>> = vec![None; steps.len()];
        let take = |i: usize, entries: &mut Vec<Option<Entry<BoxStep>>>| {
            entries[i] = Some(Entry {
                index: i,
                label: steps[i].label.clone(),
                role: steps[i].role.clone(),
                mode: steps[i].mode,
                data: steps[i].data.clone(),
                reading: grey.clone(),
            });
        };
        let skipped = |entries: &Vec<Option<Entry<BoxStep>>>| -> Vec<bool> {
            (0..6).map(|i| rule.skip(i, &steps, entries)).collect()
        };
        for i in 0..3 {
            assert!(!rule.skip(i, &steps, &entries), "step {i}");
            take(i, &mut entries);
        }
        assert_eq!(skipped(&entries), [false, false, false, true, true, true]);
        // The first spot's three identical readings pool to a factor 0: the second spot
        // is decided at the least count.
        take(6, &mut entries);
        assert!(!rule.skip(7, &steps, &entries));
        take(7, &mut entries);
        assert!((8..12).all(|i| rule.skip(i, &steps, &entries)));
    }

    /// The rule is part of the plan's options, so of its fingerprint: a journal of the
    /// fixed plan is not resumed by a width plan.
    #[test]
    fn the_fingerprint_covers_the_rule() {
        let fixed = BoxPlan::default();
        let width = BoxPlan {
            spot_rule: Some(RepeatRule::Width {
                half_width_jnd: 0.2,
                most: 10,
            }),
            spot_white: Some([15.573, 16.34, 18.356]),
            ..BoxPlan::default()
        };
        let fp = |p: &BoxPlan| {
            p.session_plan(BoxStage::Spots, &Default::default())
                .fingerprint()
                .unwrap()
        };
        assert_ne!(fp(&fixed), fp(&width));
        // The fixed plan's options are as before the rule existed.
        let options = fixed
            .session_plan(BoxStage::Spots, &Default::default())
            .options;
        assert!(
            !options["plan"].contains("spot_rule"),
            "{}",
            options["plan"]
        );
    }
}
