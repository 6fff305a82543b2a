//! The validation report in a real browser. Headless Chromium loads `report.html` from
//! disk, with logging on, and must log no console error, draw a non-trivial screenshot and
//! have the figures in its DOM. Then the page as a reader meets it: laid out 1280 and
//! 390 px wide it must not scroll sideways and draw no SVG text under 10 px; Fig. 5's
//! labels must not overlap and each patch's displacement must show in a screenshot; printed
//! to PDF, no figure may be split across pages. Skipped (with the reason printed) only
//! where no chromium binary is installed; in CI (`CI` set) a missing chromium, or a missing
//! poppler (`pdftotext`, `pdfinfo`, `pdftoppm`) for the print test, fails the test.
//!
//! Measurements come from a probe script run in a copy of the page (the report itself runs
//! no code): the copy is the `srcdoc` of an iframe exactly as wide as the width under test
//! (headless Chromium lays a window out no narrower than 500 px), and the probe writes its
//! findings as JSON into the outer page, which `--dump-dom` prints.

use std::path::{Path, PathBuf};
use std::process::Command;

use serde_json::Value;

mod chromium;

use chromium::{browser, fresh, headless, load};

use crate::support::oracle::{PDFINFO, PDFTOPPM, PDFTOTEXT};
use crate::support::validate_data;

/// Runs in the page's copy once it has loaded; measures in CSS pixels of the page.
const PROBE: &str = r#"<script>addEventListener('load', () => {
  const de = document.documentElement;
  const box = r => [r.left + scrollX, r.top + scrollY, r.right + scrollX, r.bottom + scrollY];
  const centre = e => { const r = e.getBoundingClientRect(); return [(r.left + r.right) / 2 + scrollX, (r.top + r.bottom) / 2 + scrollY]; };
  const out = { width: innerWidth, scroll_width: de.scrollWidth, height: de.scrollHeight,
                texts: 0, smallest: 1e9, small: [], labels: [], marks: [], figures: [] };
  for (const t of document.querySelectorAll('svg text')) {
    if (!t.getClientRects().length) continue;
    const m = t.getScreenCTM();
    const px = parseFloat(getComputedStyle(t).fontSize) * Math.hypot(m.a, m.b);
    out.texts++;
    out.smallest = Math.min(out.smallest, px);
    if (px < 10) out.small.push([Math.round(px * 100) / 100, t.textContent.slice(0, 50)]);
  }
  for (const svg of document.querySelectorAll('svg.plane')) {
    for (const t of svg.querySelectorAll('text.label'))
      out.labels.push({ plane: svg.id, patch: +t.dataset.patch, box: box(t.getBoundingClientRect()) });
    const scale = svg.getScreenCTM().a;
    for (const c of svg.querySelectorAll('circle.box')) {
      const d = svg.querySelector('circle.display[data-patch="' + c.dataset.patch + '"]');
      out.marks.push({ plane: svg.id, patch: +c.dataset.patch, from: centre(c), to: centre(d),
                       ring: 3.4 * scale, disc: 5 * scale, frame: box(svg.getBoundingClientRect()),
                       magnification: +d.dataset.magnification,
                       figure_magnification: +svg.querySelector('text').textContent.split('×')[1] });
    }
  }
  for (const f of document.querySelectorAll('figure[id$="-figure"]')) {
    const titles = [...f.querySelectorAll('svg.figure')]
      .filter(s => s.getClientRects().length)
      .map(s => s.querySelector('text').textContent);
    out.figures.push({ id: f.id, titles, caption: f.querySelector('figcaption').textContent,
                       box: box(f.getBoundingClientRect()) });
  }
  parent.document.getElementById('probe').textContent = JSON.stringify(out);
});</script>"#;

/// `html` with the probe, as the `srcdoc` of an iframe `width` px wide in a page of its own.
fn probe_page(html: &str, width: u32) -> String {
    let inner = html.replace("</body>", &format!("{PROBE}</body>"));
    let attr = inner.replace('&', "&amp;").replace('"', "&quot;");
    format!(
        "<!DOCTYPE html><html><head><style>html,body{{margin:0;overflow:hidden}}iframe{{border:0;display:block}}</style></head><body><iframe scrolling=\"no\" width=\"{width}\" height=\"30000\" srcdoc=\"{attr}\"></iframe><pre id=\"probe\" hidden></pre></body></html>"
    )
}

