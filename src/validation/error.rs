//! What can go wrong comparing readings and writing the report.

/// What can be wrong with the inputs of a comparison.
#[derive(Debug, thiserror::Error)]
pub enum ValidationError {
    #[error(
        "the two sets of readings differ in length: {reference} reference vs {test} test readings"
    )]
    LengthMismatch { reference: usize, test: usize },
    #[error("{} and {} have no patch in common to compare", reference.display(), test.display())]
    NoCommonPatches {
        reference: std::path::PathBuf,
        test: std::path::PathBuf,
    },
    #[error("reference white {white:?} must have positive X, Y and Z")]
    BadWhite { white: [f64; 3] },
    #[error("cannot write {file}: {source}")]
    Write {
        file: std::path::PathBuf,
        #[source]
        source: std::io::Error,
    },
    // Not transparent: the command line looks for the OutputError among the sources.
    #[error("{0}")]
    Output(#[from] crate::output::OutputError),
    #[error("cannot draw the chart {file}: {message}")]
    Chart {
        file: std::path::PathBuf,
        message: String,
    },
    #[error(transparent)]
    Readings(#[from] super::readings::ReadingsError),
    #[error(transparent)]
    Incomparable(#[from] super::plausible::Incomparable),
    /// The white the caller gave is no white for these readings (the command line words
    /// it as a refusal of its option).
    #[error("{0}")]
    GivenWhite(String),
    /// Under [`super::job::Coverage::Same`], two sides read different patches.
    #[error("readings: the {first} readings are of patches {first_patches:?} but the {second} readings of {second_patches:?}")]
    DifferentPatches {
        first: &'static str,
        first_patches: Vec<usize>,
        second: &'static str,
        second_patches: Vec<usize>,
    },
    #[error("writing JSON: {0}")]
    Json(#[source] serde_json::Error),
}
