//! `metamer characterize` (placeholder until its issue's helper lands it).

use super::{CliError, CliResult};

#[derive(clap::Args)]
pub struct Args {}

pub fn run(_args: Args) -> CliResult {
    Err(CliError::Usage("'characterize' is being built".into()))
}
