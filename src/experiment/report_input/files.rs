//! Reading a section's file, and the note when it cannot be used.

use std::path::Path;

/// A file a section needs could not be used: which, and why.
pub(crate) fn unusable(what: &str, file: &Path, why: impl std::fmt::Display) -> String {
    format!("no {what} section: {} {why}", file.display())
}

/// Reads a JSON file, or says why not (for the section's note).
pub(crate) fn read_json(file: &Path) -> Result<serde_json::Value, String> {
    let text = std::fs::read_to_string(file).map_err(|e| {
        if e.kind() == std::io::ErrorKind::NotFound {
            "does not exist".to_string()
        } else {
            format!("cannot be read: {e}")
        }
    })?;
    serde_json::from_str(&text).map_err(|e| format!("is not JSON: {e}"))
}

#[cfg(test)]
pub(crate) mod testdir {
    use std::path::{Path, PathBuf};

    /// A fresh directory for one test.
    pub fn fresh(name: &str) -> PathBuf {
        let d =
            std::env::temp_dir().join(format!("metamer-sections-{name}-{}", std::process::id()));
        std::fs::remove_dir_all(&d).ok();
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    pub fn write(dir: &Path, name: &str, text: &str) {
        std::fs::write(dir.join(name), text).unwrap();
    }
}
