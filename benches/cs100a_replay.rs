//! Driver overhead per CS-100A reading on replay: discarding stale input, encoding `MES`,
//! matching it against the transcript, framing the 28-byte reply at CR LF, parsing it and
//! building the `Reading` (Yxy → XYZ). The transcript is parsed before timing starts. The
//! instrument itself needs ≈100 ms per FAST reading plus ≈64 ms of wire time.

use criterion::{criterion_group, criterion_main, BatchSize, Criterion, Throughput};
use metamer_drivers::cs100a::Cs100a;
use metamer_drivers::link::replay::{ReplaySerial, Transcript};
use metamer_drivers::{Instrument, Request};
use metamer_protocols::cs100a::parse_reply;

const READINGS: usize = 100;

fn transcript() -> Transcript {
    let mut text = String::from(
        r#"{"format":"metamer-transcript/1","instrument":"cs100a","transport":"serial","settings":{"baud":4800,"data_bits":7,"parity":"even","stop_bits":2},"origin":"synthesized from the protocol documentation","description":"benchmark"}"#,
    );
    text.push('\n');
    text.push_str("{\"dir\":\"host\",\"data\":\"MDS,04\\r\\n\"}\n{\"dir\":\"device\",\"data\":\"OK00\\r\\n\"}\n");
    text.push_str("{\"dir\":\"host\",\"data\":\"MDS,06\\r\\n\"}\n{\"dir\":\"device\",\"data\":\"OK00\\r\\n\"}\n");
    for _ in 0..READINGS {
        text.push_str("{\"dir\":\"host\",\"data\":\"MES\\r\\n\"}\n");
        text.push_str("{\"dir\":\"device\",\"data\":\"OK00,  123.4, .3127, .3290\\r\\n\"}\n");
    }
    Transcript::parse("bench.jsonl", &text).expect("benchmark transcript parses")
}

fn bench(c: &mut Criterion) {
    let t = transcript();
    let mut group = c.benchmark_group("cs100a");
    group.throughput(Throughput::Elements(READINGS as u64));
    group.bench_function("replayed reading (framing + parsing + Reading)", |b| {
        b.iter_batched(
            || {
                let mut meter = Cs100a::new(ReplaySerial::new(t.clone()).unwrap());
                meter.connect().unwrap();
                meter.set_speed(metamer_drivers::Speed::Fast).unwrap();
                meter
            },
            |mut meter| {
                for _ in 0..READINGS {
                    std::hint::black_box(meter.measure(&Request::default()).unwrap());
                }
                meter
            },
            BatchSize::SmallInput,
        )
    });
    group.throughput(Throughput::Elements(1));
    group.bench_function("parse_reply alone", |b| {
        b.iter(|| parse_reply(std::hint::black_box(b"OK00,  123.4, .3127, .3290\r\n")).unwrap())
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
