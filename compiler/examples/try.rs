use dronecine_compiler::{compile, profile::Profile};
fn main() {
    for path in std::env::args().skip(1) {
        let src = std::fs::read_to_string(&path).unwrap();
        let base = std::path::Path::new(&path).parent().unwrap().to_path_buf();
        let opts = dronecine_grammar::Options {
            known_drones: dronecine_compiler::profile::BUILTIN_NAMES,
            base_dir: Some(&base),
        };
        let checked = dronecine_grammar::check(&src, &opts);
        let script = checked.script.unwrap();
        let profile = Profile::builtin("ardrone2").unwrap();
        let mut n = 0;
        let mut vmax: f64 = 0.0;
        let mut last = None;
        let t0 = std::time::Instant::now();
        let c = compile::compile::<()>(&script, &profile, &Default::default(), |s, _| {
            n += 1;
            vmax = vmax.max(s.velocity_mps[0].hypot(s.velocity_mps[1]));
            last = Some(*s);
            if std::env::var("DUMP").is_ok() && n % 10 == 0 {
                println!(
                    "{:.2} {:?} {:.3} shot {}",
                    s.t_s,
                    s.position_m.map(|x| (x * 1000.0).round() / 1000.0),
                    s.heading_rad,
                    s.shot
                );
            }
            Ok(())
        })
        .unwrap();
        println!(
            "{path}: {n} samples, {:.1}s, vmax {vmax:.2}, {:?} elapsed",
            c.duration_s,
            t0.elapsed()
        );
        for t in &c.timings {
            println!(
                "  shot {} script {:.1} start {:.2} end {:.2} repo {:?}",
                t.index, t.script_start_s, t.start_s, t.end_s, t.reposition
            );
        }
        print!(
            "{}",
            dronecine_grammar::diag::render(&path, &src, &c.diagnostics, false, 100)
        );
    }
}
// dump: DUMP=1 prints t, p, shot every 10 samples
