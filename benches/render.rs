//! The path tracer's inner loop: one meter sample (a path from the pinhole into the 1°
//! cone at patch 19, all its bounces and next-event estimates) per strategy; and the
//! radiosity solver's whole run (`render spots --method radiosity --target-de 0.1`).

use std::path::Path;

use criterion::{criterion_group, criterion_main, Criterion};
use metamer::render::convergence::strategies;
use metamer::render::radiosity::{render_spots_radiosity, RadiosityOptions};
use metamer::render::spectral::Rng;
use metamer::render::spot::{cone_direction, patch_aim};
use metamer::render::{Scene, Tracer};

fn bench(c: &mut Criterion) {
    let scene = Scene::load(Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/data/scenes/validation-box.json"
    )))
    .expect("bundled scene loads");
    let aim = patch_aim(&scene, 19).expect("patch 19 exists");
    let cos_max = (aim.acceptance_deg.to_radians() / 2.0).cos();
    for (name, strategy) in strategies() {
        let tracer = Tracer::new(&scene, strategy);
        let mut i = 0u64;
        c.bench_function(&format!("meter sample: {name}"), |b| {
            b.iter(|| {
                i += 1;
                let mut rng = Rng::new(1, 0, i);
                let d = cone_direction(aim.axis, cos_max, rng.next_f64(), rng.next_f64());
                std::hint::black_box(tracer.xyz_sample(aim.origin, d, &mut rng))
            })
        });
    }
}

fn radiosity(c: &mut Criterion) {
    let scene = Scene::load(Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/data/scenes/validation-box.json"
    )))
    .expect("bundled scene loads");
    let opts = RadiosityOptions {
        target_de: 0.1,
        ..RadiosityOptions::default()
    };
    let mut group = c.benchmark_group("radiosity");
    group.sample_size(10);
    group.bench_function("24 spots to ΔE*ab bound 0.1", |b| {
        b.iter(|| {
            let r = render_spots_radiosity(&scene, &opts, &|_| {}).expect("box qualifies");
            std::hint::black_box(r.patches[0].xyz)
        })
    });
    group.finish();
}

criterion_group!(benches, bench, radiosity);
criterion_main!(benches);
