//! Stage reuse: a stage's directory holds `stage.json`, the hashes of what the stage read
//! (upstream files and its own options) and of what it wrote. A stage whose inputs hash as
//! recorded and whose outputs are still there unchanged is not run again; any change
//! upstream changes an input hash downstream, so exactly the stages that depend on it run.
//!
//! A record is trusted only as far as it vouches: it must list every product of the stage
//! (the files later stages read, [`Product`]), a file it lists must be a regular file inside
//! the stage, and the record itself must be a small regular file (read through a bounded
//! reader: one that is a FIFO, a link to `/dev/zero` or a huge sparse file is simply not
//! trusted, and the stage runs again).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

use super::measuring::MeasuringPlan;
use crate::digest::{hex, sha256_file};
use crate::output::{OutputError, OutputPolicy};

/// The record's file name inside a stage directory.
pub const RECORD_FILE: &str = "stage.json";
/// Largest record read: a record is a few kilobytes of hashes.
const MAX_RECORD_BYTES: u64 = 1 << 20;

/// A file a stage writes for later stages (or the command) to read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Product {
    pub file: &'static str,
    /// Written by every run of the stage; otherwise only by some (an image when one is
    /// rendered), and then vouched for when it is there.
    pub always: bool,
}
const RECORD_FORMAT: &str = "metamer-experiment-stage";

/// A stage's record could not be read or written, or an input could not be hashed.
#[derive(Debug, thiserror::Error)]
pub enum CacheError {
    #[error("reading {} to hash it: {source}", file.display())]
    Hash {
        file: PathBuf,
        source: std::io::Error,
    },
    #[error("{0}")]
    Output(#[from] OutputError),
    #[error("writing {}: {source}", file.display())]
    Write {
        file: PathBuf,
        source: std::io::Error,
    },
}

/// What a finished stage read and wrote.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StageRecord {
    pub format: String,
    pub stage: String,
    /// Input name → SHA-256 (hex).
    pub inputs: BTreeMap<String, String>,
    /// Output file, relative to the stage directory → SHA-256 (hex).
    pub outputs: BTreeMap<String, String>,
    /// Wall time of the run that produced the outputs.
    pub seconds: f64,
    /// The measuring plan of the run that produced the outputs. Not an input: the options
    /// it stands for are, so a stage measured by the plan and one measured by the same
    /// options chosen one by one are the same stage.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub measuring: Option<MeasuringPlan>,
}

/// SHA-256 of a file's bytes. Only a regular file (or a link to one) is hashed: a FIFO
/// would wait for a writer and a device never ends.
pub fn hash_file(path: &Path) -> Result<String, CacheError> {
    crate::output::owned_file(path)?;
    sha256_file(path).map_err(|source| CacheError::Hash {
        file: path.to_path_buf(),
        source,
    })
}

/// The bytes of the record at `path` when it is a regular file of at most
/// [`MAX_RECORD_BYTES`], else None. Opened without following a link and without waiting
/// (a FIFO's open would wait for a writer), then checked on the open file.
fn read_record(path: &Path) -> Option<Vec<u8>> {
    use std::io::Read;
    use std::os::unix::fs::OpenOptionsExt;
    let file = std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NONBLOCK | libc::O_NOFOLLOW)
        .open(path)
        .ok()?;
    if !file.metadata().ok()?.is_file() {
        return None;
    }
    let mut bytes = Vec::new();
    file.take(MAX_RECORD_BYTES + 1)
        .read_to_end(&mut bytes)
        .ok()?;
    (bytes.len() as u64 <= MAX_RECORD_BYTES).then_some(bytes)
}

/// SHA-256 of a value's canonical JSON (object keys sorted): options hash the same whatever
/// order their fields are written in.
pub fn hash_value<T: Serialize>(value: &T) -> String {
    let canonical = serde_json::to_value(value)
        .map(|v| v.to_string())
        .unwrap_or_default();
    hex(&Sha256::digest(canonical.as_bytes()))
}

/// The inputs of a stage, by name.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Inputs(pub BTreeMap<String, String>);

