//! Where a flight's error comes from: flies a script on the embedded simulator (seed 7) with
//! LQG and PID, with every effect on, with none, with only the actors' deviations, and with
//! `each` also every effect switched off in turn; prints position, heading and framing
//! errors. Optional servo weights override the profile's, to try a tuning.
//!
//! For the holds it also prints what the framing asks of the camera: each tick the hold's
//! composition is solved again against the actors as the director saw them, and
//! - `demand`: the RMS horizontal acceleration of that exact camera position (a central
//!   second difference over ±0.1 s, so mocap noise does not swamp it) and the share of ticks
//!   where it exceeds the profile's `accel_max_mps2`, which the director's steering may not;
//! - `ref→exact`: the RMS distance from the director's reference to it.
//!
//! ```sh
//! cargo run --release -p dronecine-runtime --example tune -- shots/two-actors.psl [each] [Q1,..,Q6 R1,R2,R3]
//! ```

use dronecine_compiler::camera::{Lens, Vec3};
use dronecine_compiler::framing;
use dronecine_flight::NoObserver;
use dronecine_grammar::script::{Composition, Script, ShotContent};
use dronecine_mcap::record::FlightSink;
use dronecine_mcap::record::{Event, Phase, TickRecord};
use dronecine_profile::{Gimbal, Profile};
use dronecine_runtime::{fly_simulated, SimFlight};
use dronecine_servo::setup::ControllerSetup;
use dronecine_sim::{Effects, SimConfig};

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

/// Ticks of ±0.1 s for the second difference, at 100 Hz.
const SPAN: usize = 10;

/// What the holds ask of the camera (module docs).
struct Demand {
    /// The composition of each shot (a tick with framing records is in a hold of it).
    holds: Vec<Option<Composition>>,
    names: Vec<String>,
    lens: Lens,
    gimbal: Gimbal,
    accel_max_mps2: f64,
    /// The exact camera positions of the last 2·SPAN + 1 ticks of the current hold.
    exact: Vec<Vec3>,
    shot: Option<usize>,
    sq_accel: f64,
    over: u64,
    accel_n: u64,
    sq_ref: f64,
    ref_n: u64,
}

impl Demand {
    fn new(script: &Script, names: Vec<String>, profile: &Profile, lens: Lens) -> Demand {
        Demand {
            holds: script
                .timeline
                .iter()
                .map(|shot| match &shot.content {
                    ShotContent::Composition(c) => Some(c.clone()),
                    _ => None,
                })
                .collect(),
            names,
            lens,
            gimbal: profile.camera.gimbal,
            accel_max_mps2: profile.limits.accel_max_mps2,
            exact: Vec::with_capacity(2 * SPAN + 1),
            shot: None,
            sq_accel: 0.0,
            over: 0,
            accel_n: 0,
            sq_ref: 0.0,
            ref_n: 0,
        }
    }

    fn report(&self) -> String {
        if self.ref_n == 0 {
            return String::new();
        }
        let rms = |s: f64, n: u64| (s / n.max(1) as f64).sqrt();
        format!(
            "  demand {:.2} m/s² ({:.0}% > {:.2})  ref→exact {:.1} cm",
            rms(self.sq_accel, self.accel_n),
            100.0 * self.over as f64 / self.accel_n.max(1) as f64,
            self.accel_max_mps2,
            100.0 * rms(self.sq_ref, self.ref_n)
        )
    }
}

impl FlightSink for Demand {
    fn tick(&mut self, r: &TickRecord) -> std::io::Result<()> {
        let comp = match r.shot {
            Some(i) if r.phase == Phase::Shots && !r.framing.is_empty() => {
                self.holds.get(i).and_then(|c| c.as_ref())
            }
            _ => None,
        };
        let exact = comp.and_then(|c| {
            let v = framing::solve(c, &self.names, r.actors, &self.lens, &self.gimbal).ok()?;
            Some(framing::position_m(&v, r.actors, &self.lens, &self.gimbal))
        });
        let Some(exact) = exact else {
            self.exact.clear();
            return Ok(());
        };
        if self.shot != r.shot {
            self.exact.clear();
            self.shot = r.shot;
        }
        let reference = Vec3::from(r.sample.position_m);
        self.sq_ref += (reference - exact).norm_squared();
        self.ref_n += 1;
        if self.exact.len() == 2 * SPAN + 1 {
            self.exact.remove(0);
        }
        self.exact.push(exact);
        if self.exact.len() == 2 * SPAN + 1 {
            let h = SPAN as f64 / 100.0;
            let a = (self.exact[0] - 2.0 * self.exact[SPAN] + self.exact[2 * SPAN]) / (h * h);
            let a = a.xy().norm();
            self.sq_accel += a * a;
            self.over += u64::from(a > self.accel_max_mps2);
            self.accel_n += 1;
        }
        Ok(())
    }

    fn event(&mut self, _: &Event) -> std::io::Result<()> {
        Ok(())
    }
}

fn run() -> Result<(), String> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let path = args
        .first()
        .ok_or("usage: tune FILE.psl [each] [Q1,..,Q6 R1,R2,R3]")?;
    let text = std::fs::read_to_string(path).map_err(|e| format!("{path}: {e}"))?;
    let opts = dronecine_grammar::Options {
        known_drones: dronecine_profile::BUILTIN_NAMES,
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
                controller: ControllerSetup::new(controller),
                plant: None,
                sim,
                realtime: false,
                interrupts: None,
            };
            let lens =
                *dronecine_compiler::director::Director::new(&script, scene, &profile).lens();
            let names = scene.actors.iter().map(|a| a.name.clone()).collect();
            let mut demand = Demand::new(&script, names, &profile, lens);
            let r =
                fly_simulated(&flight, &mut demand, &mut NoObserver).map_err(|e| e.to_string())?;
            let f = &r.figures;
            println!(
                "{controller} {name:24} RMS {:5.2} cm  max {:5.2} cm  heading {:4.2}°  framing {}  \
                 saturated {:4.1}%{}{}",
                f.rms_position_error_m.unwrap_or(f64::NAN) * 100.0,
                f.max_position_error_m.unwrap_or(f64::NAN) * 100.0,
                f.rms_heading_error_rad.unwrap_or(f64::NAN).to_degrees(),
                f.rms_framing_error.map_or("  —  ".into(), |x| format!("{x:.3}")),
                f.saturated_fraction.unwrap_or(f64::NAN) * 100.0,
                if r.completed { "" } else { "  (not completed)" },
                demand.report()
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
