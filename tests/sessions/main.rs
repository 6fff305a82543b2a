//! Measuring sessions: the session engine, the operator's prompts, resume after a kill,
//! `measure-box` on the simulated box, a real terminal (tmux) and a real X server (Xvfb).
//! One module per topic; tests/README.md lists them.

#[path = "../support/mod.rs"]
mod support;

mod cs100a_sim;
mod i1pro_resume;
mod measure_box;
mod measure_box_adaptive;
mod operator_session;
mod operator_tmux;
mod session_engine;
mod window_xvfb;
