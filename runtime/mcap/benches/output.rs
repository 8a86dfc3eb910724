//! The writers on a one-hour reference at 100 Hz (360,000 samples, 2 actors): MCAP with each
//! chunk compression (Zstandard at level 1), and CSV. Prints each file's size once.
//!
//! Run: `cargo bench -p dronecine-mcap --bench output -- --warm-up-time 1`

use std::f64::consts::PI;
use std::path::Path;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use dronecine_compiler::camera::Lens;
use dronecine_compiler::reference::{ActorPose, Sample};
use dronecine_grammar::script::Stage;
use dronecine_mcap::output::{Compression, CsvWriter, McapOptions, McapWriter, RunInfo};

const RATE_HZ: f64 = 100.0;
const SAMPLES: usize = 360_000;

/// A smooth, full-precision trajectory (an orbit with a vertical wobble) and two actors
/// walking circles, changing shot every 10 s.
fn synthetic() -> (Vec<Sample>, Vec<[ActorPose; 2]>) {
    let mut samples = Vec::with_capacity(SAMPLES);
    let mut actors = Vec::with_capacity(SAMPLES);
    for i in 0..SAMPLES {
        let t = i as f64 / RATE_HZ;
        let w = 0.21;
        let (s, c) = (w * t).sin_cos();
        let z = 1.5 + 0.3 * (0.37 * t).sin();
        samples.push(Sample {
            t_s: t,
            position_m: [3.0 * c, 2.0 * s, z],
            velocity_mps: [-3.0 * w * s, 2.0 * w * c, 0.3 * 0.37 * (0.37 * t).cos()],
            acceleration_mps2: [
                -3.0 * w * w * c,
                -2.0 * w * w * s,
                -0.3 * 0.37 * 0.37 * (0.37 * t).sin(),
            ],
            heading_rad: ((w * t + PI) % (2.0 * PI)) - PI,
            heading_rate_radps: w,
            camera_pitch_rad: -0.2 + 0.05 * (0.1 * t).sin(),
            shot: (t / 10.0) as usize,
        });
        let actor = |phase: f64, h: f64| {
            let (s, c) = (0.1 * t + phase).sin_cos();
            ActorPose {
                position_m: [1.2 * c, 1.2 * s, 0.0],
                velocity_mps: [-0.12 * s, 0.12 * c, 0.0],
                facing_rad: ((0.1 * t + phase + PI / 2.0 + PI) % (2.0 * PI)) - PI,
                facing_rate_radps: 0.1,
                height_m: h,
            }
        };
        actors.push([actor(0.0, 1.8), actor(PI, 1.65)]);
    }
    (samples, actors)
}

fn write_mcap(
    path: &Path,
    info: &RunInfo,
    options: McapOptions,
    samples: &[Sample],
    actors: &[[ActorPose; 2]],
) {
    let mut w = McapWriter::create_with(path, info, options).unwrap();
    for (s, a) in samples.iter().zip(actors) {
        w.write(s, a).unwrap();
    }
    w.finish().unwrap();
}

fn bench(c: &mut Criterion) {
    let (samples, actors) = synthetic();
    let names = vec!["A".to_string(), "B".to_string()];
    let script = "stage 8m x 6m x 3m\nlens 84deg\n".repeat(50);
    let info = RunInfo {
        script_name: "bench.psl",
        script_text: &script,
        profile_name: "ardrone2",
        rate_hz: RATE_HZ,
        lens: Lens::new(84f64.to_radians(), 16.0 / 9.0),
        stage: Stage {
            size_m: [8.0, 6.0, 3.0],
        },
        actor_names: &names,
    };
    let dir = tempfile::tempdir().unwrap();

    let mut group = c.benchmark_group("output_1h_100hz");
    group.sample_size(10);
    group.throughput(Throughput::Elements(SAMPLES as u64));
    for (label, compression) in [
        ("mcap_none", Compression::None),
        ("mcap_lz4", Compression::Lz4),
        ("mcap_zstd", Compression::Zstd),
    ] {
        let path = dir.path().join(format!("{label}.mcap"));
        let options = McapOptions {
            compression,
            ..McapOptions::default()
        };
        write_mcap(&path, &info, options, &samples, &actors);
        let size = std::fs::metadata(&path).unwrap().len();
        eprintln!("{label}: {:.1} MB", size as f64 / 1e6);
        group.bench_function(label, |b| {
            b.iter(|| write_mcap(&path, &info, options, &samples, &actors))
        });
    }
    let path = dir.path().join("reference.csv");
    let write_csv = || {
        let mut w = CsvWriter::create(&path).unwrap();
        for s in &samples {
            w.write(s).unwrap();
        }
        w.finish().unwrap();
    };
    write_csv();
    let size = std::fs::metadata(&path).unwrap().len();
    eprintln!("csv: {:.1} MB", size as f64 / 1e6);
    group.bench_function("csv", |b| b.iter(write_csv));
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
