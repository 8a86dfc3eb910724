use dronecine_compiler::profile::Profile;
use dronecine_runtime::flight::{NoObserver, NullSink};
use dronecine_runtime::record::ControllerSetup;
use dronecine_runtime::session::{fly_simulated, SimFlight};
use dronecine_runtime::sim::{Effects, SimConfig};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let path = &args[1];
    let text = std::fs::read_to_string(path).unwrap();
    let opts = dronecine_grammar::Options {
        known_drones: dronecine_compiler::profile::BUILTIN_NAMES,
        base_dir: None,
    };
    let script = dronecine_grammar::check(&text, &opts).script.unwrap();
    let scene = script.scene.as_ref().unwrap();
    let mut profile = Profile::builtin("ardrone2").unwrap();
    if let Some(q) = args.get(3) {
        let v: Vec<f64> = q.split(',').map(|x| x.parse().unwrap()).collect();
        profile.servo.q.copy_from_slice(&v);
    }
    if let Some(r) = args.get(4) {
        let v: Vec<f64> = r.split(',').map(|x| x.parse().unwrap()).collect();
        profile.servo.r.copy_from_slice(&v);
    }
    if let Ok(t) = std::env::var("HTAU") {
        profile.servo.heading_tau_s = t.parse().unwrap();
    }
    let which = args.get(2).map(String::as_str).unwrap_or("all");
    let mut only_actors = Effects::none();
    only_actors.actor_deviation = true;
    let mut variants: Vec<(&str, Effects)> = vec![
        ("all", Effects::all()),
        ("none", Effects::none()),
        ("only-actors", only_actors),
    ];
    if which == "each" {
        let names = [
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
        ];
        for n in names {
            let mut e = Effects::all();
            match n {
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
            };
            variants.push((n, e));
        }
    }
    for ctrl in ["lqg", "pid"] {
        for (name, eff) in &variants {
            let mut sim = SimConfig::new(7);
            sim.effects = *eff;
            let f = SimFlight {
                script: &script,
                source: &text,
                scene,
                profile: &profile,
                rate_hz: 100.0,
                controller: ControllerSetup {
                    kind: ctrl.into(),
                    paper_prefilter: false,
                    per_tick_solve: false,
                },
                sim,
                realtime: false,
            };
            let r = fly_simulated(&f, &mut NullSink, &mut NoObserver).unwrap();
            println!("{ctrl} without {name:16} rms {:.2} cm max {:.2} cm head {:.2} deg framing {:?} sat {:.3} completed {}", r.figures.rms_position_error_m*100.0, r.figures.max_position_error_m*100.0, r.figures.rms_heading_error_rad.to_degrees(), r.figures.rms_framing_error, r.figures.saturated_fraction, r.completed);
        }
    }
}
