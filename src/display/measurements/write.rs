//! Writing `.ti3` files in the layout ArgyllCMS dispread writes (see the parent module for
//! the facts about the format): RGB in 0–100, XYZ normalised to the white's Y = 100 and the
//! white's absolute XYZ in `LUMINANCE_XYZ_CDM2`.

use std::path::Path;

use crate::output::OutputPolicy;

use crate::color::Xyz;
use crate::display::model::Sample;

/// The white used to normalise a `.ti3`: the brightest patch driven at full on all channels,
/// or the brightest patch when none is.
fn white_of(patches: &[Sample]) -> Option<Xyz> {
    let brightest = |it: &mut dyn Iterator<Item = &Sample>| {
        it.max_by(|a, b| a.xyz[1].total_cmp(&b.xyz[1]))
            .map(|p| p.xyz)
    };
    brightest(&mut patches.iter().filter(|p| p.rgb == [1.0, 1.0, 1.0]))
        .or_else(|| brightest(&mut patches.iter()))
}

/// `ctime()`-style UTC date, as dispread writes in CREATED.
fn created_now() -> String {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map(|d| d.as_secs() as i64)
        .unwrap_or(0);
    ctime_utc(secs)
}

/// `ctime()` layout ("Thu Jan  1 00:00:00 1970") of seconds since the Unix epoch, UTC.
fn ctime_utc(secs: i64) -> String {
    let (days, rem) = (secs.div_euclid(86_400), secs.rem_euclid(86_400));
    let (year, month, day) = crate::calendar::civil_from_days(days);
    const WEEKDAYS: [&str; 7] = ["Thu", "Fri", "Sat", "Sun", "Mon", "Tue", "Wed"];
    const MONTHS: [&str; 12] = [
        "Jan", "Feb", "Mar", "Apr", "May", "Jun", "Jul", "Aug", "Sep", "Oct", "Nov", "Dec",
    ];
    format!(
        "{} {} {:2} {:02}:{:02}:{:02} {}",
        WEEKDAYS[days.rem_euclid(7) as usize],
        MONTHS[(month - 1) as usize],
        day,
        rem / 3600,
        rem % 3600 / 60,
        rem % 60,
        year
    )
}

/// Writes patches as ArgyllCMS dispread does: RGB in 0–100, XYZ normalised to the white's
/// Y = 100 with the white's absolute XYZ in `LUMINANCE_XYZ_CDM2`. `description` goes into the
/// DESCRIPTOR keyword.
pub fn write_ti3(
    path: &Path,
    patches: &[Sample],
    description: &str,
    out: &OutputPolicy,
) -> std::io::Result<()> {
    let white = white_of(patches).filter(|w| w[1] > 0.0).ok_or_else(|| {
        std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            "no patch with positive luminance to normalise the .ti3 to",
        )
    })?;
    let k = 100.0 / white[1];
    let mut s = String::new();
    s.push_str("CTI3   \n\n");
    s.push_str(&format!(
        "DESCRIPTOR \"{}\"\n\n",
        description.replace('"', "'")
    ));
    s.push_str("ORIGINATOR \"metamer\"\n\n");
    s.push_str(&format!("CREATED \"{}\"\n", created_now()));
    for (name, value) in [
        ("DEVICE_CLASS", "DISPLAY".to_string()),
        ("COLOR_REP", "RGB_XYZ".to_string()),
        (
            "LUMINANCE_XYZ_CDM2",
            format!("{:.6} {:.6} {:.6}", white[0], white[1], white[2]),
        ),
        ("NORMALIZED_TO_Y_100", "YES".to_string()),
    ] {
        s.push_str(&format!("KEYWORD \"{name}\"\n{name} \"{value}\"\n"));
    }
    s.push_str("\nNUMBER_OF_FIELDS 7\nBEGIN_DATA_FORMAT\n");
    s.push_str("SAMPLE_ID RGB_R RGB_G RGB_B XYZ_X XYZ_Y XYZ_Z \nEND_DATA_FORMAT\n\n");
    s.push_str(&format!("NUMBER_OF_SETS {}\nBEGIN_DATA\n", patches.len()));
    for (i, p) in patches.iter().enumerate() {
        s.push_str(&format!(
            "{} {:.6} {:.6} {:.6} {:.6} {:.6} {:.6} \n",
            i + 1,
            p.rgb[0] * 100.0,
            p.rgb[1] * 100.0,
            p.rgb[2] * 100.0,
            p.xyz[0] * k,
            p.xyz[1] * k,
            p.xyz[2] * k
        ));
    }
    s.push_str("END_DATA\n");
    out.write(path, s.as_bytes()).map_err(std::io::Error::other)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::display::measurements::read_measurements;

    #[test]
    fn created_date_has_ctime_layout() {
        assert_eq!(ctime_utc(0), "Thu Jan  1 00:00:00 1970");
        // 1.7e9 s after the epoch: Tuesday 14 November 2023, 22:13:20 UTC
        assert_eq!(ctime_utc(1_700_000_000), "Tue Nov 14 22:13:20 2023");
        assert_eq!(ctime_utc(951_782_400), "Tue Feb 29 00:00:00 2000");
    }

    #[test]
    fn write_then_read_round_trips_absolute_values() {
        let patches = vec![
            Sample {
                rgb: [0.0, 0.0, 0.0],
                xyz: Xyz::new(0.2, 0.21, 0.3),
            },
            Sample {
                rgb: [1.0, 1.0, 1.0],
                xyz: Xyz::new(152.0, 160.0, 174.2),
            },
            Sample {
                rgb: [128.0 / 255.0, 0.25, 1.0],
                xyz: Xyz::new(30.5, 20.25, 90.125),
            },
        ];
        let dir = std::env::temp_dir().join(format!("metamer-ti3-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("m.ti3");
        write_ti3(
            &path,
            &patches,
            "test \"patches\"",
            &crate::output::OutputPolicy::new(true),
        )
        .unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(text.contains("LUMINANCE_XYZ_CDM2 \"152.000000 160.000000 174.200000\""));
        assert!(text.contains("2 100.000000 100.000000 100.000000 95.000000 100.000000 108.875000"));
        let back = read_measurements(&path).unwrap();
        for (a, b) in back.iter().zip(&patches) {
            for c in 0..3 {
                assert!((a.rgb[c] - b.rgb[c]).abs() < 1e-8);
                assert!((a.xyz[c] - b.xyz[c]).abs() < 1e-5 * b.xyz[c].max(1.0));
            }
        }
        std::fs::remove_dir_all(&dir).ok();
    }
}
