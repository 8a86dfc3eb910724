//! The flight log's cost: writing ticks (per tick, and one hour = 360,000 ticks at 100 Hz with
//! two actors, a key frame at each chunk's start), with and without LZ4 chunks, and reading
//! the hour back; and what each group of
//! plot topics (`/tf`, `/measurement`, the 10 Hz plots; CDR) adds to the hour
//! (`log_hour_without`: the hour with that group's rate set to nothing, so the difference with
//! `log_hour/write_none` is the group's cost).
//!
//! Run: `cargo bench -p dronecine-mcap --bench log`.

use std::hint::black_box;
use std::path::Path;
use std::time::{Duration, Instant};

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use dronecine_backend::frames::Command;
use dronecine_backend::{BodyPose, FlightState, MocapFrame};
use dronecine_compiler::camera::Lens;
use dronecine_compiler::reference::{ActorPose, Sample};
use dronecine_grammar::script::Stage;
use dronecine_mcap::log::{FlightLog, FlightLogWriter, LogCompression, LogOptions, LogScene};
use dronecine_mcap::record::{reference_of, FlightHeader, FramingRecord, Phase, TickRecord};
use dronecine_servo::control::{Controller, Estimate, Measurement, TickInput, TickOutput};
use dronecine_servo::lqg::{LqgServo, ServoOptions};
use dronecine_servo::setup::ControllerSetup;

const RATE_HZ: f64 = 100.0;
const HOUR_TICKS: usize = 360_000;
/// Distinct ticks cycled through (one minute): realistic full-precision values.
const DISTINCT: usize = 6_000;

struct Tick {
    sample: Sample,
    input: TickInput,
    output: TickOutput,
    mocap: MocapFrame,
    actors: Vec<ActorPose>,
    framing: Vec<FramingRecord>,
}

fn ticks() -> Vec<Tick> {
    (0..DISTINCT)
        .map(|k| {
            let t = k as f64 / RATE_HZ;
            let (s, c) = (0.21 * t).sin_cos();
            let sample = Sample {
                t_s: t,
                position_m: [2.5 * c, 2.5 * s, 1.5 + 0.1 * (0.5 * t).sin()],
                velocity_mps: [-0.525 * s, 0.525 * c, 0.05 * (0.5 * t).cos()],
                acceleration_mps2: [-0.11025 * c, -0.11025 * s, -0.025 * (0.5 * t).sin()],
                heading_rad: (0.21 * t + 3.0).sin() * 3.0,
                heading_rate_radps: 0.21,
                camera_pitch_rad: -0.2,
                shot: k / 1000,
            };
            let actors: Vec<ActorPose> = (0..2)
                .map(|i| ActorPose {
                    position_m: [0.5 * i as f64 + 0.01 * s, -0.3 + 0.01 * c, 0.0],
                    velocity_mps: [0.0021 * c, -0.0021 * s, 0.0],
                    facing_rad: 0.7 + 0.1 * s,
                    facing_rate_radps: 0.0,
                    height_m: 1.7 + 0.1 * i as f64,
                })
                .collect();
            let noise = |j: f64| 1e-3 * (t * 17.0 + j).sin();
            let measurement = Measurement {
                position_m: [
                    sample.position_m[0] + noise(1.0),
                    sample.position_m[1] + noise(2.0),
                    sample.position_m[2] + noise(3.0),
                ],
                heading_rad: sample.heading_rad + noise(4.0),
            };
            let output = TickOutput {
                command: Command {
                    roll_rad: 0.05 * s + noise(5.0),
                    pitch_rad: -0.04 * c + noise(6.0),
                    yaw_rate_radps: -0.21 + noise(7.0),
                    vz_mps: 0.05 * (0.5 * t).cos() + noise(8.0),
                },
                estimate: Estimate {
                    position_m: [
                        sample.position_m[0] + noise(9.0),
                        sample.position_m[1] + noise(10.0),
                        sample.position_m[2] + noise(11.0),
                    ],
                    velocity_mps: [
                        sample.velocity_mps[0] + noise(12.0),
                        sample.velocity_mps[1] + noise(13.0),
                        sample.velocity_mps[2] + noise(14.0),
                    ],
                    heading_rad: sample.heading_rad + noise(15.0),
                },
                saturated: false,
            };
            Tick {
                input: TickInput {
                    t_s: t,
                    dt_s: 0.01 + noise(16.0) * 1e-3,
                    measurement: Some(measurement),
                    reference: reference_of(&sample),
                },
                sample,
                output,
                mocap: MocapFrame {
                    t_s: t - 0.004,
                    received_s: t - 0.002,
                    frame: k as u64,
                    drone: Some(BodyPose {
                        position_m: measurement.position_m,
                        heading_rad: measurement.heading_rad,
                    }),
                    actors: actors
                        .iter()
                        .map(|a| {
                            Some(BodyPose {
                                position_m: a.position_m,
                                heading_rad: a.facing_rad,
                            })
                        })
                        .collect(),
                },
                framing: (0..2)
                    .map(|i| FramingRecord {
                        actor: i,
                        screen: Some([0.33 * s + noise(17.0), -0.1 + noise(18.0)]),
                        requested: Some([0.33, -0.1]),
                    })
                    .collect(),
                actors,
            }
        })
        .collect()
}

