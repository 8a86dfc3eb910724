//! Fuzz the compile-and-fly path with numbers at the extremes: 0 and -0, subnormals, 1e-12,
//! the edges of each range (1 ms, 1 cm, 1000 m, a day), 1e308, infinities, NaN and any bit
//! pattern. The input picks a scene (a path of each shape, a move, a hold, with an actor's
//! walk), a compile rate and a flight rate, and the numbers that replace the scene's
//! ordinary ones.
//!
//! - As text: the numbers written out in full (as Rust writes an `f64`: never with an
//!   exponent) into the script, which is checked; a script `check` accepts is compiled and
//!   flown on the simulator without a panic, every sample finite, and a shot shorter than
//!   one tick at the compile's rate is an error on its line.
//! - As they are: the same numbers put into the path of a script that checks (what no
//!   script can write: NaN, 1e308 m, a negative turn) and into a path planned on its own
//!   with any duration: compiling and evaluating it never panics.
//!
//! Seed it with `corpus/extremes/` (each seed's first byte picks the scene).
#![no_main]

use dronecine_compiler::camera::Vec3;
use dronecine_compiler::compile::{compile, Options};
use dronecine_compiler::paths::PathPlan;
use dronecine_compiler::CompileCode;
use dronecine_flight::NoObserver;
use dronecine_grammar::script::{OrbitCenter, PathShape, ShotContent};
use dronecine_grammar::{check, PslCode};
use dronecine_mcap::record::NullSink;
use dronecine_profile::{Profile, BUILTIN_NAMES};
use dronecine_runtime::{fly_simulated, SimFlight};
use dronecine_servo::setup::ControllerSetup;
use dronecine_sim::SimConfig;
use libfuzzer_sys::fuzz_target;

/// Numbers worth trying anywhere.
const EXTREMES: [f64; 32] = [
    0.0,
    -0.0,
    5e-324,
    1e-320,
    2.2250738585072014e-308,
    1e-300,
    1e-12,
    1e-9,
    -1e-9,
    1e-6,
    0.0005,
    0.000999,
    0.001,
    0.002,
    0.009,
    0.01,
    0.0444,
    0.05,
    1.0,
    -1.0,
    2.5,
    100.0,
    100.0001,
    999.999,
    1000.0,
    1000.001,
    86_400.0,
    86_400.001,
    999_999_999.0,
    1e9,
    1e308,
    f64::MAX,
];

/// The scene's ordinary numbers, in slot order: side or radius, centre x and y, altitude or
/// start height, end height, turns, the path's (or the move's) duration, the first shot's,
/// the walk's start and its duration, A's facing (degrees).
const ORDINARY: [f64; 11] = [2.0, 0.5, -0.5, 1.5, 2.5, 1.0, 6.0, 3.0, 1.0, 2.0, 0.0];

/// Compile and flight rates the commands take (`compile --rate` from 1 Hz, `shoot --rate`
/// from 10 Hz, both up to 1000 Hz).
const COMPILE_HZ: [f64; 6] = [1.0, 10.0, 20.0, 100.0, 250.0, 1000.0];
const FLY_HZ: [f64; 4] = [10.0, 50.0, 100.0, 1000.0];

/// Most samples one input compiles or flies: a few hundred milliseconds of work.
const MAX_TICKS: f64 = 20_000.0;

struct Bytes<'a>(&'a [u8]);

impl Bytes<'_> {
    fn byte(&mut self) -> u8 {
        let Some((&b, rest)) = self.0.split_first() else {
            return 0;
        };
        self.0 = rest;
        b
    }

    /// An ordinary number, one of [`EXTREMES`], or any bit pattern.
    fn number(&mut self, ordinary: f64) -> f64 {
        match self.byte() % 4 {
            0 | 1 => ordinary,
            2 => {
                let e = EXTREMES[usize::from(self.byte()) % EXTREMES.len()];
                if self.byte() % 2 == 0 {
                    e
                } else {
                    -e
                }
            }
            _ => {
                let mut b = [0u8; 8];
                for x in &mut b {
                    *x = self.byte();
                }
                f64::from_le_bytes(b)
            }
        }
    }
}

/// A number as a script writes it: in full, without an exponent.
fn text(v: f64) -> String {
    format!("{v}")
}

fn scene_text(shape: u8, n: &[f64; 11]) -> String {
    let [a, b, c, d, e, f, t0, t1, t2, t3, facing] = n.map(text);
    let second = match shape % 6 {
        0 => format!("path square side {a}m center ({b}, {c}) altitude {d}m for {t0}s"),
        1 => format!("path helix radius {a}m center ({b}, {c}) from {d}m to {e}m turns {f} for {t0}s"),
        2 => format!("path orbit around A radius {a}m altitude {d}m turns {f} clockwise for {t0}s"),
        3 => format!("path orbit radius {a}m center ({b}, {c}) altitude {d}m turns {f} for {t0}s looking at A"),
        4 => format!("then dolly to MS on A back screen ({b}, {c}) over {t0}s"),
        _ => format!("then hold for {t0}s"),
    };
    let cut = if shape % 6 < 4 { "cut to " } else { "" };
    format!(
        "stage 8m x 6m x 3m\ndrone ardrone2\nactor A height 1.8m at (0, 0) facing {facing}deg\n\
         at {t2}s A walks to ({b}, {c}) over {t3}s\nMS on A front for {t1}s\n{cut}{second}\n"
    )
}

