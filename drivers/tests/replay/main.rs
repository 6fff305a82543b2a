//! The drivers against recorded and emulated instruments: every transcript under
//! `protocols/MODEL/transcripts` replayed through the real driver (one generated test per
//! file, see `build.rs`), and the emulated CS-100A on a pseudo-terminal.

mod cs100a_pty;
mod cs100a_transcripts;
mod i1pro_transcripts;