fn header(names: &[String]) -> FlightHeader {
    FlightHeader {
        script_name: "bench.psl".into(),
        script_text: "stage 8m x 6m x 3m\n".into(),
        profile_name: "ardrone2".into(),
        profile_toml: String::new(),
        profile: dronecine_profile::Profile::builtin("ardrone2").unwrap(),
        controller: ControllerSetup::new("lqg"),
        backend: "sim".into(),
        seed: Some(1),
        sim_effects_off: Some(Vec::new()),
        rate_hz: RATE_HZ,
        actor_names: names.to_vec(),
        dronecine_version: "bench".into(),
    }
}

/// This thread's CPU time (`/proc/thread-self/schedstat`, Linux), else `None`. On a machine
/// shared with other jobs wall time counts the time they hold the core; CPU time is what the
/// flight loop's budget is about.
fn cpu_time() -> Option<Duration> {
    let stat = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    let ns: u64 = stat.split_whitespace().next()?.parse().ok()?;
    Some(Duration::from_nanos(ns))
}

/// The CPU time (wall time if unavailable) of `f`.
fn cpu_of<T>(f: impl FnOnce() -> T) -> Duration {
    let (start, start_cpu) = (Instant::now(), cpu_time());
    black_box(f());
    match (start_cpu, cpu_time()) {
        (Some(a), Some(b)) => b.saturating_sub(a),
        _ => start.elapsed(),
    }
}

/// Writes `n` ticks (cycling through `ticks`, the clock running on) and finishes the log;
/// returns the CPU time (wall time if unavailable) spent in `write_tick` alone.
fn write(path: &Path, ticks: &[Tick], n: usize, compression: LogCompression) -> Duration {
    let options = LogOptions {
        compression,
        ..LogOptions::default()
    };
    write_with(path, ticks, n, options)
}

/// [`write`] with any options.
fn write_with(path: &Path, ticks: &[Tick], n: usize, options: LogOptions) -> Duration {
    let names = vec!["Ann".to_string(), "Bo".to_string()];
    let scene = LogScene {
        stage: Stage {
            size_m: [8.0, 6.0, 3.0],
        },
        lens: Lens::new(84f64.to_radians(), 16.0 / 9.0),
        actor_names: &names,
        actor_heights_m: &[1.7, 1.8],
    };
    let mut log = FlightLogWriter::create_with(path, &header(&names), &scene, options).unwrap();
    // The controller's state, for the key frame at each chunk's start (as the flight loop
    // gives it when the log asks).
    let profile = dronecine_profile::Profile::builtin("ardrone2").unwrap();
    let state = LqgServo::new(&profile, ServoOptions::default())
        .unwrap()
        .state();
    let (start, start_cpu) = (Instant::now(), cpu_time());
    for k in 0..n {
        let tick = &ticks[k % ticks.len()];
        let mut input = tick.input;
        input.t_s = k as f64 / RATE_HZ;
        let record = TickRecord {
            phase: Phase::Shots,
            shot: Some(tick.sample.shot),
            sample: &tick.sample,
            input,
            output: Ok(tick.output),
            command_sent: tick.output.command,
            mocap: Some(&tick.mocap),
            actors: &tick.actors,
            framing: &tick.framing,
            drone_state: FlightState::Flying,
            latency_s: Some(0.002),
            gimbal: None,
        };
        log.write_tick(black_box(&record)).unwrap();
        if log.wants_key_frame() {
            log.write_key_frame(black_box(&state));
        }
    }
    let ticking = match (start_cpu, cpu_time()) {
        (Some(a), Some(b)) => b.saturating_sub(a),
        _ => start.elapsed(),
    };
    log.finish().unwrap();
    ticking
}

