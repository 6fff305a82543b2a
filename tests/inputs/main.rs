//! Malformed input and refused options: each must fail at once with a clear error (many
//! tests assert a bound on the wall-clock time, so this binary holds no heavy test). One
//! module per topic; tests/README.md lists them.

#[path = "../support/mod.rs"]
mod support;

mod experiment_preflight;
mod hardening;
mod hardening_commands;
mod hardening_inputs;
mod hardening_sessions;
mod light_inputs;
mod refusals;
mod render_hardening;
mod scene_format;
