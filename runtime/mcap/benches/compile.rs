//! `dronecine compile`'s pipeline: a generated one-hour script (720 shots of 5 s, one- and
//! two-actor framings, moving actors) compiled to MCAP at 100 Hz on one core, and evaluated
//! without writing. The 10-minute script shows how the cost grows.
//!
//! Run: `cargo bench -p dronecine-mcap --bench compile`.

use criterion::{criterion_group, criterion_main, Criterion};
use dronecine_compiler::compile::{compile, Options};
use dronecine_mcap::output::{McapWriter, RunInfo};
use dronecine_profile::Profile;

/// A script of `shots` shots of 5 s: two actors pacing the stage, framed alone and together,
/// with `then` moves between framings and a cut every sixth shot.
pub fn generated_script(shots: usize) -> String {
    let mut s = String::from(
        "stage 10m x 8m x 3m\nlens 84deg\ndrone ardrone2\n\
         actor A height 1.80m at (-1, 0) facing 0deg\n\
         actor B height 1.65m at (1, 0) facing 180deg\n",
    );
    let total = shots as f64 * 5.0;
    // Blocking: slow walks back and forth, one actor at a time, 10 s each, every 20 s.
    let mut t = 2.0;
    let mut k = 0;
    while t + 10.0 < total {
        let (who, x) = if k % 2 == 0 { ("A", -1.0) } else { ("B", 1.0) };
        let y = if (k / 2) % 2 == 0 { 0.8 } else { 0.0 };
        s.push_str(&format!("at {t}s {who} walks to ({x}, {y}) over 10s\n"));
        t += 20.0;
        k += 1;
    }
    let framings = [
        "MS on A 34left",
        "MLS on A and B",
        "MS on B 34right",
        "MLS on A and B",
        "FS on A front",
        "MLS on B front",
    ];
    for i in 0..shots {
        let f = framings[i % framings.len()];
        if i == 0 {
            s.push_str(&format!("{f} for 5s\n"));
        } else if i % 6 == 0 {
            s.push_str(&format!("cut to {f} for 5s\n"));
        } else {
            s.push_str(&format!("then dolly to {f} over 5s\n"));
        }
    }
    s
}

fn bench(c: &mut Criterion) {
    let profile = Profile::builtin("ardrone2").unwrap();
    let dir = std::env::temp_dir();
    let mut group = c.benchmark_group("compile");
    group.sample_size(10);
    for (label, shots) in [("10min", 120usize), ("60min", 720)] {
        let src = generated_script(shots);
        let checked = dronecine_grammar::check(&src, &Default::default());
        let script = checked.script.expect("the generated script checks");
        let scene = script.scene.clone().unwrap();
        let names: Vec<String> = scene.actors.iter().map(|a| a.name.clone()).collect();
        let out = dir.join(format!("dronecine-bench-{label}.mcap"));
        group.bench_function(format!("{label}_to_mcap_100hz"), |b| {
            b.iter(|| {
                let info = RunInfo {
                    script_name: "bench.psl",
                    script_text: &src,
                    profile_name: &profile.name,
                    rate_hz: 100.0,
                    lens: dronecine_compiler::camera::Lens::new(84f64.to_radians(), 16.0 / 9.0),
                    stage: scene.stage,
                    actor_names: &names,
                };
                let mut w = McapWriter::create(&out, &info).unwrap();
                let c =
                    compile(&script, &profile, &Options::default(), |s, a| w.write(s, a)).unwrap();
                w.finish().unwrap();
                c.samples
            })
        });
        group.bench_function(format!("{label}_evaluate_only"), |b| {
            b.iter(|| {
                compile::<()>(&script, &profile, &Options::default(), |_, _| Ok(()))
                    .unwrap()
                    .samples
            })
        });
        let _ = std::fs::remove_file(&out);
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
