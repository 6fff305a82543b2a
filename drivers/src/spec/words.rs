//! The words of the instrument spec grammar that are not model names, and the connection
//! texts built from them. A leaf: the links and the models' open functions describe their
//! connections with these, and the spec parser, which depends on the registry (and so on
//! those open functions), reads them, so they cannot live in the parser's file.

/// `replay:FILE.jsonl`: a transcript played through the real driver.
pub const REPLAY_PREFIX: &str = "replay";
/// `sim:MODEL[?OPTIONS]`: the model's emulator.
pub const SIM_PREFIX: &str = "sim";

/// The connection an emulated `model` reports (`sim:cs100a`), which is also its spec.
pub fn sim_connection(model: &str) -> String {
    format!("{SIM_PREFIX}:{model}")
}

/// The connection a replayed transcript reports (`replay:FILE`), which is also its spec.
pub fn replay_connection(file: &str) -> String {
    format!("{REPLAY_PREFIX}:{file}")
}