impl Inputs {
    pub fn new() -> Inputs {
        Inputs::default()
    }

    /// Adds a file's content hash under `name`.
    pub fn file(mut self, name: &str, path: &Path) -> Result<Inputs, CacheError> {
        self.0.insert(name.to_string(), hash_file(path)?);
        Ok(self)
    }

    /// Adds the hash of a value (options) under `name`.
    pub fn value<T: Serialize>(mut self, name: &str, v: &T) -> Inputs {
        self.0.insert(name.to_string(), hash_value(v));
        self
    }
}

/// One stage's directory.
#[derive(Clone, Debug)]
pub struct StageDir {
    pub name: &'static str,
    pub dir: PathBuf,
}

impl StageDir {
    pub fn new(root: &Path, name: &'static str) -> StageDir {
        StageDir {
            name,
            dir: root.join(name),
        }
    }

    pub fn path(&self, file: &str) -> PathBuf {
        self.dir.join(file)
    }

    /// The record, when the stage finished with exactly these inputs, the record vouches
    /// for each of the stage's `products` (every one that is always written, and every
    /// other one that is there), and every output it lists is still there with the
    /// content it had.
    pub fn reusable(&self, inputs: &Inputs, products: &[Product]) -> Option<StageRecord> {
        let bytes = read_record(&self.path(RECORD_FILE))?;
        let record: StageRecord = serde_json::from_slice(&bytes).ok()?;
        if record.format != RECORD_FORMAT || record.stage != self.name || record.inputs != inputs.0
        {
            return None;
        }
        // A record that leaves a product out (`"outputs": {}`) would let an edited file
        // pass as this stage's work.
        let vouched = products.iter().all(|p| {
            record.outputs.contains_key(p.file)
                || (!p.always && std::fs::symlink_metadata(self.path(p.file)).is_err())
        });
        if !vouched {
            return None;
        }
        let intact = record.outputs.iter().all(|(file, hash)| {
            self.own_file(file) && hash_file(&self.path(file)).ok().as_ref() == Some(hash)
        });
        intact.then_some(record)
    }

    /// Whether `name` is a regular file inside the stage directory, as every output a stage
    /// writes is. A record edited to name `/dev/zero`, `../elsewhere` or a link would
    /// otherwise be hashed wherever it points (a device, for ever).
    fn own_file(&self, name: &str) -> bool {
        let plain = !name.is_empty()
            && Path::new(name)
                .components()
                .all(|c| matches!(c, std::path::Component::Normal(_)));
        plain && std::fs::symlink_metadata(self.path(name)).is_ok_and(|m| m.file_type().is_file())
    }

    /// Forgets an earlier finish, so a stage that is re-run and fails half-way is never
    /// mistaken for finished.
    pub fn invalidate(&self) -> Result<(), CacheError> {
        match std::fs::remove_file(self.path(RECORD_FILE)) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => Err(CacheError::Write {
                file: self.path(RECORD_FILE),
                source: e,
            }),
            _ => Ok(()),
        }
    }

    /// Records the stage as finished: the inputs it ran with and the hashes of `outputs`
    /// (relative to the stage directory). Written to a temporary file and renamed, so a
    /// crash leaves either the old state (re-run) or the complete record.
    pub fn finish<S: AsRef<str>>(
        &self,
        inputs: &Inputs,
        outputs: &[S],
        seconds: f64,
        measuring: MeasuringPlan,
    ) -> Result<StageRecord, CacheError> {
        let mut hashes = BTreeMap::new();
        for f in outputs {
            let f = f.as_ref();
            hashes.insert(f.to_string(), hash_file(&self.path(f))?);
        }
        let record = StageRecord {
            format: RECORD_FORMAT.into(),
            stage: self.name.into(),
            inputs: inputs.0.clone(),
            outputs: hashes,
            seconds,
            measuring: Some(measuring),
        };
        let text = serde_json::to_string_pretty(&record).unwrap_or_default();
        write_atomic(&self.path(RECORD_FILE), text.as_bytes())?;
        Ok(record)
    }
}

