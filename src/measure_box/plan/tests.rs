//! The plan's steps, prompts and checks.

use super::*;

#[test]
fn the_default_plan_is_the_papers() {
    let p = BoxPlan::default();
    p.validate().unwrap();
    // 25 tiles × 5, 2 planes × 9 angles, wall + 24 patches, 24 spots × 5.
    let counts: Vec<usize> = BoxStage::ALL.iter().map(|&s| p.steps(s).len()).collect();
    assert_eq!(counts, [125, 18, 25, 120]);
    let tiles = p.steps(BoxStage::Tiles);
    assert_eq!(
        tiles[5 * 13].prepare,
        Prepare::Operator {
            prompt: "place the i1Pro on tile row 2, column 3 of the light on the left wall \
                     (3rd row from the top, 4th column from the open front)"
                .into()
        }
    );
    let place = |r, c| p.tile_place(r, c);
    assert_eq!(place(0, 0), "the top corner nearest the open front");
    assert_eq!(place(4, 4), "the bottom corner nearest the back");
    assert_eq!(place(2, 2), "the centre tile");
    assert_eq!(place(0, 2), "top row, 3rd column from the open front");
    assert_eq!(
        place(3, 0),
        "4th row from the top, column nearest the open front"
    );
    assert_eq!(ordinal(12), "12th");
    assert_eq!(ordinal(22), "22nd");
    assert_eq!(p.falloff_tile(), [2, 2]);
    assert_eq!(Plane::Vertical.c_gamma(-40.0), (270.0, 40.0));
    assert_eq!(Plane::Horizontal.c_gamma(20.0), (0.0, 20.0));
}

#[test]
fn bad_plans_name_the_field() {
    let check = |json: &str, want: &str| {
        let dir = std::env::temp_dir().join(format!("metamer-boxplan-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("plan.json");
        std::fs::write(&path, json).unwrap();
        let e = BoxPlan::load(&path).unwrap_err().to_string();
        assert!(e.contains(want), "{json}: {e}");
    };
    check(
        r#"{"repeats":0}"#,
        "plan: repeats: must be between 1 and 100, got 0",
    );
    check(r#"{"falloff_angles_deg":[-20,20]}"#, "must contain 0");
    check(r#"{"falloff_angles_deg":[0,95]}"#, "95.0 is not an angle");
    // A number no one can read in 309 digits.
    check(
        r#"{"falloff_angles_deg":[0,1e308]}"#,
        "falloff_angles_deg: 1e308 is not an angle",
    );
    check(r#"{"geometry":{"size_m":1e308}}"#, "and 5 m, got 1e308");
    // serde would read an array as the fields in order: three repeat counts.
    check(
        "[1, 2, 3]",
        "not a valid plan: a plan is a JSON object of named fields",
    );
    check(
        r#"{"geometry": [0.5]}"#,
        "not a valid plan: geometry is a JSON object of named fields",
    );
    check(r#"{"falloff_angles_deg":[0,20,10]}"#, "10 follows 20");
    check(
        r#"{"falloff_angles_deg":[0,20,40,60]}"#,
        "falloff_angles_deg: needs an angle on each side of the normal, and has no negative one",
    );
    check(
        r#"{"falloff_angles_deg":[-60,-30,0]}"#,
        "has no positive one",
    );
    check(r#"{"patches":[1,25]}"#, "25 is not a patch number");
    check(r#"{"patches":[3,3]}"#, "patch 3 is listed twice");
    check(
        r#"{"geometry":{"rows":0}}"#,
        "geometry.rows: must be between 1 and 64",
    );
    check(
        r#"{"geometry":{"light_m":[0.4,0.1,0.1,0.4]}}"#,
        "geometry.light_m",
    );
    check(r#"{"geometry":{"viewpoint_m":[0,0,1]}}"#, "z < 0");
    check(r#"{"falloff_tile":[5,0]}"#, "outside the 5 × 5 grid");
    check(r#"{"repeat":3}"#, "unknown field `repeat`");
    check(
        r#"{"spot_rule":{"rule":"width","half_width_jnd":0.2,"most":10}}"#,
        "plan: spot_white: a width rule needs the white",
    );
    check(
        r#"{"spot_rule":{"rule":"verdict","margin":0.1,"most":10}}"#,
        "plan: spot_rule: a verdict needs the display's reading",
    );
    check(
        r#"{"spot_rule":{"rule":"width","half_width_jnd":0.2,"most":1},"spot_white":[1,1,1]}"#,
        "plan: spot_rule: the most readings must be between 2 and 100, got 1",
    );
    check(r#"{"repeats":"x"}"#, "not a valid plan");
}

#[test]
fn the_adaptive_first_pass_is_the_subset_argued() {
    let plan = BoxPlan::default();
    assert_eq!(
        first_angles(&plan.falloff_angles_deg),
        [-80.0, -40.0, 0.0, 40.0, 80.0]
    );
    assert_eq!(first_angles(&[-60.0, -30.0, 0.0, 30.0]), [-60.0, 0.0, 30.0]);
    let tiles = plan.first_pass(BoxStage::Tiles);
    assert_eq!(tiles.len(), 9);
    assert_eq!(tiles[4], Target::Tile { row: 2, col: 2 });
    // The normal once, in the horizontal plane: 5 + 4 angles, not 5 + 5.
    let falloff = plan.first_pass(BoxStage::Falloff);
    assert_eq!(falloff.len(), 9);
    let normals: Vec<&Target> = falloff
        .iter()
        .filter(|t| matches!(t, Target::Falloff { angle_deg, .. } if *angle_deg == 0.0))
        .collect();
    assert_eq!(
        normals,
        [&Target::Falloff {
            plane: Plane::Horizontal,
            angle_deg: 0.0
        }]
    );
    // The fixed plan reads every target; the adaptive one its first pass, and at most its
    // caps in the budget.
    let adaptive = BoxPlan {
        adaptive: Some(AdaptiveRule::default()),
        ..BoxPlan::default()
    };
    assert_eq!(adaptive.steps(BoxStage::Tiles).len(), 9 * 2);
    assert_eq!(adaptive.most_steps(BoxStage::Tiles).len(), 11 * 2);
    assert_eq!(adaptive.most_steps(BoxStage::Falloff).len(), 12);
    assert_eq!(adaptive.steps(BoxStage::Spots).len(), 120);
}