/// The probe's findings on `report` laid out `width` px wide.
fn probe(browser: &Path, dir: &Path, report: &Path, width: u32) -> Value {
    let html = std::fs::read_to_string(report).unwrap();
    let page = dir.join(format!("probe-{width}.html"));
    std::fs::write(&page, probe_page(&html, width)).unwrap();
    let run = headless(
        browser,
        dir,
        &[
            "--dump-dom",
            &format!("--window-size={},900", width.max(500)),
        ],
        &page,
    );
    let dom = String::from_utf8_lossy(&run.stdout);
    let start = dom
        .find("<pre id=\"probe\" hidden=\"\">")
        .map(|i| i + "<pre id=\"probe\" hidden=\"\">".len())
        .unwrap_or_else(|| panic!("no probe in the DOM:\n{}", &dom[..dom.len().min(2000)]));
    let end = start + dom[start..].find("</pre>").unwrap();
    let json = dom[start..end]
        .replace("&lt;", "<")
        .replace("&gt;", ">")
        .replace("&amp;", "&");
    serde_json::from_str(&json).unwrap_or_else(|e| panic!("probe JSON: {e}\n{json}"))
}

/// At `width` px: the page does not scroll sideways and no SVG text is under 10 px.
fn check_layout(p: &Value, width: u32, what: &str) {
    assert_eq!(p["width"], width, "{what}: laid out at another width");
    let scroll = p["scroll_width"].as_f64().unwrap();
    assert!(
        scroll <= f64::from(width),
        "{what} at {width} px: the page is {scroll} px wide and scrolls sideways"
    );
    assert!(p["texts"].as_u64().unwrap() > 100, "{what}: too few texts");
    assert!(
        p["small"].as_array().unwrap().is_empty(),
        "{what} at {width} px: SVG text under 10 px: {}",
        p["small"]
    );
    eprintln!(
        "{what} at {width} px: {} SVG texts, the smallest {:.2} px; page {} px wide",
        p["texts"],
        p["smallest"].as_f64().unwrap(),
        scroll
    );
}

/// No two of Fig. 5's labels overlap, in either plane.
fn check_labels(p: &Value, what: &str) {
    let labels = p["labels"].as_array().unwrap();
    assert_eq!(labels.len(), 2 * 24, "{what}: Fig. 5 has 24 labels a plane");
    let rect = |l: &Value| -> [f64; 4] {
        let b = l["box"].as_array().unwrap();
        [0, 1, 2, 3].map(|k| b[k].as_f64().unwrap())
    };
    for (i, a) in labels.iter().enumerate() {
        let ra = rect(a);
        assert!(ra[2] > ra[0] && ra[3] > ra[1], "{what}: an empty label {a}");
        for b in &labels[i + 1..] {
            if a["plane"] != b["plane"] {
                continue;
            }
            let rb = rect(b);
            let overlap = (ra[2].min(rb[2]) - ra[0].max(rb[0])).max(0.0)
                * (ra[3].min(rb[3]) - ra[1].max(rb[1])).max(0.0);
            assert!(
                overlap == 0.0,
                "{what}: labels {} and {} overlap in {} ({overlap} px²)",
                a["patch"],
                b["patch"],
                a["plane"]
            );
        }
    }
}

/// The validate example's report (CIEDE2000 pairs as readings) in `dir`.
fn validate_report(dir: &Path) -> PathBuf {
    let out = Command::new(env!("CARGO_BIN_EXE_metamer"))
        .args(["validate", "--reference"])
        .arg(validate_data("box.csv"))
        .arg("--test")
        .arg(validate_data("display.csv"))
        .arg("--simulation")
        .arg(validate_data("box.csv"))
        .args(["--out-of-gamut", "7,12", "-o"])
        .arg(dir)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    dir.join("report.html")
}

