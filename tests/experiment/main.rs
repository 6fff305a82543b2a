//! `metamer experiment` and `metamer lab` end to end (the slowest tests), and the
//! validation report in a real browser. One module per topic; tests/README.md lists them.

#[path = "../support/mod.rs"]
mod support;

mod experiment;
mod experiment_external;
mod experiment_image;
mod experiment_kill;
mod lab;
mod lab_study;
mod report_browser;
