//! Parse + resolve (`check`), `format`, and the parser alone, on a generated 10,000-shot
//! script.
//!
//! Run: `cargo bench -p dronecine-grammar --bench parse -- --warm-up-time 1 --measurement-time 5`

use criterion::{black_box, criterion_group, criterion_main, Criterion, Throughput};
use dronecine_grammar::{check, format, parser, Options};

const SHOTS: usize = 10_000;

const HEADER: &str = "\
stage 8m x 6m x 3m
lens 84deg
drone ardrone2
actor A height 1.80m at (0, 0) facing 0deg
actor B height 1.65m at (2.5, 0) facing 180deg
at 6s A walks to (1, 1.5) over 4s
at 12s B turns to 90deg over 1s
";

/// The shot lines the generator cycles through (after the first shot). A path line is always
/// followed by a `cut to` line: a `then` move cannot continue a path.
const CYCLE: &[&str] = &[
    "cut to MS on A front for 4s",
    "then dolly to MS on A 34backright over 6s",
    "cut to high angle MS on A and B for 5s",
    "cut to MS on B 34backright MLS on A 34left screen right for 3s",
    "cut to CU on B 34left screen left for 2.5s",
    "then as A sits down pan to MCU on A left over 3s",
    "then hold for 2s",
    "cut to path orbit around A radius 2m altitude 1.5m turns 1 for 20s",
    "cut to low angle MCU on A 34right for 3s",
    "then track to MS on A right over 2s",
    "cut to path square side 2m center (0, 0) altitude 1.5m for 20s looking at A",
    "cut to MS B 34backright MLS A 34left screen right for 3s",
    "cut to FS on A and B for 4s",
];

/// A valid script of exactly `shots` shots, deterministic.
fn script(shots: usize) -> String {
    let mut s = String::with_capacity(HEADER.len() + shots * 48);
    s.push_str(HEADER);
    s.push_str("MS on A front for 4s\n");
    for i in 1..shots {
        if i % 97 == 0 {
            s.push_str("# a comment between shots\n");
        }
        s.push_str(CYCLE[(i - 1) % CYCLE.len()]);
        s.push('\n');
    }
    s
}

fn bench(c: &mut Criterion) {
    let src = script(SHOTS);

    // Outside the timed loops: make sure we measure the success path.
    let checked = check(&src, &Options::default());
    if checked.has_errors() {
        let shown: Vec<String> = checked
            .diagnostics
            .iter()
            .take(5)
            .map(|d| format!("{d:?}"))
            .collect();
        panic!("generated script has errors:\n{}", shown.join("\n"));
    }
    let n = checked.script.expect("script").timeline.len();
    assert_eq!(n, SHOTS, "timeline entries");
    let formatted = format(&src).unwrap_or_else(|d| panic!("format failed: {d:?}"));
    assert!(!formatted.is_empty());

    let mut g = c.benchmark_group("psl_10k_shots");
    g.throughput(Throughput::Bytes(src.len() as u64));
    g.bench_function("check", |b| {
        b.iter(|| check(black_box(&src), &Options::default()))
    });
    g.bench_function("format", |b| b.iter(|| format(black_box(&src))));
    g.bench_function("parse", |b| b.iter(|| parser::parse(black_box(&src))));
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
