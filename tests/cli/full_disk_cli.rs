//! Every command on a full disk: with its output stream on `/dev/full` (every write fails
//! with ENOSPC) a command ends with exit 1 and one line naming the stream, never a panic
//! (exit 101, "panicked at"); with standard error there it still exits without a panic.
//! The commands are enumerated from the program's own help, recursively, so a new command
//! fails `every_command_is_listed` until it is given arguments here (or a reason it is run
//! elsewhere). A result file written onto a full disk leaves the earlier file whole.

use std::fs::File;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use crate::support::{fresh_dir, metamer_command, root, text};

/// Where a command says what it has to say once its work is done.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Says {
    Stdout,
    Stderr,
}

/// The leaf commands named in the help of `metamer` and of each group, e.g. `color xyz`.
fn commands(prefix: &[String]) -> Vec<Vec<String>> {
    let o = metamer_command()
        .args(prefix)
        .arg("--help")
        .output()
        .unwrap();
    assert!(o.status.success(), "{prefix:?} --help: {}", text(&o.stderr));
    let help = text(&o.stdout);
    let Some(list) = help.split("Commands:\n").nth(1) else {
        return vec![prefix.to_vec()];
    };
    let names: Vec<String> = list
        .lines()
        .take_while(|l| l.starts_with("  "))
        .filter_map(|l| l.split_whitespace().next().map(str::to_string))
        .filter(|n| n != "help")
        .collect();
    names
        .into_iter()
        .flat_map(|n| {
            let mut p = prefix.to_vec();
            p.push(n);
            commands(&p)
        })
        .collect()
}

/// How each command is run here, or why it is not.
fn case(command: &[&str], dir: &Path) -> Result<(Vec<String>, Says), &'static str> {
    let d = |name: &str| dir.join(name).to_str().unwrap().to_string();
    let own = |a: &[&str]| a.iter().map(|s| s.to_string()).collect::<Vec<_>>();
    let ti3 = "tests/data/dispread_analytic.ti3";
    Ok(match command {
        ["color", "xyz"] => (
            own(&[
                "data/paper_white_reflectance.csv",
                "--quantity",
                "reflectance",
            ]),
            Says::Stdout,
        ),
        ["color", "delta-e"] => (vec!["--pairs".into(), d("pairs.csv")], Says::Stdout),
        ["devices"] => (vec![], Says::Stdout),
        ["spot"] => (
            own(&["--instrument", "sim:cs100a?time_scale=0"]),
            Says::Stdout,
        ),
        ["fit"] => (
            [
                own(&["--measurements", ti3, "--force", "-o"]),
                vec![d("fit.json")],
            ]
            .concat(),
            Says::Stdout,
        ),
        ["verify"] => (
            [
                own(&["--measurements", ti3, "--profile"]),
                vec![d("profile.json")],
            ]
            .concat(),
            Says::Stdout,
        ),
        ["reproduce"] => (
            vec![
                "--profile".into(),
                d("profile.json"),
                "--xyz".into(),
                d("targets.csv"),
                "-o".into(),
                d("rgb.csv"),
                "--force".into(),
            ],
            Says::Stderr,
        ),
        ["light", "fit"] => (
            [
                own(&[
                    "--falloff",
                    "data/light_falloff_9_angles.csv",
                    "--width-m",
                    "0.3",
                    "--height-m",
                    "0.3",
                    "--luminance",
                    "1000",
                    "--force",
                    "-o",
                ]),
                vec![d("light.json")],
            ]
            .concat(),
            Says::Stdout,
        ),
        ["light", "show"] => (vec![d("light.ies")], Says::Stdout),
        ["validate"] => (
            [
                own(&[
                    "--reference",
                    "tests/data/validate/box.csv",
                    "--test",
                    "tests/data/validate/display.csv",
                    "--draws",
                    "1000",
                    "--force",
                    "-o",
                ]),
                vec![d("validation")],
            ]
            .concat(),
            Says::Stdout,
        ),
        ["simulate", "cs100a"] => (own(&["--pty"]), Says::Stdout),
        ["export"] => (
            [
                own(&["--to", "pbrt-v4", "--no-difference", "--force", "-o"]),
                vec![d("export")],
            ]
            .concat(),
            Says::Stdout,
        ),
        ["render", "spots"] => (own(&["--method", "radiosity"]), Says::Stdout),
        ["render", "image" | "spots-from-image" | "probes" | "convergence"]
        | ["characterize" | "measure-box" | "budget" | "experiment" | "lab"] => {
            return Err(
                "a measuring session, a render or a study, kept out of this quick test; it \
                 prints through the console path, which `no_source_prints_around_the_console` \
                 checks",
            )
        }
        _ => return Err("not listed"),
    })
}

