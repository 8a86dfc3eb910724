//! Where a flight's error comes from: flies a script on the embedded simulator (seed 7) with
//! LQG and PID, with every effect on, with none, with only the actors' deviations, and with
//! `each` also every effect switched off in turn; prints position, heading and framing
//! errors. Optional servo weights override the profile's, to try a tuning.
//!
//! ```sh
//! cargo run --release -p dronecine-runtime --example tune -- shots/two-actors.psl [each] [Q1,..,Q6 R1,R2,R3]
//! ```

use dronecine_compiler::profile::Profile;
use dronecine_runtime::flight::{NoObserver, NullSink};
use dronecine_runtime::record::ControllerSetup;
use dronecine_runtime::session::{fly_simulated, SimFlight};
use dronecine_runtime::sim::{Effects, SimConfig};

fn numbers<const N: usize>(arg: &str) -> Result<[f64; N], String> {
    let v: Vec<f64> = arg
        .split(',')
        .map(|x| x.trim().parse::<f64>().map_err(|e| format!("`{x}`: {e}")))
        .collect::<Result<_, _>>()?;
    v.try_into()
        .map_err(|v: Vec<f64>| format!("{N} numbers expected, got {}", v.len()))
}

/// Effects with one switched off, by name.
fn without(name: &str) -> Effects {
    let mut e = Effects::all();
    match name {
        "attitude_lag" => e.attitude_lag = false,
        "tilt_saturation" => e.tilt_saturation = false,
        "drag" => e.drag = false,
        "asymmetric_vz" => e.asymmetric_vz = false,
        "yaw_lag" => e.yaw_lag = false,
        "latency" => e.latency = false,
        "radio_loss" => e.radio_loss = false,
        "mocap_noise" => e.mocap_noise = false,
        "mocap_dropouts" => e.mocap_dropouts = false,
        "wind" => e.wind = false,
        "actor_deviation" => e.actor_deviation = false,
        _ => e.battery = false,
    }
    e
}

fn run() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let path = args
        .first()
        .ok_or("usage: tune FILE.psl [each] [Q1,..,Q6 R1,R2,R3]")?;
    let text = std::fs::read_to_string(path).map_err(|e| format!("{path}: {e}"))?;
    let opts = dronecine_grammar::Options {
        known_drones: dronecine_compiler::profile::BUILTIN_NAMES,
        base_dir: None,
    };
    let checked = dronecine_grammar::check(&text, &opts);
    let script = checked
        .script
        .ok_or_else(|| format!("{path} has errors: run `dronecine check {path}`"))?;
    let scene = script.scene.as_ref().ok_or("the script has no scene")?;
    let mut profile = Profile::builtin("ardrone2").ok_or("no ardrone2 profile")?;
    let each = args.get(1).is_some_and(|a| a == "each");
    let rest: Vec<&String> = args.iter().skip(1).filter(|a| *a != "each").collect();
    if let [q, r] = rest.as_slice() {
        profile.servo.q = numbers::<6>(q)?;
        profile.servo.r = numbers::<3>(r)?;
    }
    let mut only_actors = Effects::none();
    only_actors.actor_deviation = true;
    let mut variants = vec![
        ("every effect".to_string(), Effects::all()),
        ("no effect".to_string(), Effects::none()),
        ("only actor deviations".to_string(), only_actors),
    ];
    if each {
        for name in [
            "attitude_lag",
            "tilt_saturation",
            "drag",
            "asymmetric_vz",
            "yaw_lag",
            "latency",
            "radio_loss",
            "mocap_noise",
            "mocap_dropouts",
            "wind",
            "actor_deviation",
            "battery",
        ] {
            variants.push((format!("without {name}"), without(name)));
        }
    }
    for controller in ["lqg", "pid"] {
        for (name, effects) in &variants {
            let mut sim = SimConfig::new(7);
            sim.effects = *effects;
            let flight = SimFlight {
                script: &script,
                source: &text,
                scene,
                profile: &profile,
                rate_hz: 100.0,
                controller: ControllerSetup {
                    kind: controller.into(),
                    paper_prefilter: false,
                    per_tick_solve: false,
                },
                plant: None,
                sim,
                realtime: false,
                interrupts: None,
            };
            let r = fly_simulated(&flight, &mut NullSink, &mut NoObserver)
                .map_err(|e| e.to_string())?;
            let f = &r.figures;
            println!(
                "{controller} {name:24} RMS {:5.2} cm  max {:5.2} cm  heading {:4.2}°  framing {}  \
                 saturated {:4.1}%{}",
                f.rms_position_error_m * 100.0,
                f.max_position_error_m * 100.0,
                f.rms_heading_error_rad.to_degrees(),
                f.rms_framing_error.map_or("  —  ".into(), |x| format!("{x:.3}")),
                f.saturated_fraction * 100.0,
                if r.completed { "" } else { "  (not completed)" }
            );
        }
    }
    Ok(())
}

fn main() {
    if let Err(e) = run() {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}
