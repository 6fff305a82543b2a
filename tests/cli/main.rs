//! The command line end to end: each command's output against independent references, its
//! files, and the errors a user sees. One module per topic; tests/README.md lists them.

#[path = "../support/mod.rs"]
mod support;

mod budget_cli;
mod characterize_cli;
mod color_cli;
mod devices_cli;
mod docs_commands;
mod full_disk_cli;
mod i1pro_spot_cli;
mod light_cli;
mod oracle_probe;
mod output_policy_cli;
mod simulate_cli;
mod spot_cli;
mod validate_cli;
mod verify_cli;
