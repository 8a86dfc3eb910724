use dronecine_compiler::blocking::Blocking;
use dronecine_compiler::director::Director;
use dronecine_compiler::profile::Profile;
fn main() {
    let path = std::env::args().nth(1).unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    let opts = dronecine_grammar::Options {
        known_drones: dronecine_compiler::profile::BUILTIN_NAMES,
        base_dir: None,
    };
    let script = dronecine_grammar::check(&text, &opts).script.unwrap();
    let scene = script.scene.as_ref().unwrap();
    let name = match scene.drone.as_ref() {
        Some(dronecine_grammar::script::DroneRef::Builtin { name }) => name.clone(),
        _ => "ardrone2".into(),
    };
    let profile = Profile::builtin(&name).unwrap();
    let blocking = Blocking::new(scene);
    let mut d = Director::new(&script, scene, &profile);
    let mut prev: Option<[f64; 3]> = None;
    for k in 0..=1600 {
        let t = k as f64 * 0.01;
        let poses = blocking.poses(t);
        let s = d.step(t, &poses);
        let p = d.solved_target_m();
        let b = poses[1].position_m;
        let jump = prev.map_or(0.0, |q: [f64; 3]| {
            ((p.x - q[0]).powi(2) + (p.y - q[1]).powi(2) + (p.z - q[2]).powi(2)).sqrt()
        });
        if k % 10 == 0 || jump > 0.05 {
            println!("t {t:.2} target ({:.3}, {:.3}, {:.3}) ref ({:.3},{:.3}) B ({:.3},{:.3}) jump {jump:.3}", p.x, p.y, p.z, s.position_m[0], s.position_m[1], b[0], b[1]);
        }
        prev = Some([p.x, p.y, p.z]);
    }
    for diag in d.diagnostics_so_far() {
        println!("{:?}: {}", diag.code, diag.message);
    }
}
