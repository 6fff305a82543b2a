//! Each display command's whole job as one library call: a request the caller fills in,
//! events for what is worth saying while it runs, and a report of what it made. The
//! commands in `src/cli/` only parse their flags into the request and print.

pub mod budget;
pub mod fit;
pub mod reproduce;
pub mod verify;
