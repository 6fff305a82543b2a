//! The readers of every readings format, on small inputs with hand-checked values.

use super::*;

fn parse(text: &str) -> Result<ReadingSet, ReadingsError> {
    parse_readings(text, Path::new("r.csv"))
}

#[test]
fn csv_repeats_give_the_standard_error_of_their_mean() {
    // Rows 10, 12, 14 in Y: mean 12, s = 2, standard error 2/√3 = 1.1547005.
    let s = parse("patch,X,Y,Z\n1,1,10,1\n1,1,12,1\n1,1,14,1\nwhite,95,100,108\n").unwrap();
    assert_eq!(s.format, Format::Csv);
    let p = &s.patches[&1];
    assert_eq!(p.xyz, Xyz::new(1.0, 12.0, 1.0));
    assert!((p.u_xyz[1] - 1.154_700_5).abs() < 1e-6);
    assert_eq!(p.u_xyz[0], 0.0);
    assert_eq!((p.n, p.source), (3, UncertaintySource::Repeats));
    assert_eq!(s.white.unwrap().xyz, Xyz::new(95.0, 100.0, 108.0));
}

#[test]
fn csv_given_sd_and_n() {
    // sd 0.4 over n = 4 readings: u = 0.2; two such rows: √(0.2² + 0.2²)/2 = 0.1414214.
    let s = parse("patch,X,Y,Z,sd_X,sd_Y,sd_Z,n\n2,1,2,3,0.4,0.4,0.4,4\n2,1,2,3,0.4,0.4,0.4,4\n")
        .unwrap();
    let p = &s.patches[&2];
    assert!((p.u_xyz[2] - 0.141_421_4).abs() < 1e-6);
    assert_eq!((p.n, p.source), (8, UncertaintySource::Given));
}

#[test]
fn csv_errors_name_the_line() {
    let e = parse("patch,X,Y,Z\n1,1,2,3\n25,1,2,3\n")
        .unwrap_err()
        .to_string();
    assert!(e.starts_with("r.csv:3:") && e.contains("'25'"), "{e}");
    let e = parse("patch,X,Y\n1,1,2\n").unwrap_err().to_string();
    assert!(e.contains("r.csv:1:") && e.contains("'Z'"), "{e}");
    let e = parse("patch,X,Y,Z\n1,1,x,3\n").unwrap_err().to_string();
    assert!(e.contains("r.csv:2:") && e.contains("'x'"), "{e}");
}

#[test]
fn spot_lines_unnumbered_are_patches_in_order_or_repeats() {
    let line = |y: f64| {
        format!(
            "{{\"XYZ\":[1,{y},1],\"xyY\":[0.3,0.3,{y}],\"flags\":[],\"instrument\":\"cs100a\"}}\n"
        )
    };
    let two: String = [1.0, 2.0].iter().map(|y| line(*y)).collect();
    let s = parse(&two).unwrap();
    assert_eq!(s.format, Format::SpotJson);
    assert_eq!(s.patches[&2].xyz[1], 2.0);
    assert_eq!(s.instruments, ["cs100a"]);
    let rep: String = (0..48).map(|i| line(i as f64)).collect();
    let s = parse(&rep).unwrap();
    assert_eq!(s.patches.len(), 24);
    assert_eq!(s.patches[&24].xyz[1], 46.5);
    let bad: String = (0..25).map(|i| line(i as f64)).collect();
    assert!(parse(&bad)
        .unwrap_err()
        .to_string()
        .contains("25 unnumbered"));
    let null = "{\"XYZ\":[null,1,null],\"xyY\":[null,null,1]}\n";
    let e = parse(null).unwrap_err().to_string();
    assert!(
        e.contains("r.csv:1:") && e.contains("did not measure"),
        "{e}"
    );
}

