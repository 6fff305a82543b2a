//! The panel model against hand derivations.

use super::*;
use crate::color::Xyz;

fn sub(a: impl Into<[f64; 3]>, b: impl Into<[f64; 3]>) -> [f64; 3] {
    let (a, b) = (a.into(), b.into());
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn close(a: impl Into<[f64; 3]>, b: impl Into<[f64; 3]>, tol: f64) -> bool {
    let (a, b): ([f64; 3], [f64; 3]) = (a.into(), b.into());
    a.iter()
        .zip(b)
        .all(|(x, y)| (x - y).abs() <= tol * y.abs().max(1.0))
}

fn xy(v: impl Into<[f64; 3]>) -> [f64; 2] {
    let v = v.into();
    let s = v[0] + v[1] + v[2];
    [v[0] / s, v[1] / s]
}

#[test]
fn full_white_is_the_preset_white_exactly() {
    // D65 at 100 cd/m²: X = 0.3127/0.3290·100 = 95.04559…, Z = 0.3583/0.3290·100.
    let crt = VirtualPanel::preset(Preset::IdealCrt);
    let w = crt.xyz([255; 3]);
    assert!(
        close(
            w,
            [95.045_592_705_167_17, 100.0, 108.905_775_075_987_84],
            1e-12
        ),
        "{w:?}"
    );
    for p in Preset::ALL {
        let panel = VirtualPanel::preset(p);
        let w = panel.xyz([255; 3]);
        let q = p.params();
        assert!((w[1] - q.white_cd_m2).abs() < 1e-9, "{}", p.name());
        let c = xy(w);
        assert!((c[0] - q.white_xy[0]).abs() < 1e-12 && (c[1] - q.white_xy[1]).abs() < 1e-12);
    }
    // Without crosstalk, white = black + the three primaries' own terms; with it, each
    // primary also lights its neighbours a little, so their sum exceeds white.
    for p in Preset::ALL {
        let panel = VirtualPanel::preset(p);
        let w = panel.xyz([255; 3]);
        let k = panel.xyz([0; 3]);
        let sum = (0..3).fold(k, |acc, c| {
            let mut rgb = [0u8; 3];
            rgb[c] = 255;
            let t = sub(panel.xyz(rgb), k);
            Xyz::new(acc[0] + t[0], acc[1] + t[1], acc[2] + t[2])
        });
        if p == Preset::IdealCrt {
            assert!(close(w, sum, 1e-12), "{w:?} vs {sum:?}");
        } else {
            let excess = sum[1] / w[1] - 1.0;
            assert!((0.001..0.03).contains(&excess), "{}: {excess}", p.name());
        }
    }
}

#[test]
fn ideal_crt_is_plcc_exactly() {
    let crt = VirtualPanel::preset(Preset::IdealCrt);
    let k = crt.xyz([0; 3]);
    // Black: 0.05 cd/m² at (0.300, 0.315).
    assert!(close(
        k,
        [0.05 * 0.300 / 0.315, 0.05, 0.05 * 0.385 / 0.315],
        1e-12
    ));
    let full: Vec<[f64; 3]> = (0..3)
        .map(|c| {
            let mut rgb = [0u8; 3];
            rgb[c] = 255;
            sub(crt.xyz(rgb), k)
        })
        .collect();
    // Primaries keep the BT.709 chromaticities at every level; TRC = v^γ.
    let gammas = [2.25, 2.2, 2.15];
    let bt709 = [[0.64, 0.33], [0.30, 0.60], [0.15, 0.06]];
    for c in 0..3 {
        // The phosphors' spectra were fitted to the BT.709 primaries.
        let primary = crt.primary_xy(c);
        assert!(
            (primary[0] - bt709[c][0]).abs() < 2e-4 && (primary[1] - bt709[c][1]).abs() < 2e-4,
            "{primary:?}"
        );
        for code in [1u8, 17, 128, 200] {
            let mut rgb = [0u8; 3];
            rgb[c] = code;
            let term = sub(crt.xyz(rgb), k);
            let expect = (f64::from(code) / 255.0).powf(gammas[c]);
            assert!(
                close(term, full[c].map(|t| t * expect), 1e-9),
                "c {c} code {code}"
            );
            let [x, y] = xy(term);
            assert!((x - primary[0]).abs() < 1e-9 && (y - primary[1]).abs() < 1e-9);
        }
    }
    // Additive: any mixture is black plus the sum of its channels alone.
    for rgb in [[10u8, 200, 33], [128, 128, 128], [255, 1, 77]] {
        let mut sum = k;
        for c in 0..3 {
            let mut alone = [0u8; 3];
            alone[c] = rgb[c];
            let t = sub(crt.xyz(alone), k);
            sum = Xyz::new(sum[0] + t[0], sum[1] + t[1], sum[2] + t[2]);
        }
        assert!(close(crt.xyz(rgb), sum, 1e-12), "{rgb:?}");
    }
}

#[test]
fn lcd_black_has_its_own_chromaticity_and_channels_drift() {
    let lcd = VirtualPanel::preset(Preset::IpsLcd);
    let k = lcd.xyz([0; 3]);
    assert!((k[1] - 0.22).abs() < 1e-12);
    let [x, y] = xy(k);
    assert!((x - 0.262).abs() < 1e-12 && (y - 0.258).abs() < 1e-12);
    // Red alone at code 64 (crosstalk off, so red is all there is): chromaticity =
    // primary (its spectrum's) + drift·(1 − L), L its level.
    let mut params = Preset::IpsLcd.params();
    params.crosstalk = [[0.0; 3]; 3];
    let lcd = VirtualPanel::new("no crosstalk", params);
    let [x0, y0] = lcd.primary_xy(0);
    let full = sub(lcd.xyz([255, 0, 0]), k);
    let term = sub(lcd.xyz([64, 0, 0]), k);
    let level = term[1] / full[1];
    let [x, y] = xy(term);
    assert!((x - (x0 - 0.030 * (1.0 - level))).abs() < 1e-12);
    assert!((y - (y0 + 0.020 * (1.0 - level))).abs() < 1e-12);
    assert!(0.030 * (1.0 - level) > 0.02, "drift visible at a low level");
}

#[test]
fn lcd_mixtures_are_not_additive_by_the_crosstalk() {
    // Only red ↔ green crosstalk, no drift: luminances follow by hand.
    let mut params = Preset::IpsLcd.params();
    params.crosstalk = [[0.0, 0.015, 0.0], [0.020, 0.0, 0.0], [0.0; 3]];
    params.drift_xy = [[0.0; 2]; 3];
    let lcd = VirtualPanel::new("red-green crosstalk", params.clone());
    let k = lcd.xyz([0; 3]);
    let max = lcd.channel_max_cd_m2();
    let v = 128.0 / 255.0;
    // Red alone at v: red driven at v, green leaks at 0.020·v·(1 − 0).
    let red = sub(lcd.xyz([128, 0, 0]), k);
    let expect = max[0] * params.trc[0].eval(v) + max[1] * params.trc[1].eval(0.020 * v);
    assert!(
        (red[1] - expect).abs() < 1e-9 * expect,
        "{} vs {expect}",
        red[1]
    );
    // Both at v: red driven at v + 0.015·v(1 − v), green at v + 0.020·v(1 − v).
    let mixed = sub(lcd.xyz([128, 128, 0]), k);
    let expect = max[0] * params.trc[0].eval(v + 0.015 * v * (1.0 - v))
        + max[1] * params.trc[1].eval(v + 0.020 * v * (1.0 - v));
    assert!(
        (mixed[1] - expect).abs() < 1e-9 * expect,
        "{} vs {expect}",
        mixed[1]
    );
    // On the preset itself the additivity failure of a mixture is of the order of 1 %.
    let lcd = VirtualPanel::preset(Preset::IpsLcd);
    let k = lcd.xyz([0; 3]);
    let alone: f64 = (0..3)
        .map(|c| {
            let mut rgb = [0u8; 3];
            rgb[c] = 128;
            lcd.xyz(rgb)[1] - k[1]
        })
        .sum();
    let failure = ((lcd.xyz([128; 3])[1] - k[1]) / alone - 1.0).abs();
    assert!(
        (0.003..0.05).contains(&failure),
        "additivity failure {failure}"
    );
}

#[test]
fn lcd_trcs_are_not_power_laws() {
    // Local exponent d ln L / d ln v: constant γ for a power law.
    let exponent = |t: &PanelTrc, v: f64| {
        let h = 1e-4;
        ((t.eval(v + h)).ln() - (t.eval(v - h)).ln()) / ((v + h).ln() - (v - h).ln())
    };
    for preset in [Preset::IpsLcd, Preset::WideGamutCcfl] {
        for t in preset.params().trc {
            assert_eq!(t.eval(0.0), 0.0);
            assert!((t.eval(1.0) - 1.0).abs() < 1e-15);
            let (lo, hi) = (exponent(&t, 0.25), exponent(&t, 0.75));
            assert!((lo - hi).abs() > 0.1, "{}: {lo} vs {hi}", preset.name());
            let mut last = 0.0;
            for i in 1..=255 {
                let l = t.eval(f64::from(i) / 255.0);
                assert!(l > last);
                last = l;
            }
        }
    }
    let t = PanelTrc::power(2.2);
    assert!((exponent(&t, 0.25) - 2.2).abs() < 1e-6 && (exponent(&t, 0.75) - 2.2).abs() < 1e-6);
}

#[test]
fn drive_values_are_quantised_to_8_bits() {
    let lcd = VirtualPanel::preset(Preset::IpsLcd);
    assert_eq!(quantize(0.5), 128); // 127.5 rounds up
    assert_eq!(quantize(0.499), 127);
    assert_eq!(quantize(-0.2), 0);
    assert_eq!(quantize(1.7), 255);
    assert_eq!(lcd.xyz_of_drive([0.5, 0.2, 1.0]), lcd.xyz([128, 51, 255]));
    assert_eq!(
        lcd.xyz_of_drive([0.5011, 0.2, 1.0]),
        lcd.xyz([128, 51, 255])
    );
}

#[test]
fn white_luminance_scales_everything_alike() {
    let crt = VirtualPanel::preset(Preset::IdealCrt);
    let dim = crt.with_white_luminance(80.0);
    for rgb in [[0u8, 0, 0], [255, 255, 255], [12, 200, 99]] {
        assert!(
            close(dim.xyz(rgb), crt.xyz(rgb).map(|v| v * 0.8), 1e-12),
            "{rgb:?}"
        );
    }
    assert!((dim.xyz([0; 3])[1] - 0.04).abs() < 1e-15);
}

#[test]
fn the_simulated_meter_measures_what_is_shown() {
    let mut display = VirtualDisplay::preset(Preset::IdealCrt);
    let mut meter =
        metamer_drivers::open_instrument("sim:cs100a?time_scale=0&noise=off", display.stimulus())
            .unwrap();
    let request = metamer_drivers::Request::default();
    display.show([255, 255, 255]).unwrap();
    let r = meter.measure(&request).unwrap();
    // The CS-100A sends x, y with 4 decimals and Y with 3 significant digits or more.
    assert_eq!(r.xyy, [0.3127, 0.3290, 100.0]);
    display.show([0, 0, 255]).unwrap();
    assert_eq!(display.shown(), [0, 0, 255]);
    let r = meter.measure(&request).unwrap();
    let expect = display.panel().xyz([0, 0, 255]);
    assert!(
        (r.xyy[2] - expect[1]).abs() < 0.01,
        "{:?} vs {expect:?}",
        r.xyy
    );
    assert_eq!(display.spec(), "virtual:ideal-crt");
}

/// x, y of a spectrum summed here from the CIE 1931 table at 1 nm (380–780 nm).
fn spectrum_xy(s: &metamer_color::Spectrum) -> [f64; 2] {
    let o = metamer_color::observer(metamer_color::ObserverKind::Cie1931);
    let mut xyz = [0.0; 3];
    for nm in 380..=780 {
        let v = s.value_at(f64::from(nm));
        for (k, c) in o.at_nm(nm).into_iter().enumerate() {
            xyz[k] += v * c;
        }
    }
    xy(xyz)
}

#[test]
fn every_channel_spectrum_has_its_primary_chromaticity() {
    for p in Preset::ALL {
        let panel = VirtualPanel::preset(p);
        for c in 0..3 {
            let s = panel.channel_spectrum(c);
            assert!(s.values().iter().all(|&v| v >= 0.0), "{} {c}", p.name());
            let got = spectrum_xy(s);
            let want = p.params().primaries_xy[c];
            let d = (got[0] - want[0]).abs().max((got[1] - want[1]).abs());
            assert!(d < 0.002, "{} channel {c}: {got:?} vs {want:?}", p.name());
        }
    }
}

/// What the panel emits is one spectrum whose CIE 1931 integral is the XYZ the colorimeter
/// model gives, for every kind of drive (black, primaries, dim channels that drift, mixtures).
#[test]
fn the_emitted_spectrum_integrates_to_the_emitted_xyz() {
    for p in Preset::ALL {
        let panel = VirtualPanel::preset(p);
        for rgb in [
            [0u8; 3],
            [255; 3],
            [255, 0, 0],
            [0, 30, 0],
            [12, 200, 99],
            [90, 5, 250],
        ] {
            let s = panel.spectrum(rgb);
            assert!(s.values().iter().all(|&v| v >= 0.0));
            let from_spectrum =
                metamer_color::radiance_to_xyz(&s, metamer_color::ObserverKind::Cie1931);
            assert!(
                close(from_spectrum.to_array(), panel.xyz(rgb), 1e-12),
                "{} {rgb:?}",
                p.name()
            );
        }
        // Black is the preset's, as a spectrum too.
        let [x, y] = spectrum_xy(&panel.spectrum([0; 3]));
        let want = p.params().black_xy;
        assert!((x - want[0]).abs() < 1e-9 && (y - want[1]).abs() < 1e-9);
    }
}

#[test]
fn drive_values_come_back_from_their_colour_and_outside_colours_have_none() {
    for p in Preset::ALL {
        let panel = VirtualPanel::preset(p);
        for v in [
            [0.5, 0.5, 0.5],
            [0.9, 0.1, 0.3],
            [0.2, 0.8, 0.05],
            [1.0, 1.0, 1.0],
        ] {
            let back = panel
                .drive_for(panel.xyz_at(v))
                .unwrap_or_else(|| panic!("{} {v:?}", p.name()));
            assert!(
                back.iter().zip(v).all(|(a, b)| (a - b).abs() < 1e-6),
                "{} {v:?} -> {back:?}",
                p.name()
            );
        }
        // Brighter than full white, and the spectral locus at 520 nm (x 0.0743, y 0.8338).
        let w = panel.xyz([255; 3]);
        assert_eq!(panel.drive_for(w.map(|c| c * 1.1)), None, "{}", p.name());
        let locus = xyy(0.0743, 0.8338, 10.0);
        assert_eq!(panel.drive_for(locus.into()), None, "{}", p.name());
    }
}

fn xyy(x: f64, y: f64, lum: f64) -> [f64; 3] {
    [x / y * lum, lum, (1.0 - x - y) / y * lum]
}

/// A simulated spectrometer aimed at the display reads the spectrum it shows.
#[test]
fn the_simulated_spectrometer_sees_the_spectrum() {
    let mut display = VirtualDisplay::preset(Preset::IpsLcd);
    let mut meter =
        metamer_drivers::open_instrument("sim:i1pro?time_scale=0&noise=off", display.stimulus())
            .unwrap();
    let mode = metamer_drivers::MeasureMode::Emissive;
    while let Some(condition) = meter.calibration_needed(mode).unwrap() {
        meter.calibrate(mode, &condition).unwrap();
    }
    display.show([255, 255, 255]).unwrap();
    let request = metamer_drivers::Request { mode };
    let r = meter.measure(&request).unwrap();
    let seen = r.spectrum.expect("a spectrometer reports a spectrum");
    let shown = display.panel().spectrum([255; 3]);
    // The blue LED's peak and the phosphor's hump, 10 nm samples against the 1 nm truth.
    for nm in [450.0, 550.0, 600.0] {
        let (a, b) = (seen.value_at(nm), shown.value_at(nm));
        assert!((a / b - 1.0).abs() < 0.02, "{nm} nm: {a} vs {b}");
    }
    assert!((r.xyz[1] / 200.0 - 1.0).abs() < 0.01, "{:?}", r.xyz);
}

/// An image shown whole: a meter aimed inside the left half sees the left colour's
/// emission, one not aimed sees the mean of both halves' spectra (equal pixel counts),
/// and one whose spot straddles the edge sees the pixel-count-weighted mean.
#[test]
fn an_aimed_meter_sees_the_mean_emission_under_its_spot() {
    let (red, blue) = ([255, 0, 0], [0, 0, 255]);
    // 4×2: the left two columns red, the right two blue.
    let pixels = (0..8).map(|i| if i % 4 < 2 { red } else { blue }).collect();
    let image = Drive8Image::new(4, 2, pixels).unwrap();
    let mut display = VirtualDisplay::preset(Preset::IpsLcd);
    assert_eq!(display.show_image(&image).unwrap(), Placement::WHOLE);
    let world = display.stimulus().unwrap();
    let aim = display.meter_aim().unwrap();
    let seen = || match world.view() {
        View::Emissive(Light::Radiance(s)) => s.values().to_vec(),
        _ => panic!("a display emits"),
    };
    let (r, b) = (
        display.panel().spectrum(red).values().to_vec(),
        display.panel().spectrum(blue).values().to_vec(),
    );
    let near = |a: &[f64], want: &[f64]| a.iter().zip(want).all(|(x, y)| (x - y).abs() <= 1e-12);
    aim.set(Some(ScreenSpot {
        x: 0.25,
        y: 0.5,
        radius: 0.3,
    }));
    assert!(near(&seen(), &r));
    assert_eq!(display.shown(), red);
    aim.set(None);
    let mean: Vec<f64> = r.iter().zip(&b).map(|(x, y)| (x + y) / 2.0).collect();
    assert!(near(&seen(), &mean));
    // Centred on the corner (2, 1) of four pixels with radius 0.3 of the height = 0.6 px:
    // their centres lie 0.707 px away, so the disc holds none and the pixel under the
    // centre, column 2 (blue), stands for it.
    aim.set(Some(ScreenSpot {
        x: 0.5,
        y: 0.5,
        radius: 0.3,
    }));
    assert!(near(&seen(), &b));
    // Radius 0.4 of the height = 0.8 px: all four centres, two red and two blue.
    aim.set(Some(ScreenSpot {
        x: 0.5,
        y: 0.5,
        radius: 0.4,
    }));
    assert!(near(&seen(), &mean));
}

/// A still meter over a slid image: the image's left half red and right half blue, the
/// meter's spot inside the left half. Slid two pixels right, the spot sees what the slide
/// uncovered (black); slid two left, the blue half; slid back, red; slid a row up, black
/// again. A slide before any
/// image is refused, and a colour shown in between is replaced by the image slid.
#[test]
fn a_still_meter_sees_what_the_slide_brings_under_it() {
    let (red, blue) = ([255, 0, 0], [0, 0, 255]);
    let pixels = (0..8).map(|i| if i % 4 < 2 { red } else { blue }).collect();
    let image = Drive8Image::new(4, 2, pixels).unwrap();
    let mut display = VirtualDisplay::preset(Preset::IpsLcd);
    assert!(matches!(
        display.shift_image([1, 0]),
        Err(ScreenError::NoImage { .. })
    ));
    display.show_image(&image).unwrap();
    let world = display.stimulus().unwrap();
    display.meter_aim().unwrap().set(Some(ScreenSpot {
        x: 0.25,
        y: 0.5,
        radius: 0.3,
    }));
    let seen = || match world.view() {
        View::Emissive(Light::Radiance(s)) => {
            metamer_color::radiance_to_xyz(&s, metamer_color::ObserverKind::Cie1931)
        }
        _ => panic!("a display emits"),
    };
    let panel = display.panel().clone();
    for (by, under) in [
        ([2, 0], [0, 0, 0]),
        ([-2, 0], blue),
        ([0, 0], red),
        // The spot, under 1 px across, counts the pixel under its centre, (1, 1): the
        // slide up leaves that row black.
        ([0, -1], [0, 0, 0]),
    ] {
        display.shift_image(by).unwrap();
        assert!(close(seen(), panel.xyz(under), 1e-12), "{by:?}");
        assert_eq!(display.shown(), under, "{by:?}");
    }
    display.show([0, 255, 0]).unwrap();
    display.shift_image([0, 0]).unwrap();
    assert_eq!(display.shown(), red);
}
