//! `metamer reproduce` (placeholder until its issue's helper lands it).

use super::{CliError, CliResult};

#[derive(clap::Args)]
pub struct Args {}

pub fn run(_args: Args) -> CliResult {
    Err(CliError::Usage("'reproduce' is being built".into()))
}
