//! The validation box and the data files it names, compiled into the program so that
//! `metamer lab` and `metamer render` work from any directory.

use super::{build, PathError, Scene};

/// The canonical validation box (Lambertian light), as in `data/scenes/validation-box.json`.
pub const VALIDATION_BOX: &str = include_str!("../../../data/scenes/validation-box.json");

/// The spectral files the built-in scene names, as it names them.
pub const DATA_FILES: [&str; 3] = [
    "../paper_white_reflectance.csv",
    "../colorchecker_babelcolor_average.csv",
    "../illuminant_led_rgb1.csv",
];

/// The text of a built-in data file by the name a built-in scene gives it.
pub fn data_file(name: &str) -> Option<&'static str> {
    Some(match name {
        "../paper_white_reflectance.csv" => {
            include_str!("../../../data/paper_white_reflectance.csv")
        }
        "../colorchecker_babelcolor_average.csv" => {
            include_str!("../../../data/colorchecker_babelcolor_average.csv")
        }
        "../illuminant_led_rgb1.csv" => include_str!("../../../data/illuminant_led_rgb1.csv"),
        _ => return None,
    })
}

/// The built-in validation box, validated.
pub fn validation_box() -> Result<Scene, PathError> {
    build::builtin_scene(VALIDATION_BOX)
}
