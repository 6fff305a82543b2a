//! The per-patch readings the stages pass on (`box/spots.csv`, `simulation/spots.csv`,
//! `display-spots/spots.csv`) are the validation's: one type, [`PatchReading`], one
//! reader and one writer, in [`crate::validation::readings`], re-exported here where the
//! stages have always found them.

pub use crate::validation::readings::{
    read_readings, write_readings, PatchReading, ReadingSet, ReadingsError,
};