/// Runs `metamer ARGS` in the repository's root with `stream` on /dev/full and the other
/// captured; (exit code, the captured stream). Killed after a minute: a command that
/// serves until stopped must stop on its first failed write.
fn on_full_disk(args: &[String], stream: Says) -> (Option<i32>, String) {
    let full = || Stdio::from(File::options().write(true).open("/dev/full").unwrap());
    let mut c = metamer_command();
    c.args(args)
        .current_dir(root())
        .env_remove("METAMER_SIM_TIME_SCALE")
        .stdin(Stdio::null());
    match stream {
        Says::Stdout => c.stdout(full()).stderr(Stdio::piped()),
        Says::Stderr => c.stderr(full()).stdout(Stdio::piped()),
    };
    let mut child = c.spawn().unwrap();
    let start = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > Duration::from_secs(60) {
            child.kill().unwrap();
            panic!("{args:?} with {stream:?} on /dev/full did not stop");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let o = child.wait_with_output().unwrap();
    let captured = match stream {
        Says::Stdout => text(&o.stderr),
        Says::Stderr => text(&o.stdout),
    };
    (o.status.code(), captured)
}

/// The inputs the listed commands read: a profile, its targets, a light file, Lab pairs.
fn inputs(dir: &Path) {
    std::fs::write(
        dir.join("pairs.csv"),
        "L1,a1,b1,L2,a2,b2\n50,2.6772,-79.7751,50,0,-82.7485\n",
    )
    .unwrap();
    std::fs::write(dir.join("targets.csv"), "X,Y,Z\n40,50,60\n").unwrap();
    let run = |args: &[&str]| {
        let o = metamer_command()
            .args(args)
            .current_dir(root())
            .output()
            .unwrap();
        assert!(o.status.success(), "{args:?}: {}", text(&o.stderr));
    };
    let d = |name: &str| dir.join(name).to_str().unwrap().to_string();
    let (profile, light, ies) = (d("profile.json"), d("l.json"), d("light.ies"));
    run(&[
        "fit",
        "--measurements",
        "tests/data/dispread_analytic.ti3",
        "-o",
        &profile,
    ]);
    run(&[
        "light",
        "fit",
        "--falloff",
        "data/light_falloff_9_angles.csv",
        "-o",
        &light,
        "--ies",
        &ies,
        "--width-m",
        "0.3",
        "--height-m",
        "0.3",
        "--luminance",
        "1000",
    ]);
}

#[test]
fn every_command_ends_with_one_line_and_exit_1_when_its_output_cannot_be_written() {
    let dir = fresh_dir("full");
    inputs(&dir);
    let mut skipped = Vec::new();
    let mut run = 0;
    // The program itself: clap's help and version go to stdout too.
    let mut cases: Vec<(Vec<String>, Says)> = vec![
        (vec!["--help".into()], Says::Stdout),
        (vec!["--version".into()], Says::Stdout),
        (vec!["help".into(), "fit".into()], Says::Stdout),
    ];
    for command in commands(&[]) {
        let words: Vec<&str> = command.iter().map(String::as_str).collect();
        match case(&words, &dir) {
            Ok((args, says)) => cases.push(([command.clone(), args].concat(), says)),
            Err(why) => skipped.push(format!("{}: {why}", command.join(" "))),
        }
    }
    for (args, says) in &cases {
        let (code, err) = on_full_disk(args, *says);
        match says {
            Says::Stdout => {
                assert_eq!(code, Some(1), "{args:?}: {err}");
                let lines: Vec<&str> = err.lines().collect();
                assert_eq!(
                    lines.last().copied(),
                    Some("error: cannot write to standard output: No space left on device (os error 28)"),
                    "{args:?}: {err}"
                );
                assert!(
                    !lines
                        .iter()
                        .any(|l| l.starts_with("error:") && l != lines.last().unwrap()),
                    "{args:?}: one error line: {err}"
                );
            }
            Says::Stderr => assert_eq!(code, Some(1), "{args:?}"),
        }
        assert!(!err.contains("panicked"), "{args:?}: {err}");
        // Standard error on /dev/full as well: nobody to tell, but no panic.
        let (code, out) = on_full_disk(args, Says::Stderr);
        assert!(
            matches!(code, Some(0 | 1)),
            "{args:?}: exit {code:?}: {out}"
        );
        run += 1;
    }
    eprintln!(
        "ran {run} commands on /dev/full; not run here:\n  {}",
        skipped.join("\n  ")
    );
    assert!(
        !skipped.iter().any(|s| s.ends_with("not listed")),
        "commands with no arguments here: {skipped:?}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// No file of the program prints with the standard macros, which panic when the write
/// fails: the console path (`metamer::output::console`, the command line's `outln!` and
/// `errln!`) is the one way. Test code (after `#[cfg(test)]`, and test-only files) may.
#[test]
fn no_source_prints_around_the_console() {
    let mut found = Vec::new();
    let roots = [
        root().join("src"),
        root().join("drivers/src"),
        root().join("protocols"),
    ];
    let test_only = test_only_modules(&roots);
    assert!(
        test_only.contains(&root().join("src/validation/coverage.rs")),
        "the test-only module list is read from the declarations: {test_only:?}"
    );
    let mut stack = roots.to_vec();
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
                continue;
            }
            let name = path.file_name().unwrap().to_string_lossy().to_string();
            if !name.ends_with(".rs") || name.contains("tests") || test_only.contains(&path) {
                continue;
            }
            let source = std::fs::read_to_string(&path).unwrap();
            let code = source.split("#[cfg(test)]").next().unwrap();
            for (i, line) in code.lines().enumerate() {
                let l = line.trim_start();
                if l.starts_with("//") {
                    continue;
                }
                if ["println!(", "eprintln!(", "print!(", "eprint!("]
                    .iter()
                    .any(|m| l.contains(m) && !l.contains(&format!("_{m}")))
                {
                    found.push(format!("{}:{}: {l}", path.display(), i + 1));
                }
            }
        }
    }
    assert!(
        found.is_empty(),
        "printing that panics on a full disk:\n{}",
        found.join("\n")
    );
}

