//! A whole simulated flight, flight log included: `shoot` of a generated one-hour script at
//! 100 Hz (720 shots of 5 s, one- and two-actor framings, walking actors), on the embedded
//! simulator with every effect on, the LQG servo, and the MCAP flight log written to a
//! temporary file. Also the same flight without the log, to split the cost.
//!
//! Run: `cargo bench -p dronecine-runtime --bench flight`.

use std::fmt::Write as _;
use std::time::{Duration, Instant};

use criterion::{criterion_group, criterion_main, Criterion};
use dronecine_compiler::profile::Profile;
use dronecine_grammar::Script;
use dronecine_runtime::flight::{NoObserver, NullSink};
use dronecine_runtime::log::{FlightLogWriter, LogScene, LogThread};
use dronecine_runtime::record::{ControllerSetup, FlightHeader};
use dronecine_runtime::session::{fly_simulated, SimFlight};
use dronecine_runtime::sim::SimConfig;

/// `minutes` of shots: blocks of one-actor and two-actor holds while the actors walk.
fn generated_script(minutes: usize) -> String {
    let mut s = String::from(
        "stage 10m x 8m x 3m\ndrone ardrone2\n\
         actor A height 1.80m at (-1, 0) facing 0deg\n\
         actor B height 1.80m at (1, 0) facing 180deg\n",
    );
    let shots = minutes * 12;
    for k in 0..shots / 4 {
        let t = k as f64 * 20.0;
        let x = if k % 2 == 0 { 0.5 } else { -0.5 };
        let _ = writeln!(s, "at {t}s A walks to ({}, 0.5) over 6s", x - 1.0);
        let _ = writeln!(s, "at {}s B walks to ({}, -0.5) over 6s", t + 10.0, x + 1.0);
    }
    for k in 0..shots {
        let line = match k % 4 {
            0 => "MS on A and B for 5s",
            1 => "then hold for 5s",
            2 => "then hold for 5s",
            _ => "then hold for 5s",
        };
        let _ = writeln!(s, "{line}");
    }
    s
}

fn parse(text: &str) -> Script {
    let opts = dronecine_grammar::Options {
        known_drones: dronecine_compiler::profile::BUILTIN_NAMES,
        base_dir: None,
    };
    let checked = dronecine_grammar::check(text, &opts);
    assert!(!checked.has_errors(), "{:?}", checked.diagnostics);
    checked.script.unwrap()
}

fn fly(text: &str, script: &Script, log: Option<&std::path::Path>) {
    let scene = script.scene.as_ref().unwrap();
    let profile = Profile::builtin("ardrone2").unwrap();
    let mut sim = SimConfig::new(1);
    sim.effects.battery = false;
    let flight = SimFlight {
        script,
        source: text,
        scene,
        profile: &profile,
        rate_hz: 100.0,
        controller: ControllerSetup {
            kind: "lqg".into(),
            paper_prefilter: false,
            per_tick_solve: false,
        },
        plant: None,
        sim,
        realtime: false,
        interrupts: None,
    };
    let report = match log {
        None => fly_simulated(&flight, &mut NullSink, &mut NoObserver).unwrap(),
        Some(path) => {
            let names: Vec<String> = scene.actors.iter().map(|a| a.name.clone()).collect();
            let heights: Vec<f64> = scene.actors.iter().map(|a| a.height_m).collect();
            let header = FlightHeader {
                script_name: "bench.psl".into(),
                script_text: text.into(),
                profile_name: profile.name.clone(),
                profile_toml: String::new(),
                profile: profile.clone(),
                controller: flight.controller.clone(),
                backend: "sim".into(),
                seed: Some(1),
                rate_hz: 100.0,
                actor_names: names.clone(),
                dronecine_version: "bench".into(),
            };
            let lens = *dronecine_compiler::director::Director::new(script, scene, &profile).lens();
            let writer = FlightLogWriter::create(
                path,
                &header,
                &LogScene {
                    stage: scene.stage,
                    lens,
                    actor_names: &names,
                    actor_heights_m: &heights,
                },
            )
            .unwrap();
            // As `shoot` writes it: on a thread of its own.
            let mut sink = LogThread::spawn(writer, 100.0).unwrap();
            let r = fly_simulated(&flight, &mut sink, &mut NoObserver).unwrap();
            sink.finish().unwrap();
            r
        }
    };
    assert!(report.completed);
}

fn bench(c: &mut Criterion) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("flight.mcap");
    let mut g = c.benchmark_group("shoot");
    g.sample_size(10);
    for minutes in [10usize, 60] {
        let text = generated_script(minutes);
        let script = parse(&text);
        g.bench_function(format!("{minutes} min flight, no log"), |b| {
            b.iter(|| fly(&text, &script, None))
        });
        // Each flight writes a new file, as `shoot` does (its default log name carries the
        // time): the previous flight's file is removed before the clock starts. Truncating it
        // inside the timed run instead (an hour's 400 MB of page cache to drop, some of it
        // still being written back) added about 0.1 s that no flight pays.
        g.bench_function(format!("{minutes} min flight with its log"), |b| {
            b.iter_custom(|iters| {
                let mut total = Duration::ZERO;
                for _ in 0..iters {
                    let _ = std::fs::remove_file(&path);
                    let start = Instant::now();
                    fly(&text, &script, Some(&path));
                    total += start.elapsed();
                }
                total
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