/// Writes `bytes` to `path` by the project's output policy (a temporary sibling, synced and
/// renamed over the target), creating the stage directory first. A stage's directory is
/// its own, so earlier files in it are replaced.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), CacheError> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|source| CacheError::Write {
            file: path.to_path_buf(),
            source,
        })?;
    }
    Ok(OutputPolicy::new(true).write(path, bytes)?)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("metamer-cache-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&d);
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    #[test]
    fn known_digest() {
        // FIPS 180-2 example: SHA-256("abc").
        let d = scratch("digest");
        std::fs::write(d.join("abc"), "abc").unwrap();
        assert_eq!(
            hash_file(&d.join("abc")).unwrap(),
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
        );
    }

    #[test]
    fn reused_only_with_same_inputs_and_intact_outputs() {
        let root = scratch("reuse");
        let s = StageDir::new(&root, "simulation");
        std::fs::create_dir_all(&s.dir).unwrap();
        std::fs::write(root.join("scene.json"), "{}").unwrap();
        std::fs::write(s.path("spots.csv"), "1,2,3").unwrap();
        let inputs = Inputs::new()
            .file("scene", &root.join("scene.json"))
            .unwrap()
            .value("target_de", &0.1);
        let products = [Product {
            file: "spots.csv",
            always: true,
        }];
        assert!(s.reusable(&inputs, &products).is_none());
        s.finish(&inputs, &["spots.csv"], 1.0, MeasuringPlan::Paper)
            .unwrap();
        assert!(s.reusable(&inputs, &products).is_some());
        // Another option value: run again.
        assert!(s
            .reusable(&inputs.clone().value("target_de", &0.2), &products)
            .is_none());
        // An upstream file changed: run again.
        std::fs::write(root.join("scene.json"), "{ }").unwrap();
        let changed = Inputs::new()
            .file("scene", &root.join("scene.json"))
            .unwrap()
            .value("target_de", &0.1);
        assert!(s.reusable(&changed, &products).is_none());
        // An output edited or removed: run again.
        std::fs::write(s.path("spots.csv"), "1,2,4").unwrap();
        assert!(s.reusable(&inputs, &products).is_none());
        s.finish(&inputs, &["spots.csv"], 1.0, MeasuringPlan::Paper)
            .unwrap();
        std::fs::remove_file(s.path("spots.csv")).unwrap();
        assert!(s.reusable(&inputs, &products).is_none());
        s.invalidate().unwrap();
        s.invalidate().unwrap();
    }

    /// A record whose outputs name a device, a path outside the stage or a link is not
    /// re-used, and saying so takes no time (hashing /dev/zero would never end).
    #[test]
    fn a_record_naming_files_outside_the_stage_is_not_reused() {
        let root = scratch("outside");
        let s = StageDir::new(&root, "display");
        std::fs::create_dir_all(&s.dir).unwrap();
        std::fs::write(root.join("elsewhere"), "x").unwrap();
        std::fs::write(s.path("profile.json"), "{}").unwrap();
        let inputs = Inputs::new().value("model", &"lut");
        let good = s
            .finish(&inputs, &["profile.json"], 1.0, MeasuringPlan::Paper)
            .unwrap();
        assert!(s.reusable(&inputs, &[]).is_some());
        let x_hash = hash_file(&root.join("elsewhere")).unwrap();
        std::os::unix::fs::symlink(root.join("elsewhere"), s.path("link")).unwrap();
        for (name, hash) in [
            ("/dev/zero", good.outputs["profile.json"].clone()),
            ("../elsewhere", x_hash.clone()),
            ("link", x_hash),
            ("", good.outputs["profile.json"].clone()),
        ] {
            let mut edited = good.clone();
            edited.outputs.insert(name.to_string(), hash);
            let text = serde_json::to_string(&edited).unwrap();
            std::fs::write(s.path(RECORD_FILE), text).unwrap();
            let start = std::time::Instant::now();
            assert!(s.reusable(&inputs, &[]).is_none(), "{name:?} was trusted");
            assert!(start.elapsed() < std::time::Duration::from_secs(1));
        }
    }

    /// A record that leaves a product out vouches for nothing: an edited file that a
    /// later stage reads must not pass as the stage's work. A product only some runs write
    /// is vouched for when it is there.
    #[test]
    fn a_record_that_leaves_a_product_out_is_not_reused() {
        let root = scratch("products");
        let s = StageDir::new(&root, "simulation");
        std::fs::create_dir_all(&s.dir).unwrap();
        std::fs::write(s.path("spots.csv"), "1,2,3").unwrap();
        let inputs = Inputs::new().value("seed", &1);
        let products = [
            Product {
                file: "spots.csv",
                always: true,
            },
            Product {
                file: "image.exr",
                always: false,
            },
        ];
        s.finish(&inputs, &["spots.csv"], 1.0, MeasuringPlan::Paper)
            .unwrap();
        assert!(s.reusable(&inputs, &products).is_some());
        s.finish(&inputs, &[] as &[&str], 1.0, MeasuringPlan::Paper)
            .unwrap();
        assert!(s.reusable(&inputs, &products).is_none(), "outputs {{}}");
        s.finish(&inputs, &["spots.csv"], 1.0, MeasuringPlan::Paper)
            .unwrap();
        std::fs::write(s.path("image.exr"), "an image no record vouches for").unwrap();
        assert!(
            s.reusable(&inputs, &products).is_none(),
            "an unrecorded image"
        );
        s.finish(
            &inputs,
            &["spots.csv", "image.exr"],
            1.0,
            MeasuringPlan::Paper,
        )
        .unwrap();
        assert!(s.reusable(&inputs, &products).is_some());
    }

    /// The record itself is read only when it is a small regular file: a FIFO (whose open
    /// would wait for a writer), a link to /dev/zero and a sparse file of 6 GB are not
    /// trusted, at once and without reading them.
    #[test]
    fn a_record_that_is_no_small_regular_file_is_not_read() {
        let root = scratch("record-kinds");
        let s = StageDir::new(&root, "display");
        std::fs::create_dir_all(&s.dir).unwrap();
        let inputs = Inputs::new().value("model", &"lut");
        s.finish(&inputs, &[] as &[&str], 1.0, MeasuringPlan::Paper)
            .unwrap();
        assert!(s.reusable(&inputs, &[]).is_some());
        let record = s.path(RECORD_FILE);
        let c = std::ffi::CString::new(record.as_os_str().as_encoded_bytes()).unwrap();
        type Make<'a> = (&'a str, Box<dyn Fn() + 'a>);
        let make: [Make; 3] = [
            (
                "a FIFO",
                // SAFETY: a NUL-terminated path and a mode.
                Box::new(|| assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o644) }, 0)),
            ),
            (
                "a link to /dev/zero",
                Box::new(|| std::os::unix::fs::symlink("/dev/zero", &record).unwrap()),
            ),
            (
                "a 6 GB sparse file",
                Box::new(|| {
                    std::fs::File::create(&record)
                        .unwrap()
                        .set_len(6 << 30)
                        .unwrap()
                }),
            ),
        ];
        for (what, make) in make {
            let _ = std::fs::remove_file(&record);
            make();
            let start = std::time::Instant::now();
            assert!(s.reusable(&inputs, &[]).is_none(), "{what} was trusted");
            assert!(
                start.elapsed() < std::time::Duration::from_secs(1),
                "{what}: {:?}",
                start.elapsed()
            );
        }
        let _ = std::fs::remove_file(&record);
    }

    #[test]
    fn option_hash_ignores_field_order() {
        let a: serde_json::Value = serde_json::from_str(r#"{"a":1,"b":[2,3]}"#).unwrap();
        let b: serde_json::Value = serde_json::from_str(r#"{"b":[2,3],"a":1}"#).unwrap();
        assert_eq!(hash_value(&a), hash_value(&b));
        assert_ne!(hash_value(&a), hash_value(&1));
    }
}