#[test]
fn journal_entries_by_patch_number_or_colorchecker_label() {
    let header = r#"{"type":"header","format":"metamer-session-journal","version":2,"kind":"measure-box","fingerprint":"x","options":{},"steps":3,"started_s":0,"data":{"instruments":{"spot":{"info":{"model":"cs100a","serial":"7"},"options":{}}},"details":null}}"#;
    let entry = |patch: &str, y: f64| {
        format!(
            r#"{{"type":"entry","index":0,"label":"p","role":"spot","mode":"emissive","data":{{"patch":{patch}}},"reading":{{"xyz":[1,{y},1],"xyy":[0,0,0],"spectrum":null,"flags":[],"integration_s":null,"instrument":"cs100a","timestamp_s":0}}}}"#
        )
    };
    let text = format!(
        "{header}\n{}\n{}\n{}\n{{\"type\":\"ent",
        entry("3", 1.0),
        entry("3", 3.0),
        entry("\"white\"", 9.0)
    );
    let s = parse(&text).unwrap();
    assert_eq!(s.format, Format::Journal);
    assert_eq!(s.patches[&3].xyz[1], 2.0);
    assert_eq!(s.white.as_ref().unwrap().xyz[1], 9.0);
    assert_eq!(s.instruments, ["spot: cs100a #7"]);
    assert!(s.notes.iter().any(|n| n.contains("torn")));
    // characterize journals number drive colours; ColorChecker ones are known by label.
    let text = text
        .replace("measure-box", "characterize")
        .replace(r#""label":"p""#, r#""label":"ColorChecker orange""#);
    let s = parse(&text).unwrap();
    assert_eq!(s.patches.keys().collect::<Vec<_>>(), [&7]);
}

#[test]
fn render_json_carries_its_confidence() {
    let text = r#"{"method":"radiosity","white":[1,1,1],"patches":[{"patch":5,"XYZ":[1,2,3],"de_bound":0.0279548}]}"#;
    let s = parse(text).unwrap();
    assert_eq!(s.format, Format::RenderJson);
    let p = &s.patches[&5];
    assert_eq!(p.source, UncertaintySource::Render);
    assert!((p.u_lab - 0.01).abs() < 1e-6);
}

/// A `spot --json` line is written and read by this module: what [`spot_line`] writes
/// reads back to the same XYZ, and a single reading gets its instrument's stated
/// repeatability only where the model reads emitted light alone (the CS-100A), since the
/// line does not say its mode.
#[test]
fn spot_lines_written_here_read_back() {
    use metamer_drivers::Reading;
    let cs = Reading::from_yxy(10.0, 0.25, 0.5, "cs100a");
    let line = spot_line(&cs);
    assert!(
        line.starts_with("{\"XYZ\":[5.0,10.0,5.0],\"xyY\":[0.25,0.5,10.0],\"flags\":[],\"instrument\":\"cs100a\"}"),
        "{line}"
    );
    let s = parse(&format!("{line}\n")).unwrap();
    assert_eq!(s.format, Format::SpotJson);
    let p = &s.patches[&1];
    assert_eq!(p.xyz, cs.xyz);
    assert_eq!(p.source, UncertaintySource::Instrument);
    // σY of one CS-100A reading of 10 cd/m²: 0.1 % of 10 and the last of four digits
    // (0.01, variance 0.01²/12): 0.01·√(1 + 1/12) = 0.010408.
    assert!((p.reading_sd()[1] - 0.010_408_33).abs() < 1e-8, "{p:?}");
    let i1 = Reading::from_yxy(10.0, 0.45, 0.5, "i1pro");
    let s = parse(&format!("{}\n", spot_line(&i1))).unwrap();
    assert_eq!(s.patches[&1].source, UncertaintySource::Unknown);
}

/// A row whose sd and cov are a figure pooled across the patches states its degrees of
/// freedom (`dof`) and, read by a verdict rule, its `most`; written and read back they are
/// the same; a file without the columns reads as before (n − 1 for n ≥ 2), an empty `dof`
/// cell states the figure known, and impossible cells are refused with their line.
#[test]
fn a_pooled_row_states_its_degrees_of_freedom_and_old_rows_read_as_before() {
    let dir = std::env::temp_dir().join(format!("metamer-pooled-{}", std::process::id()));
    let file = dir.join("spots.csv");
    let cov = covariance::from_parts([0.01, 0.02, 0.03], [0.0001, 0.0, 0.0002]);
    let pooled = PatchReading::pooled(Xyz::new(1.0, 2.0, 3.0), cov, 2, 72, Some(6));
    let own = PatchReading::of(&[Xyz::new(4.0, 5.0, 6.0), Xyz::new(4.1, 5.0, 6.0)]);
    write_readings(&file, &[(1, pooled.clone()), (2, own.clone())]).unwrap();
    let text = std::fs::read_to_string(&file).unwrap();
    assert!(
        text.starts_with(&format!("{}{}", write::HEADER, ",dof,most\n")),
        "{text}"
    );
    let back = read_readings(&file).unwrap();
    assert_eq!(
        (back.patches[&1].dof, back.patches[&1].most),
        (Some(72), Some(6))
    );
    assert_eq!(back.patches[&1].n, 2);
    assert_eq!(
        (back.patches[&2].dof, back.patches[&2].most),
        (Some(1), None)
    );
    // The mean's covariance is one reading's over n: 0.02²/2 in Y.
    assert!((back.patches[&1].u_xyz[1] - 0.02 / 2f64.sqrt()).abs() < 1e-12);
    // Without a rule the stages' files are as they were.
    write_readings(&file, &[(2, own)]).unwrap();
    let text = std::fs::read_to_string(&file).unwrap();
    assert_eq!(text.lines().next(), Some(write::HEADER));
    std::fs::remove_dir_all(&dir).unwrap();

    let old = parse("patch,X,Y,Z,sd_X,sd_Y,sd_Z,n\n3,1,2,3,0.1,0.2,0.3,5\n").unwrap();
    assert_eq!((old.patches[&3].dof, old.patches[&3].most), (Some(4), None));
    let known = parse("patch,X,Y,Z,sd_X,sd_Y,sd_Z,n,dof\n3,1,2,3,0.1,0.2,0.3,5,\n").unwrap();
    assert_eq!(known.patches[&3].dof, None);
    for (row, says) in [
        ("3,1,2,3,0.1,0.2,0.3,5,0,", "dof: '0'"),
        ("3,1,2,3,0.1,0.2,0.3,5,1.5,", "dof: '1.5'"),
        (
            "3,1,2,3,0.1,0.2,0.3,5,4,101",
            "most: '101' must be a whole number from 1 to 100",
        ),
    ] {
        let e = parse(&format!("patch,X,Y,Z,sd_X,sd_Y,sd_Z,n,dof,most\n{row}\n"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("r.csv:2:") && e.contains(says), "{row}: {e}");
    }
    let e = parse("patch,X,Y,Z,dof\n3,1,2,3,4\n")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("r.csv:1:") && e.contains("dof needs the sd_X"),
        "{e}"
    );
}
