//! Rendering the diagnostics of a 50,000-line script with a mistake on every line: the whole
//! list (the first ones quoted, the rest counted), and the last 100 alone (quoted from the
//! end of the file, where reading from the text's start would cost the most).
//!
//! Run: `cargo bench -p dronecine-diag --bench render -- --warm-up-time 1 --measurement-time 5`

use criterion::{black_box, criterion_group, criterion_main, Criterion, Throughput};
use dronecine_diag::{render, Code, Diagnostic, Span, MAX_RENDERED};

const LINES: usize = 50_000;

const HEADER: &str = "\
stage 8m x 6m x 3m
drone ardrone2
actor A height 1.80m at (0, 0) facing 0deg
";

/// The script and its diagnostics: an unknown actor on every shot line, a warning every tenth.
fn script() -> (String, Vec<Diagnostic>) {
    let unknown = Code::new("psl::unknown_actor", "An actor not declared.", 0);
    let timed = Code::new("psl::duration_keyword", "A move timed with `for`.", 1);
    let mut src = String::from(HEADER);
    let mut diagnostics = Vec::with_capacity(LINES);
    for i in 0..LINES {
        let at = src.len();
        src.push_str("MS on Nobody for 4s\n");
        diagnostics.push(if i % 10 == 9 {
            Diagnostic::warning(timed, Span::new(at + 13, at + 16), "timed with `for`")
                .with_help("write `over 4s`: the move takes that long")
        } else {
            Diagnostic::error(
                unknown,
                Span::new(at + 6, at + 12),
                "unknown actor `Nobody`",
            )
            .with_label("not declared")
            .with_help("declare it before the shots")
        });
    }
    (src, diagnostics)
}

fn bench(c: &mut Criterion) {
    let (src, diagnostics) = script();
    let last = &diagnostics[LINES - MAX_RENDERED..];

    // Outside the timed loops: the first ones are quoted and the rest counted.
    let out = render("x.psl", &src, &diagnostics, false, 100);
    assert!(out.ends_with("… 44910 more errors and 4990 more warnings in `x.psl` not shown\n"));
    let out = render("x.psl", &src, last, false, 100);
    let last_line = HEADER.lines().count() + LINES;
    assert!(out.contains(&format!("[x.psl:{last_line}:14]")) && !out.contains("not shown"));

    let mut g = c.benchmark_group("render_50k_diagnostics");
    g.throughput(Throughput::Elements(diagnostics.len() as u64));
    g.bench_function("all", |b| {
        b.iter(|| {
            render(
                "x.psl",
                black_box(&src),
                black_box(&diagnostics),
                false,
                100,
            )
        })
    });
    g.throughput(Throughput::Elements(last.len() as u64));
    g.bench_function("last_100", |b| {
        b.iter(|| render("x.psl", black_box(&src), black_box(last), false, 100))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
