//! Reproduction of the paper's 1014×1014 image through each display model fitted to the
//! dispread-format fixture (rows in parallel over the machine's cores).

use std::path::Path;

use criterion::{criterion_group, criterion_main, Criterion};
use metamer::display::gamut::GamutMapping;
use metamer::display::reproduce::reproduce_image;
use metamer::display::{fit_profile, read_measurements, ModelKind};
use metamer::image::XyzImage;

fn bench(c: &mut Criterion) {
    let fixture = Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/dispread_analytic.ti3"
    ));
    let patches = read_measurements(fixture).expect("fixture reads");
    let n = 1014;
    let mut group = c.benchmark_group("reproduce 1014x1014");
    group.sample_size(10);
    for kind in ModelKind::ALL {
        let profile = fit_profile(kind, &patches, None).expect("fixture fits");
        // A smooth sweep of the display's gamut, every pixel a displayable colour.
        let pixels = (0..n * n)
            .map(|i| {
                let (x, y) = (
                    (i % n) as f64 / (n - 1) as f64,
                    (i / n) as f64 / (n - 1) as f64,
                );
                profile
                    .forward([x, y, (x + y) / 2.0])
                    .to_array()
                    .map(|v| v as f32)
            })
            .collect();
        let image = XyzImage {
            width: n,
            height: n,
            pixels,
        };
        group.bench_function(kind.name(), |b| {
            b.iter(|| {
                std::hint::black_box(reproduce_image(&profile, &image, false, GamutMapping::Clip))
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