/// The experiment's report with every section, from the cut-down experiment directory
/// `tests/data/report/experiment` (a lab run lit by LED-RGB1), compared with the cut-down
/// run `tests/data/report/adaptive` (the display characterized by the adaptive plan, its
/// spots read until decided), in `dir`.
fn experiment_report(dir: &Path) -> PathBuf {
    use metamer::experiment::validate::report_input;
    use metamer::output::OutputPolicy;
    use metamer::validation::job::ReadingFiles;
    use metamer::validation::write_report_files;

    let exp = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/report/experiment");
    let files = ReadingFiles {
        box_readings: &exp.join("box/spots.csv"),
        display: &exp.join("display-spots/spots.csv"),
        simulation: Some(&exp.join("simulation/spots.csv")),
    };
    let white = metamer::color::Xyz::new(29.424_122_518_279_695, 31.015, 34.538_708_337_905_01);
    let oog = [1, 4, 7, 9, 11, 12, 14, 15, 16];
    let other = exp.with_file_name("adaptive");
    let input = report_input(&exp.join("validation"), white, &files, &oog, Some(&other)).unwrap();
    write_report_files(dir, &input, &OutputPolicy::new(true)).unwrap();
    dir.join("report.html")
}

#[test]
fn report_renders_in_headless_chromium_without_console_errors() {
    let Some(browser) = browser() else {
        return;
    };
    let dir = fresh("report-browser");
    let page = validate_report(&dir);
    let dom = load(&browser, &dir, &page, "METAMER_KEEP_SCREENSHOT");
    for id in ["fig4", "fig5", "fig6", "fig7", "verdict"] {
        assert!(dom.contains(&format!("id=\"{id}\"")), "the DOM lacks #{id}");
    }
    // Three bar charts of 24 patches, each drawn wide and narrow, and one figure of two
    // planes with 24 patches each. The two patches out of the display's gamut are marked
    // in the two charts with the display on one side, not in box vs simulation.
    assert_eq!(dom.matches("class=\"bar\"").count(), 2 * 3 * 24);
    assert_eq!(dom.matches("class=\"box\"").count(), 2 * 24);
    assert_eq!(dom.matches("class=\"display\"").count(), 2 * 24);
    assert_eq!(dom.matches("class=\"oog\"").count(), 2 * 2 * 2);
    std::fs::remove_dir_all(&dir).ok();
}

