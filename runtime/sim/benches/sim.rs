//! One hour of simulated flight at 100 Hz with every effect on: the flight loop's pattern per
//! tick (sleep to the tick, poll the mocap, send a command). Criterion reports the time per
//! hour; divide by 360 000 for the time per tick (the throughput line gives ticks per second).
//!
//! Two measurements of the same work: wall-clock time (criterion's default), and the thread's
//! CPU time (Linux `/proc/thread-self/schedstat`; wall time elsewhere), which is what to read on
//! a machine shared with other jobs.

use std::time::{Duration, Instant};

use criterion::{black_box, criterion_group, criterion_main, Criterion, Throughput};
use dronecine_backend::frames::Command;
use dronecine_backend::{Clock, Drone, Mocap, MocapFrame};
use dronecine_grammar::script::Scene;
use dronecine_profile::Profile;
use dronecine_sim::{SimConfig, Simulator};

const SCENE: &str = "stage 8m x 6m x 3m\n\
    actor A height 1.80m at (-1, 0) facing 0deg\n\
    actor B height 1.65m at (1, 0) facing 180deg\n\
    at 2s A walks to (-0.5, 1.5) over 6s\n\
    at 2s B walks to (1.5, 1) over 6s\n\
    at 9s B turns to 90deg over 1.5s\n\
    at 10s A walks to (0, -1) over 5s\n\
    MS on A and B for 16s\n";

const TICKS: u64 = 360_000;

/// Nanoseconds this thread has run on a CPU (Linux), `None` elsewhere.
fn thread_cpu_ns() -> Option<u64> {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()?
        .split_whitespace()
        .next()?
        .parse()
        .ok()
}

fn fly_one_hour(
    cfg: &SimConfig,
    profile: &Profile,
    scene: &Scene,
    commands: &[Command],
) -> dronecine_sim::Truth {
    let sim = Simulator::new(cfg, profile, scene).unwrap();
    let (mut drone, mut mocap, mut clock) = (sim.drone(), sim.mocap(), sim.clock());
    let mut frame = MocapFrame::default();
    drone.take_off().unwrap();
    let mut seen = 0u64;
    for k in 1..=TICKS {
        clock.sleep_until(k as f64 * 0.01);
        seen += mocap.poll(&mut frame).unwrap() as u64;
        drone
            .send(&commands[(k % commands.len() as u64) as usize])
            .unwrap();
    }
    assert_eq!(seen, TICKS);
    sim.truth()
}

fn one_hour(c: &mut Criterion) {
    let checked = dronecine_grammar::check(SCENE, &dronecine_grammar::Options::default());
    let scene = checked.script.unwrap().scene.unwrap();
    let profile = Profile::builtin("ardrone2").unwrap();
    // Every effect on; the battery drains slowly enough to last the hour.
    let cfg = SimConfig {
        battery_drain_percent_per_min: 1.0,
        ..SimConfig::new(1)
    };
    // A varied command pattern, computed once (the loop measures the simulator only).
    let commands: Vec<Command> = (0..1000)
        .map(|i| {
            let s = i as f64 * 0.0063;
            Command {
                roll_rad: 0.08 * (3.0 * s).sin(),
                pitch_rad: 0.08 * (2.0 * s).cos(),
                yaw_rate_radps: 0.3 * s.sin(),
                vz_mps: 0.1 * (5.0 * s).sin(),
            }
        })
        .collect();
    let mut group = c.benchmark_group("sim");
    group.sample_size(10);
    group.throughput(Throughput::Elements(TICKS));
    group.bench_function("one_hour_100hz_all_effects", |b| {
        b.iter(|| fly_one_hour(&cfg, &profile, &scene, &commands))
    });
    group.bench_function("one_hour_100hz_all_effects_cpu_time", |b| {
        b.iter_custom(|iters| {
            let (cpu0, wall0) = (thread_cpu_ns(), Instant::now());
            for _ in 0..iters {
                black_box(fly_one_hour(&cfg, &profile, &scene, &commands));
            }
            match (cpu0, thread_cpu_ns()) {
                (Some(a), Some(b)) => Duration::from_nanos(b - a),
                _ => wall0.elapsed(),
            }
        })
    });
    group.finish();
}

criterion_group!(benches, one_hour);
criterion_main!(benches);
