//! Driver overhead per i1Pro emissive reading on replay: the two control transfers (set
//! parameters, trigger) and the bulk read matched against the transcript, parsing 3 × 256
//! bytes of counts, the raw → spectrum pipeline (linearisation, interpolated dark,
//! averaging, resampling 128 cells to 36 bands) and XYZ through the colour core. The
//! transcript is recorded from the simulated i1Pro and parsed before timing starts; the
//! open and the dark calibration are outside the timed part. The instrument itself
//! integrates 3 × 0.25 s for each of these readings.

use std::sync::Arc;

use criterion::{criterion_group, criterion_main, BatchSize, Criterion, Throughput};
use metamer_drivers::i1pro::emulator::{default_light, EmulatorConfig};
use metamer_drivers::i1pro::open::sim_with;
use metamer_drivers::i1pro::{I1Pro, ManualClock};
use metamer_drivers::link::replay::Transcript;
use metamer_drivers::link::usb::ReplayUsb;
use metamer_drivers::{
    CalibrationCondition, Instrument, MeasureMode, OpenOptions, Request, SharedWorld, View, World,
};

const READINGS: usize = 20;

/// Records open, dark calibration and READINGS readings at a fixed 0.25 s.
fn transcript() -> Transcript {
    let path =
        std::env::temp_dir().join(format!("metamer-i1pro-bench-{}.jsonl", std::process::id()));
    let _ = std::fs::remove_file(&path);
    let world = Arc::new(SharedWorld::new(View::WhiteTile));
    let options = OpenOptions {
        stimulus: None,
        record: Some(path.clone()),
    };
    let config = EmulatorConfig {
        time_scale: 0.0,
        ..EmulatorConfig::default()
    };
    let mut m = sim_with(
        world.clone() as Arc<dyn World>,
        config,
        &options,
        Arc::new(ManualClock::new()),
    )
    .unwrap();
    m.calibrate(MeasureMode::Emissive, &CalibrationCondition::OnWhiteTile)
        .unwrap();
    m.set_option("integration_s", "0.25").unwrap();
    world.set(View::radiance(default_light()).unwrap());
    for _ in 0..READINGS {
        m.measure(&Request::default()).unwrap();
    }
    drop(m);
    let t = Transcript::load(&path).unwrap();
    let _ = std::fs::remove_file(&path);
    t
}

fn bench(c: &mut Criterion) {
    let t = transcript();
    let mut group = c.benchmark_group("i1pro");
    group.throughput(Throughput::Elements(READINGS as u64));
    group.bench_function(
        "replayed emissive reading (transfers + pipeline + XYZ)",
        |b| {
            b.iter_batched(
                || {
                    let link = ReplayUsb::new(t.clone()).unwrap();
                    let mut m = I1Pro::open(link, Arc::new(ManualClock::new())).unwrap();
                    m.calibrate(MeasureMode::Emissive, &CalibrationCondition::OnWhiteTile)
                        .unwrap();
                    m.set_option("integration_s", "0.25").unwrap();
                    m
                },
                |mut m| {
                    for _ in 0..READINGS {
                        std::hint::black_box(m.measure(&Request::default()).unwrap());
                    }
                    m
                },
                BatchSize::SmallInput,
            )
        },
    );
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
