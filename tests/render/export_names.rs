//! Names and files an export must not let through: a scene or surface name built to break
//! the renderers' grammars (pbrt-v4's `#` comments end at `\n` or `\r`; an XML comment at
//! `-->`) leaves the pbrt-v4 file the same tokens and the Mitsuba 3 file well-formed XML,
//! and `--force` never replaces a file the scene reads, nor the scene file.

use std::path::{Path, PathBuf};
use std::process::Command;

use metamer::render::Scene;

use crate::export_pbrt::tokenize;
use crate::support::{fresh_dir, metamer, scenes_dir, stderr};

/// A name written to break a renderer's grammar: line ends that end a comment (pbrt-v4
/// ends one at `\r` too), a pbrt directive and comment start, an XML comment's end and
/// start, quotes, an ampersand, angle brackets, a backslash and a last hyphen.
const HOSTILE: &str = "box\r WorldEnd\n# -->\"q\" 'a' & <scene> <!-- \\ \u{2028} \u{1b}[1m end-";

/// The shipped validation box with its files' paths made absolute and every name (the
/// scene's and its surfaces') `name`, written into `dir`.
fn named_scene(dir: &Path, file: &str, name: &str) -> PathBuf {
    use serde_json::Value;
    fn absolute(v: &mut Value, base: &Path) {
        match v {
            Value::Object(m) => {
                for (k, x) in m.iter_mut() {
                    match x {
                        Value::String(s) if k == "file" => {
                            *s = base.join(&*s).to_str().unwrap().to_string()
                        }
                        _ => absolute(x, base),
                    }
                }
            }
            Value::Array(a) => a.iter_mut().for_each(|x| absolute(x, base)),
            _ => {}
        }
    }
    let text = std::fs::read_to_string(scenes_dir().join("validation-box.json")).unwrap();
    let mut v: Value = serde_json::from_str(&text).unwrap();
    absolute(&mut v, scenes_dir());
    v["name"] = Value::String(name.into());
    for s in v["surfaces"].as_array_mut().unwrap() {
        s["name"] = Value::String(name.into());
    }
    let p = dir.join(file);
    std::fs::write(&p, v.to_string()).unwrap();
    p
}