/// The experiment's report with every section, built from a small experiment directory
/// (`tests/data/report/`), in a real browser: no console error, every section in the DOM,
/// the light chart inlined without scripts.
#[test]
fn experiment_report_has_every_section_in_headless_chromium() {
    let Some(browser) = browser() else {
        return;
    };
    let dir = fresh("report-experiment");
    let page = experiment_report(&dir);
    let dom = load(&browser, &dir, &page, "METAMER_KEEP_EXPERIMENT_SCREENSHOT");
    for id in [
        "verdict",
        "fig4",
        "fig6",
        "uncertainty",
        "display-model",
        "display-verification",
        "light-fit",
        "light-chart",
        "render-confidence",
        "instruments",
        "cost",
        "cost-chart",
        "cost-curves",
        "inputs",
    ] {
        assert!(dom.contains(&format!("id=\"{id}\"")), "the DOM lacks #{id}");
    }
    assert!(!dom.contains("<script"), "the page must run no code");
    // The verdict names the six patches above the JND and why.
    assert!(
        dom.contains("18 of 24 patches are below the JND"),
        "verdict"
    );
    assert!(dom.contains(
        "6 outside the display's gamut (7 orange, 11 yellow green, 12 orange yellow, 14 green, 15 red, 16 yellow)"
    ));
    assert!(dom.contains(
        "In all 6 the simulation is within 0.4 of the box: the error arises on the display."
    ));
    // The i1Pro's two calibrations (emissive for the tiles, reflective for the materials).
    assert_eq!(dom.matches("on white tile").count(), 2);
    // The render's bound enters the simulation's intervals.
    assert!(dom.contains("radiosity solver's per-patch error bound"));
    // The display's and the display spots' costs as their files keep them (the box's
    // readings were given, and cost nothing here), and their total: 194 + 72 readings.
    assert!(
        dom.contains("<td class=\"l\">all</td><td>266</td><td>24</td>"),
        "the cost table's total"
    );
    // The compared run's total beside it (its files keep no box: the box's cost was
    // measured by the same fixed plan): its display's 128 readings (104 fitted, 24 held
    // out) and its display spots' 50 (every patch read twice or more, until decided).
    assert!(
        dom.contains("<td class=\"l\">all (adaptive)</td><td>178 (budget 200)</td>"),
        "the compared run's total"
    );
    // The chart's lines, one per side and plan: this run's display model (fixed, held out:
    // its spot journals keep no readings) and the compared run's.
    for line in [
        "display model, held out, fixed (this run)",
        "display model, adaptive (adaptive)",
        "display model, held out, adaptive (adaptive)",
        "display spots, until decided (adaptive)",
    ] {
        assert_eq!(
            dom.matches(line).count(),
            2,
            "{line}: once against readings, once against minutes"
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// Both reports laid out 1280 and 390 px wide: no sideways scrolling of the page (tables
/// and the light chart scroll in their boxes), no SVG text under 10 px, Fig. 5's labels
/// apart.
#[test]
fn reports_fit_1280_and_390_px_with_text_of_10_px_or_more() {
    let Some(browser) = browser() else {
        return;
    };
    let dir = fresh("report-widths");
    let validate_dir = dir.join("validate");
    let experiment_dir = dir.join("experiment");
    for (what, page) in [
        ("validate report", validate_report(&validate_dir)),
        ("experiment report", experiment_report(&experiment_dir)),
    ] {
        for width in [1280, 390] {
            let p = probe(&browser, &dir, &page, width);
            check_layout(&p, width, what);
            check_labels(&p, what);
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// sRGB of the pixel at (x, y) of an 8-bit RGB or RGBA PNG.
struct Image {
    width: usize,
    height: usize,
    channels: usize,
    pixels: Vec<u8>,
}

impl Image {
    fn read(file: &Path) -> Image {
        let decoder =
            png::Decoder::new(std::io::BufReader::new(std::fs::File::open(file).unwrap()));
        let mut reader = decoder.read_info().unwrap();
        let mut pixels = vec![0; reader.output_buffer_size().unwrap()];
        let info = reader.next_frame(&mut pixels).unwrap();
        assert_eq!(info.bit_depth, png::BitDepth::Eight);
        Image {
            width: info.width as usize,
            height: info.height as usize,
            channels: info.color_type.samples(),
            pixels,
        }
    }

    /// The pixel that holds the point (x, y) of the page.
    fn at(&self, x: f64, y: f64) -> [u8; 3] {
        let (x, y) = (x.floor() as usize, y.floor() as usize);
        assert!(
            x < self.width && y < self.height,
            "({x}, {y}) is off the screenshot"
        );
        let i = (y * self.width + x) * self.channels;
        [self.pixels[i], self.pixels[i + 1], self.pixels[i + 2]]
    }
}

/// Not the plot's background (#fafafa), its white margin or a halo.
fn drawn(c: [u8; 3]) -> bool {
    c.iter().any(|&v| v < 215)
}

/// Fig. 5 in a 1280 px screenshot: for every patch whose displacement is drawn longer than
/// its ring's radius, the pixels from its disc to its ring are drawn, and its ring is drawn
/// at its far side; a patch drawn at a magnification other than the figure's is named in
/// the caption with it; a patch drawn shorter is named in the caption as such. In the
/// test data every displacement shows, in both planes.
#[test]
fn fig5_shows_each_displacement_in_a_screenshot() {
    let Some(browser) = browser() else {
        return;
    };
    let dir = fresh("report-fig5");
    let page = experiment_report(&dir);
    let p = probe(&browser, &dir, &page, 1280);
    let marks = p["marks"].as_array().unwrap();
    assert_eq!(marks.len(), 2 * 24);
    let bottom = marks
        .iter()
        .map(|m| m["frame"][3].as_f64().unwrap())
        .fold(0.0, f64::max);
    // The same probe page, shot at a height that holds Fig. 5 whole: the same layout.
    let shot = dir.join("fig5.png");
    headless(
        &browser,
        &dir,
        &[
            &format!("--screenshot={}", shot.display()),
            &format!("--window-size=1280,{}", bottom.ceil() as u32 + 20),
        ],
        &dir.join("probe-1280.html"),
    );
    if let Ok(keep) = std::env::var("METAMER_KEEP_FIG5_SCREENSHOT") {
        std::fs::copy(&shot, keep).unwrap();
    }
    let img = Image::read(&shot);
    let caption = p["figures"]
        .as_array()
        .unwrap()
        .iter()
        .find(|f| f["id"] == "fig5-figure")
        .expect("Fig. 5 is a figure")["caption"]
        .as_str()
        .unwrap()
        .to_string();
    let mut checked = 0;
    let mut own_count = 0;
    for m in marks {
        let xy = |k: &str| (m[k][0].as_f64().unwrap(), m[k][1].as_f64().unwrap());
        let (from, to) = (xy("from"), xy("to"));
        let ring = m["ring"].as_f64().unwrap();
        let len = (to.0 - from.0).hypot(to.1 - from.1);
        let plane = if m["plane"] == "fig5-ab" {
            "a*b*"
        } else {
            "L*a*"
        };
        let (own, figure) = (
            m["magnification"].as_f64().unwrap(),
            m["figure_magnification"].as_f64().unwrap(),
        );
        assert!(figure >= 1.0, "no magnification in Fig. 5's title");
        if own != figure {
            // "…: a*b* plane 9 ×500, 22 ×200; L*a* plane 7 ×100, …."
            let stated = format!("{} ×{own}", m["patch"]);
            let listed = caption
                .split("that shows it): ")
                .nth(1)
                .and_then(|rest| rest.split(". ").next())
                .map(|list| list.trim_end_matches('.'))
                .is_some_and(|list| {
                    list.split("; ").any(|part| {
                        part.starts_with(&format!("{plane} plane "))
                            && part
                                .split(", ")
                                .any(|e| e.trim_start_matches(&format!("{plane} plane ")) == stated)
                    })
                });
            assert!(
                listed,
                "patch {} is drawn ×{own} in {plane}, not ×{figure}, and the caption does not say so: {caption}",
                m["patch"]
            );
            own_count += 1;
        }
        if len < ring {
            // "…, so the ring sits on its disc: 9, 22 in the a*b* plane; 7, 9, 22 in …; their"
            let named = caption
                .split_once("the ring sits on its disc:")
                .and_then(|(_, rest)| rest.split_once("; their"))
                .map(|(list, _)| list.to_string())
                .unwrap_or_default();
            let patch = m["patch"].to_string();
            let listed = named.split("; ").any(|part| {
                part.ends_with(&format!(" in the {plane} plane"))
                    && part
                        .split(|c: char| !c.is_ascii_digit())
                        .any(|n| n == patch)
            });
            // Within a tenth of a pixel the page's rounding may put it either side.
            assert!(
                listed || len > ring - 0.1,
                "patch {} is drawn {len:.2} px long in {plane}, and the caption does not say so: {caption}",
                m["patch"]
            );
            continue;
        }
        let (ux, uy) = ((to.0 - from.0) / len, (to.1 - from.1) / len);
        // Along the line, up to where the ring begins.
        let steps = ((len - ring) / 1.0).floor() as usize;
        for k in 0..=steps {
            let t = k as f64;
            let c = img.at(from.0 + t * ux, from.1 + t * uy);
            assert!(
                drawn(c),
                "patch {} in {}: nothing drawn {t:.0} px along its {len:.1} px displacement (pixel {c:?})",
                m["patch"],
                m["plane"]
            );
        }
        // The ring, on the far side from the disc: black (the darkest pixel where it is
        // drawn, as its edge is smoothed), or where it has a magnification of its own, blue
        // (the bluest pixel there), never under another mark.
        let (fx, fy) = (to.0 + ring * ux, to.1 + ring * uy);
        let around = [-1.0, 0.0, 1.0]
            .iter()
            .flat_map(|dx| [-1.0, 0.0, 1.0].map(|dy| img.at(fx + dx, fy + dy)));
        let blueness = |c: &[u8; 3]| i32::from(c[2]) - i32::from(c[0]);
        let far = if own == figure {
            around
                .min_by_key(|c| c.iter().map(|&v| u32::from(v)).sum::<u32>())
                .unwrap()
        } else {
            around.max_by_key(blueness).unwrap()
        };
        assert!(
            if own == figure {
                // Black, or where a short mark of its own magnification is drawn over it, blue.
                far.iter().all(|&v| v < 100) || blueness(&far) > 80
            } else {
                blueness(&far) > 80
            },
            "patch {} in {}: its ring is not drawn (pixel {far:?})",
            m["patch"],
            m["plane"]
        );
        checked += 1;
    }
    eprintln!(
        "Fig. 5: {checked} of 48 displacements checked pixel by pixel, {own_count} at a magnification of their own"
    );
    // The data's displacements run from 0.08 to 9.3 ΔE*ab: the small ones get their own
    // magnification, so every one is drawn long enough to see.
    assert_eq!(
        checked, 48,
        "not every displacement is drawn long enough to see"
    );
    assert!(
        own_count > 0,
        "the test data's small displacements need their own magnification"
    );
    std::fs::remove_dir_all(&dir).ok();
}

fn squash(s: &str) -> String {
    s.split_whitespace().collect::<Vec<_>>().join(" ")
}

/// Printed to PDF, every figure's title and caption's first and last words are on one
/// page; no page is blank.
#[test]
fn report_prints_to_pdf_without_splitting_a_figure() {
    let Some(browser) = browser() else {
        return;
    };
    let (Some(pdftotext), Some(pdfinfo), Some(pdftoppm)) =
        (PDFTOTEXT.find(), PDFINFO.find(), PDFTOPPM.find())
    else {
        return;
    };
    let dir = fresh("report-print");
    let page = experiment_report(&dir);
    let pdf = dir.join("report.pdf");
    headless(
        &browser,
        &dir,
        &[
            &format!("--print-to-pdf={}", pdf.display()),
            "--no-pdf-header-footer",
        ],
        &page,
    );
    let info = Command::new(pdfinfo).arg(&pdf).output().unwrap();
    let info = String::from_utf8_lossy(&info.stdout);
    let pages: usize = info
        .lines()
        .find_map(|l| l.strip_prefix("Pages:"))
        .unwrap_or_else(|| panic!("pdfinfo: {info}"))
        .trim()
        .parse()
        .unwrap();
    let text = Command::new(pdftotext).arg(&pdf).arg("-").output().unwrap();
    let text = String::from_utf8_lossy(&text.stdout);
    let page_texts: Vec<String> = text.split('\u{c}').map(squash).collect();
    assert!(page_texts.len() >= pages, "pdftotext found fewer pages");
    let page_of = |needle: &str| -> Vec<usize> {
        let needle = squash(needle);
        (0..pages)
            .filter(|&k| page_texts[k].contains(&needle))
            .map(|k| k + 1)
            .collect()
    };
    // What each figure's top and bottom say, from the page itself (wide drawings, as
    // printed).
    let p = probe(&browser, &dir, &page, 1280);
    let figures = p["figures"].as_array().unwrap();
    assert!(figures.len() >= 3, "figures: {figures:?}");
    for f in figures {
        let caption = squash(f["caption"].as_str().unwrap());
        let words: Vec<&str> = caption.split(' ').collect();
        let first = words[..words.len().min(8)].join(" ");
        let last = words[words.len().saturating_sub(4)..].join(" ");
        let mut seen = Vec::new();
        for needle in f["titles"]
            .as_array()
            .unwrap()
            .iter()
            .map(|t| t.as_str().unwrap().to_string())
            .chain([first, last])
        {
            let on = page_of(&needle);
            assert_eq!(on.len(), 1, "{}: {needle:?} is on pages {on:?}", f["id"]);
            seen.push((needle, on[0]));
        }
        assert!(
            seen.iter().all(|s| s.1 == seen[0].1),
            "{} is split across pages: {seen:?}",
            f["id"]
        );
        eprintln!("{} on page {} of {pages}", f["id"], seen[0].1);
    }
    // Every page holds something: rendered at 20 dpi, no page is all white.
    let prefix = dir.join("page");
    let run = Command::new(pdftoppm)
        .args(["-r", "20", "-png"])
        .arg(&pdf)
        .arg(&prefix)
        .output()
        .unwrap();
    assert!(run.status.success(), "pdftoppm failed");
    let mut rendered = 0;
    for entry in std::fs::read_dir(&dir).unwrap().flatten() {
        let name = entry.file_name().to_string_lossy().into_owned();
        if name.starts_with("page") && name.ends_with(".png") {
            let img = Image::read(&entry.path());
            assert!(img.pixels.iter().any(|&v| v < 200), "{name} is blank");
            rendered += 1;
        }
    }
    assert_eq!(rendered, pages);
    std::fs::remove_dir_all(&dir).ok();
}
