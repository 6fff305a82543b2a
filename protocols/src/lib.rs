//! Sans-I/O codecs for colour measuring instruments: commands encode to bytes, replies parse
//! from bytes into typed values. No I/O and no clocks here, so every codec is unit-tested on
//! byte strings and shared by real, replayed and emulated devices alike.

pub mod cs100a;
pub mod i1pro;
pub mod transcript;
