use dronecine_compiler::profile::Profile;
use dronecine_runtime::flight::{FlightSink, NoObserver};
use dronecine_runtime::record::{ControllerSetup, Event, TickRecord};
use dronecine_runtime::session::{fly_simulated, SimFlight};
use dronecine_runtime::sim::SimConfig;
struct P(usize);
impl FlightSink for P {
    fn tick(&mut self, r: &TickRecord) -> std::io::Result<()> {
        self.0 += 1;
        if self.0 % 50 == 0 || r.sample.position_m.iter().any(|x| x.abs() > 5.0) {
            if self.0 < 200000 {
                println!(
                    "{:?} {:?} t {:.2} ref {:?} meas {:?} actors {:?} cmd {:?}",
                    r.phase,
                    r.shot,
                    r.input.t_s,
                    r.sample.position_m,
                    r.input.measurement.map(|m| m.position_m),
                    r.actors
                        .iter()
                        .map(|a| (a.position_m, a.velocity_mps))
                        .collect::<Vec<_>>(),
                    r.command_sent
                );
            }
            if self.0 > 200000 {
                std::process::exit(0)
            }
        }
        Ok(())
    }
    fn event(&mut self, e: &Event) -> std::io::Result<()> {
        println!("EVENT {:?}", e);
        Ok(())
    }
}
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let text = std::fs::read_to_string(&args[1]).unwrap();
    let opts = dronecine_grammar::Options {
        known_drones: dronecine_compiler::profile::BUILTIN_NAMES,
        base_dir: None,
    };
    let script = dronecine_grammar::check(&text, &opts).script.unwrap();
    let scene = script.scene.as_ref().unwrap();
    let profile = Profile::builtin("ardrone2").unwrap();
    let mut sim = SimConfig::new(7);
    sim.effects.actor_deviation = false;
    let f = SimFlight {
        script: &script,
        source: &text,
        scene,
        profile: &profile,
        rate_hz: 100.0,
        controller: ControllerSetup {
            kind: "lqg".into(),
            paper_prefilter: false,
            per_tick_solve: false,
        },
        sim,
        realtime: false,
    };
    let r = fly_simulated(&f, &mut P(0), &mut NoObserver).unwrap();
    println!("{:?}", r.figures);
}
