//! Errors of links and drivers, each with the context a user needs to act on it.

/// What went wrong talking to an instrument.
#[derive(Debug, thiserror::Error)]
pub enum DriverError {
    /// The instrument spec string is not understood.
    #[error("unknown instrument '{spec}': expected cs100a:PORT, replay:FILE.jsonl or sim:cs100a")]
    UnknownSpec { spec: String },
}