fn finite_samples(script: &dronecine_grammar::Script, profile: &Profile, rate_hz: f64) {
    let c = compile(script, profile, &Options { rate_hz }, |s, _| {
        let all = s
            .position_m
            .iter()
            .chain(&s.velocity_mps)
            .chain(&s.acceleration_mps2);
        assert!(all.copied().all(f64::is_finite), "{s:?}");
        assert!(
            s.heading_rad.is_finite() && s.camera_pitch_rad.is_finite(),
            "{s:?}"
        );
        Ok::<(), ()>(())
    })
    .unwrap();
    for shot in &script.timeline {
        let short = (shot.end_s - shot.start_s) * rate_hz < 1.0 - 1e-9;
        let told = c
            .diagnostics
            .iter()
            .any(|d| d.code == CompileCode::TooShortForRate && d.span == shot.span && d.is_error());
        assert_eq!(short, told, "{shot:?} at {rate_hz} Hz: {:?}", c.diagnostics);
    }
}

/// The path of the script's second shot with its numbers replaced by `n`, as they are.
fn raw_shape(shape: &PathShape, n: &[f64; 11]) -> PathShape {
    let [a, b, c, d, e, f, ..] = *n;
    match shape {
        PathShape::Square { clockwise, .. } => PathShape::Square {
            side_m: a,
            center_m: [b, c],
            altitude_m: d,
            clockwise: *clockwise,
        },
        PathShape::Helix { clockwise, .. } => PathShape::Helix {
            radius_m: a,
            center_m: [b, c],
            from_m: d,
            to_m: e,
            turns: f,
            clockwise: *clockwise,
        },
        PathShape::Orbit {
            center, clockwise, ..
        } => PathShape::Orbit {
            center: match center {
                OrbitCenter::Point { .. } => OrbitCenter::Point { at_m: [b, c] },
                actor => actor.clone(),
            },
            radius_m: a,
            altitude_m: d,
            turns: f,
            clockwise: *clockwise,
        },
        PathShape::Waypoints { file, .. } => PathShape::Waypoints {
            file: file.clone(),
            points_m: vec![[a, b, d], [c, e, f]],
        },
    }
}

fuzz_target!(|data: &[u8]| {
    let mut bytes = Bytes(data);
    let shape = bytes.byte();
    let rates = bytes.byte();
    let compile_hz = COMPILE_HZ[usize::from(rates % 6)];
    let fly_hz = FLY_HZ[usize::from(rates / 6 % 4)];
    let mut n = ORDINARY;
    for (slot, x) in n.iter_mut().enumerate() {
        // The walk's start is never far: a flight waits for nothing else.
        *x = if slot == 8 { *x } else { bytes.number(*x) };
    }
    let opts = dronecine_grammar::Options {
        known_drones: BUILTIN_NAMES,
        base_dir: None,
    };
    let profile = Profile::builtin("ardrone2").unwrap();

    // As text, through `check`.
    let src = scene_text(shape, &n);
    let checked = check(&src, &opts);
    if let (false, Some(script)) = (checked.has_errors(), checked.script.as_ref()) {
        let scene = script.scene.as_ref().unwrap();
        if script.duration_s * compile_hz <= MAX_TICKS {
            finite_samples(script, &profile, compile_hz);
        }
        if script.duration_s * fly_hz <= MAX_TICKS {
            let mut sim = SimConfig::new(u64::from(shape));
            sim.effects.battery = false;
            let flight = SimFlight {
                script,
                source: &src,
                scene,
                profile: &profile,
                rate_hz: fly_hz,
                controller: ControllerSetup::new("lqg"),
                plant: None,
                sim,
                realtime: false,
                interrupts: None,
            };
            let _ = fly_simulated(&flight, &mut NullSink, &mut NoObserver);
        }
    } else {
        // A refused number says what to write instead (a line that does not parse, such as
        // one with `NaN` or `inf` written in it, is told its grammar).
        assert!(checked.has_errors());
        for d in checked
            .diagnostics
            .iter()
            .filter(|d| d.code != PslCode::Syntax)
        {
            assert!(d.help.is_some(), "{} has no help line: {d:?}", d.code);
        }
    }

    // As they are, past `check`: the same numbers in the path of the ordinary scene.
    let ordinary = check(&scene_text(shape, &ORDINARY), &opts);
    let mut script = ordinary.script.expect("the ordinary scene checks");
    let path_s = n[6];
    if let ShotContent::Path(path) = &mut script.timeline[1].content {
        path.shape = raw_shape(&path.shape, &n);
        if shape % 7 == 6 {
            path.shape = raw_shape(
                &PathShape::Waypoints {
                    file: String::new(),
                    points_m: Vec::new(),
                },
                &n,
            );
        }
        // Any duration a planned path is given, evaluated where it starts, ends and between.
        let plan = PathPlan::new(&path.shape, path_s, 1.0, Vec3::zeros(), |_| Some(0), &[]);
        for t in [0.0, path_s / 2.0, path_s, -path_s, f64::NAN, 1e-9] {
            let _ = plan.at(t, &[]);
        }
        // Compiled with a duration that keeps the compile short.
        if path_s.is_finite() && path_s * compile_hz <= MAX_TICKS && path_s >= 0.0 {
            let shot = &mut script.timeline[1];
            shot.end_s = shot.start_s + path_s;
            script.duration_s = shot.end_s;
            let _ = compile(
                &script,
                &profile,
                &Options {
                    rate_hz: compile_hz,
                },
                |_, _| Ok::<(), ()>(()),
            );
        }
    }
});
