//! A whole simulated flight, flight log included: `shoot` of a generated one-hour script at
//! 100 Hz (720 shots of 5 s, one- and two-actor framings, walking actors), on the embedded
//! simulator with every effect on, the LQG servo, and the MCAP flight log written to a
//! temporary file with `shoot`'s options ([`LogOptions::shoot`]: handed to the OS, not forced
//! to the disk, as `shoot` writes a simulated flight's). Also the same flight without the log,
//! to split the cost, the hour with the director stepped ahead of the loop on a thread of its
//! own (`SimConfig::actors_ahead`), and that hour with its log forced to the disk as it is
//! written (`shoot --sync-log`, as a real flight's is).
//!
//! Each group also prints the CPU time a flight took, all threads together (the loop, the log's
//! writer and syncer): on a machine with two cores, the flight with its log cannot take less
//! wall time than half of it.
//!
//! Run: `cargo bench -p dronecine-runtime --bench flight`.

use std::fmt::Write as _;
use std::time::{Duration, Instant};

use criterion::{criterion_group, criterion_main, Criterion};
use dronecine_flight::NoObserver;
use dronecine_grammar::Script;
use dronecine_mcap::log::{FlightLogWriter, LogOptions, LogScene, LogThread};
use dronecine_mcap::record::FlightHeader;
use dronecine_mcap::record::NullSink;
use dronecine_profile::Profile;
use dronecine_runtime::{fly_simulated, SimFlight};
use dronecine_servo::setup::ControllerSetup;
use dronecine_sim::SimConfig;

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
        known_drones: dronecine_profile::BUILTIN_NAMES,
        base_dir: None,
    };
    let checked = dronecine_grammar::check(text, &opts);
    assert!(!checked.has_errors(), "{:?}", checked.diagnostics);
    checked.script.unwrap()
}

/// Flies the script; with `log`, writes it there as `shoot` does, forced to the disk as it is
/// written if `durable`.
fn fly(text: &str, script: &Script, log: Option<(&std::path::Path, bool)>, ahead: bool) {
    let scene = script.scene.as_ref().unwrap();
    let profile = Profile::builtin("ardrone2").unwrap();
    let mut sim = SimConfig::new(1);
    sim.effects.battery = false;
    sim.actors_ahead = ahead;
    let flight = SimFlight {
        script,
        source: text,
        scene,
        profile: &profile,
        rate_hz: 100.0,
        controller: ControllerSetup::new("lqg"),
        plant: None,
        sim,
        realtime: false,
        interrupts: None,
    };
    let report = match log {
        None => fly_simulated(&flight, &mut NullSink, &mut NoObserver).unwrap(),
        Some((path, durable)) => {
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
                sim_effects_off: Some(vec!["battery".into()]),
                rate_hz: 100.0,
                actor_names: names.clone(),
                dronecine_version: "bench".into(),
            };
            let lens = *dronecine_compiler::director::Director::new(script, scene, &profile).lens();
            // As `shoot` writes a simulated flight's log: its options, on a thread of its own.
            let writer = FlightLogWriter::create_with(
                path,
                &header,
                &LogScene {
                    stage: scene.stage,
                    lens,
                    actor_names: &names,
                    actor_heights_m: &heights,
                },
                LogOptions::shoot(durable),
            )
            .unwrap();
            let mut sink = LogThread::spawn(writer, 100.0).unwrap();
            let r = fly_simulated(&flight, &mut sink, &mut NoObserver).unwrap();
            sink.finish().unwrap();
            r
        }
    };
    assert!(report.completed);
}

/// CPU time of the whole process so far, every thread's (ended ones included), from
/// `/proc/self/stat` (Linux; in its fixed 1/100 s unit). `None` elsewhere.
fn process_cpu() -> Option<Duration> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // The fields after the command name (which may hold spaces), from the third on.
    let rest = stat.get(stat.rfind(')')? + 2..)?;
    let mut fields = rest.split_whitespace().skip(11);
    let utime: u64 = fields.next()?.parse().ok()?;
    let stime: u64 = fields.next()?.parse().ok()?;
    Some(Duration::from_millis((utime + stime) * 10))
}

/// Sums the CPU time and the count of flights measured, and prints the mean at the end.
#[derive(Default)]
struct CpuTally {
    cpu: Duration,
    flights: u32,
}

impl CpuTally {
    fn measure(&mut self, f: impl FnOnce()) {
        let start = process_cpu();
        f();
        if let (Some(a), Some(b)) = (start, process_cpu()) {
            self.cpu += b.saturating_sub(a);
            self.flights += 1;
        }
    }

    fn report(&self, what: &str) {
        if self.flights > 0 {
            eprintln!(
                "{what}: {:.2} s of CPU per flight, all threads ({} flights)",
                self.cpu.as_secs_f64() / f64::from(self.flights),
                self.flights
            );
        }
    }
}

fn bench(c: &mut Criterion) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("flight.mcap");
    let mut g = c.benchmark_group("shoot");
    g.sample_size(10);
    // The hour also with the director stepped ahead of the loop on a thread of its own
    // (`SimConfig::actors_ahead`; `shoot` does so when the machine has a core for it).
    for (minutes, ahead) in [(10usize, false), (60, false), (60, true)] {
        let text = generated_script(minutes);
        let script = parse(&text);
        let how = if ahead { ", director ahead" } else { "" };
        let mut tally = CpuTally::default();
        let name = format!("{minutes} min flight{how}, no log");
        g.bench_function(&name, |b| {
            b.iter(|| tally.measure(|| fly(&text, &script, None, ahead)))
        });
        tally.report(&name);
        // Each flight writes a new file, as `shoot` does (its default log name carries the
        // time): the previous flight's file is removed before the clock starts, so that the
        // timed run does not drop the previous hour's page cache, which no flight pays.
        //
        // The log as `shoot` writes a simulated flight's, handed to the OS and not forced to
        // the disk (the file is removed before the OS writes it back: no disk write is
        // measured); and for the hour with the director ahead, also forced to the disk as it
        // is written (`shoot --sync-log`, and a real flight's).
        let durabilities: &[bool] = if ahead { &[false, true] } else { &[false] };
        for &durable in durabilities {
            let mut tally = CpuTally::default();
            let forced = if durable { " forced to the disk" } else { "" };
            let name = format!("{minutes} min flight{how} with its log{forced}");
            g.bench_function(&name, |b| {
                b.iter_custom(|iters| {
                    let mut total = Duration::ZERO;
                    for _ in 0..iters {
                        let _ = std::fs::remove_file(&path);
                        let start = Instant::now();
                        tally.measure(|| fly(&text, &script, Some((&path, durable)), ahead));
                        total += start.elapsed();
                    }
                    total
                })
            });
            tally.report(&name);
        }
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