/// The files of modules declared right after `#[cfg(test)]` (`mod name;`), which are
/// compiled only for tests: `name.rs` beside the declaring file, or in the folder named
/// after it when the declaring file is not a `mod.rs`/`lib.rs`.
fn test_only_modules(roots: &[std::path::PathBuf]) -> Vec<std::path::PathBuf> {
    let mut modules = Vec::new();
    let mut stack = roots.to_vec();
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
                continue;
            }
            if path.extension().is_none_or(|e| e != "rs") {
                continue;
            }
            let source = std::fs::read_to_string(&path).unwrap();
            let lines: Vec<&str> = source.lines().map(str::trim).collect();
            for pair in lines.windows(2) {
                if pair[0] != "#[cfg(test)]" {
                    continue;
                }
                let decl = pair[1]
                    .trim_start_matches("pub(crate) ")
                    .trim_start_matches("pub ");
                let Some(name) = decl.strip_prefix("mod ").and_then(|d| d.strip_suffix(';')) else {
                    continue;
                };
                let stem = path.file_stem().unwrap().to_string_lossy();
                let folder = if stem == "mod" || stem == "lib" || stem == "main" {
                    path.parent().unwrap().to_path_buf()
                } else {
                    path.with_extension("")
                };
                modules.push(folder.join(format!("{name}.rs")));
                modules.push(folder.join(name).join("mod.rs"));
            }
        }
    }
    modules
}

/// A result file written onto a disk that fills up: the write fails part way (here the
/// process's file-size limit, `ulimit -f`, with SIGXFSZ ignored, stands in for a full disk
/// and makes the write fail with EFBIG), the command says which file on one line and exits
/// 1, and the profile saved before is still there byte for byte, with no temporary file
/// left beside it.
#[test]
fn a_result_file_that_cannot_be_written_leaves_the_saved_one_whole() {
    let dir = fresh_dir("fsize");
    let profile = dir.join("profile.json");
    let ti3 = "tests/data/dispread_analytic.ti3";
    let fit = |extra: &[&str]| {
        metamer_command()
            .args([
                "fit",
                "--measurements",
                ti3,
                "-o",
                profile.to_str().unwrap(),
            ])
            .args(extra)
            .current_dir(root())
            .output()
            .unwrap()
    };
    let o = fit(&["--model", "plcc"]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let saved = std::fs::read(&profile).unwrap();
    assert!(
        saved.len() > 2048,
        "the profile is larger than the limit below"
    );
    // 1 KiB (bash counts `ulimit -f` in 1024-byte blocks): less than any profile.
    let script = format!(
        "trap '' XFSZ; ulimit -f 1; exec '{}' fit --measurements {ti3} --model lut --force -o '{}'",
        env!("CARGO_BIN_EXE_metamer"),
        profile.display()
    );
    let o = Command::new("bash")
        .args(["-c", &script])
        .current_dir(root())
        .output()
        .unwrap();
    let err = text(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.lines()
            .any(|l| l.starts_with("error: ") && l.contains("profile.json")),
        "{err}"
    );
    assert!(!err.contains("panicked"), "{err}");
    assert_eq!(
        std::fs::read(&profile).unwrap(),
        saved,
        "the saved profile is unchanged"
    );
    let left: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(
        left,
        vec![std::ffi::OsString::from("profile.json")],
        "{left:?}"
    );
    std::fs::remove_dir_all(&dir).ok();
}
