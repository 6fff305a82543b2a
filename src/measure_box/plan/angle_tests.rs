//! The plan's fall-off rule against the fit it is for.

use super::*;

/// The plan accepts exactly the fall-off angles the fit can use: for sets of angles
/// that pass the other rules (inside ±90°, increasing, with 0), `validate` says yes
/// where the fit of readings at those angles (a cos^1.3 light, both planes) succeeds.
#[test]
fn the_plan_accepts_exactly_the_angles_the_fit_can_use() {
    let mut state = 0x2545_f491_4f6c_dd1d_u64;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    let (mut accepted, mut refused) = (0, 0);
    for case in 0..120 {
        let mut a: Vec<f64> = vec![0.0];
        for _ in 0..next() % 6 {
            let v = (next() % 171) as f64 - 85.0;
            if !a.contains(&v) {
                a.push(v);
            }
        }
        // Every fourth set one-sided, so both answers come up.
        if case % 4 == 0 {
            a.retain(|v| *v >= 0.0);
        }
        a.sort_by(f64::total_cmp);
        let plan = BoxPlan {
            falloff_angles_deg: a.clone(),
            ..BoxPlan::default()
        };
        let readings: Vec<(Plane, f64, f64)> = [Plane::Horizontal, Plane::Vertical]
            .into_iter()
            .flat_map(|p| {
                a.iter()
                    .map(move |&g| (p, g, 80.0 * g.to_radians().cos().powf(1.3)))
            })
            .collect();
        let fits = crate::measure_box::falloff::fit_light(&readings).is_ok();
        assert_eq!(plan.validate().is_ok(), fits, "angles {a:?}");
        if fits {
            accepted += 1
        } else {
            refused += 1
        }
    }
    assert!(accepted > 10 && refused > 10, "{accepted} {refused}");
}