fn bench(c: &mut Criterion) {
    let ticks = ticks();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("flight.mcap");

    // The ticks alone (the file's creation and finish excluded): the per-tick cost.
    let mut group = c.benchmark_group("log_write_ticks");
    group.throughput(Throughput::Elements(DISTINCT as u64));
    for (name, compression) in [("none", LogCompression::None), ("lz4", LogCompression::Lz4)] {
        group.bench_function(BenchmarkId::from_parameter(name), |b| {
            b.iter_custom(|iters| {
                (0..iters)
                    .map(|_| write(&path, &ticks, DISTINCT, compression))
                    .sum()
            })
        });
        // Only when this benchmark ran (a filter may have skipped it).
        if let Ok(m) = std::fs::metadata(&path) {
            eprintln!(
                "{name}: {:.0} bytes per tick",
                m.len() as f64 / DISTINCT as f64
            );
            let _ = std::fs::remove_file(&path);
        }
    }
    group.finish();

    let mut group = c.benchmark_group("log_hour");
    group.sample_size(10);
    group.throughput(Throughput::Elements(HOUR_TICKS as u64));
    // Everything: create, an hour of ticks, finish (with its fsync).
    group.bench_function("write_none", |b| {
        b.iter_custom(|iters| {
            (0..iters)
                .map(|_| cpu_of(|| write(&path, &ticks, HOUR_TICKS, LogCompression::None)))
                .sum()
        })
    });
    if let Ok(m) = std::fs::metadata(&path) {
        eprintln!("hour, none: {:.1} MB", m.len() as f64 / 1e6);
    }
    if !path.exists() {
        // `read` run alone: the hour to read.
        write(&path, &ticks, HOUR_TICKS, LogCompression::None);
    }
    group.bench_function("read", |b| {
        b.iter_custom(|iters| {
            (0..iters)
                .map(|_| {
                    cpu_of(|| {
                        let log = FlightLog::open(&path).unwrap();
                        assert_eq!(log.ticks.len(), HOUR_TICKS);
                    })
                })
                .sum()
        })
    });
    group.finish();

    // What each group of plot topics costs: the hour with that group off (a rate of one
    // message in a thousand hours: the first tick's only).
    let mut group = c.benchmark_group("log_hour_without");
    group.sample_size(10);
    group.throughput(Throughput::Elements(HOUR_TICKS as u64));
    const NEVER_HZ: f64 = 1.0 / 3.6e6;
    let defaults = LogOptions::default();
    let variants = [
        (
            "tf",
            LogOptions {
                tf_hz: NEVER_HZ,
                ..defaults
            },
        ),
        (
            "measurement",
            LogOptions {
                measurement_hz: NEVER_HZ,
                ..defaults
            },
        ),
        (
            "plots",
            LogOptions {
                plot_hz: NEVER_HZ,
                ..defaults
            },
        ),
        (
            "all_plots",
            LogOptions {
                tf_hz: NEVER_HZ,
                measurement_hz: NEVER_HZ,
                plot_hz: NEVER_HZ,
                ..defaults
            },
        ),
    ];
    for (name, options) in variants {
        group.bench_function(BenchmarkId::from_parameter(name), |b| {
            b.iter_custom(|iters| {
                (0..iters)
                    .map(|_| cpu_of(|| write_with(&path, &ticks, HOUR_TICKS, options)))
                    .sum()
            })
        });
        if let Ok(m) = std::fs::metadata(&path) {
            eprintln!("hour without {name}: {:.1} MB", m.len() as f64 / 1e6);
            let _ = std::fs::remove_file(&path);
        }
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