/// `metamer export --to pbrt-v4` on `scene` into `out`; its scene file's text.
fn export_pbrt(scene: &Path, out: &Path) -> String {
    let o = metamer(&[
        "export",
        scene.to_str().unwrap(),
        "--to",
        "pbrt-v4",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    std::fs::read_to_string(out.join("scene.pbrt")).unwrap()
}

/// Names go into pbrt-v4's comments only, so a hostile name leaves the file's tokens those
/// of the same scene with a plain name: nothing ends its comment early.
#[test]
fn a_hostile_name_changes_no_pbrt_token() {
    let dir = fresh_dir("export-pbrt-names");
    let plain = export_pbrt(
        &named_scene(&dir, "plain.json", "plain"),
        &dir.join("plain"),
    );
    let hostile = export_pbrt(
        &named_scene(&dir, "hostile.json", HOSTILE),
        &dir.join("hostile"),
    );
    assert_eq!(tokenize(&hostile), tokenize(&plain));
    // The name is there, on its line, as the escapes show it.
    assert!(
        hostile.starts_with("# box\\r WorldEnd\\n# -->\"q\" 'a' & <scene> <!-- \\\\ \\u{2028} \\u{1b}[1m end-: written by metamer export"),
        "{:?}",
        hostile.lines().next()
    );
    assert_eq!(hostile.lines().count(), plain.lines().count());
    std::fs::remove_dir_all(&dir).unwrap();
}

/// `--force` replaces what the output directory holds, but never a file the scene reads
/// nor the scene file itself; the refusal comes before anything is written.
#[test]
fn a_forced_export_never_replaces_what_the_scene_reads() {
    let dir = fresh_dir("export-force-inputs");
    // A scene that reads its walls' reflectance from README.md, which the export writes.
    let source = scenes_dir().join("../paper_white_reflectance.csv");
    let table = std::fs::read_to_string(&source).unwrap();
    std::fs::write(dir.join("README.md"), &table).unwrap();
    let scene = named_scene(&dir, "box.json", "box");
    let text = std::fs::read_to_string(&scene)
        .unwrap()
        .replace(source.to_str().unwrap(), "README.md");
    std::fs::write(&scene, &text).unwrap();
    let listing = |d: &Path| {
        let mut v: Vec<String> = std::fs::read_dir(d)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    };
    for to in ["mitsuba3", "pbrt-v4"] {
        let o = metamer(&[
            "export",
            scene.to_str().unwrap(),
            "--to",
            to,
            "-o",
            dir.to_str().unwrap(),
            "--force",
        ]);
        assert_eq!(o.status.code(), Some(1), "{to}: {}", stderr(&o));
        let e = stderr(&o);
        assert!(
            e.contains(&format!(
                "refusing to write {}: it is the input",
                dir.join("README.md").display()
            )),
            "{to}: {e}"
        );
        assert_eq!(
            std::fs::read_to_string(dir.join("README.md")).unwrap(),
            table
        );
        assert_eq!(listing(&dir), ["README.md", "box.json"], "{to}");
    }
    // The scene file itself, named as the export's scene file.
    let pbrt_named = dir.join("scene.pbrt");
    std::fs::rename(&scene, &pbrt_named).unwrap();
    let o = metamer(&[
        "export",
        pbrt_named.to_str().unwrap(),
        "--to",
        "pbrt-v4",
        "-o",
        dir.to_str().unwrap(),
        "--force",
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    assert!(stderr(&o).contains("it is the input"), "{}", stderr(&o));
    assert_eq!(std::fs::read_to_string(&pbrt_named).unwrap(), text);
    assert_eq!(listing(&dir), ["README.md", "scene.pbrt"]);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A hostile scene and surface name leaves the Mitsuba file well-formed XML (read by
/// Python's expat, which refuses `--` in a comment) with one comment before the `scene`
/// element and one `shape` per surface and tile, and Mitsuba loads it.
#[test]
fn a_hostile_name_leaves_the_mitsuba_xml_well_formed() {
    let dir = fresh_dir("export-mitsuba-names");
    let scene_file = named_scene(&dir, "hostile.json", HOSTILE);
    let out = dir.join("mitsuba");
    let o = metamer(&[
        "export",
        scene_file.to_str().unwrap(),
        "--to",
        "mitsuba3",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let scene = Scene::load(&scene_file).unwrap();
    let shapes = scene.surfaces.len()
        + scene
            .emitters
            .iter()
            .map(|e| e.rows * e.cols)
            .sum::<usize>();
    let script = r#"
import sys
import xml.dom.minidom as md
doc = md.parse(sys.argv[1])
kinds = [n.nodeType for n in doc.childNodes]
assert kinds == [md.Node.COMMENT_NODE, md.Node.ELEMENT_NODE], kinds
root = doc.childNodes[1]
assert root.tagName == "scene", root.tagName
print(len([n for n in root.childNodes if n.nodeType == md.Node.ELEMENT_NODE and n.tagName == "shape"]))
print(doc.childNodes[0].data.split(": written by")[0])
try:
    import mitsuba as mi
except ImportError:
    print("no mitsuba")
    sys.exit(0)
mi.set_variant("scalar_spectral")
mi.load_file(sys.argv[1], spp=1, width=8, height=8)
print("loaded")
"#;
    let o = Command::new("python3")
        .args(["-c", script])
        .arg(out.join("scene.xml"))
        .output()
        .unwrap();
    let (text, err) = (
        String::from_utf8_lossy(&o.stdout).to_string(),
        String::from_utf8_lossy(&o.stderr),
    );
    assert!(o.status.success(), "{err}");
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines[0], shapes.to_string(), "{text}");
    // The name as the escapes write it, every `--` broken by a space.
    assert_eq!(
        lines[1], r#" box\r WorldEnd\n# - ->"q" 'a' & <scene> <!- - \\ \u{2028} \u{1b}[1m end- "#,
        "{text}"
    );
    if lines[2] == "no mitsuba" {
        assert!(
            std::env::var("METAMER_ORACLES").as_deref() != Ok("required"),
            "METAMER_ORACLES=required but mitsuba is not installed"
        );
        eprintln!(
            "skipped loading in Mitsuba: Mitsuba 3 is not installed (pip install mitsuba==3.9.1)"
        );
    } else {
        assert_eq!(lines[2], "loaded", "{text}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
