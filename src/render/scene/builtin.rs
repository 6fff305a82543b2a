//! The validation boxes and the data files they name, compiled into the program so that
//! `metamer lab` and `metamer render` work from any directory.

/// The canonical validation box, lit by the `ips-lcd` display's white as the paper's box
/// was lit by an LCD, as in `data/scenes/validation-box.json`.
pub const VALIDATION_BOX: &str = include_str!("../../../data/scenes/validation-box.json");

/// The same box lit by CIE LED-RGB1, as in `data/scenes/validation-box-led-rgb1.json`.
pub const VALIDATION_BOX_LED_RGB1: &str =
    include_str!("../../../data/scenes/validation-box-led-rgb1.json");

/// The spectral files the built-in scenes name, as they name them.
pub const DATA_FILES: [&str; 4] = [
    "../paper_white_reflectance.csv",
    "../colorchecker_babelcolor_average.csv",
    "../display_white_ips_lcd.csv",
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
        "../display_white_ips_lcd.csv" => {
            include_str!("../../../data/display_white_ips_lcd.csv")
        }
        "../illuminant_led_rgb1.csv" => include_str!("../../../data/illuminant_led_rgb1.csv"),
        _ => return None,
    })
}

/// The built-in boxes' names, the first the default.
pub const NAMES: [&str; 2] = ["validation-box", "validation-box-led-rgb1"];

/// The text of a built-in box by name (`validation-box`, `validation-box-led-rgb1`; any
/// other name is the default box).
pub fn scene_text(name: &str) -> &'static str {
    match name {
        "validation-box-led-rgb1" => VALIDATION_BOX_LED_RGB1,
        _ => VALIDATION_BOX,
    }
}
