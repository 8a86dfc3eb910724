//! ArduCopter SITL: the autopilot's own code and multicopter physics, flown through the MAVLink
//! backend, judged on the simulator's true position (`--mocap sitl`: SIM_STATE is the motion
//! capture, and what the autopilot's EKF is fed).
//!
//! Opt-in: `DRONECINE_ARDUCOPTER_SITL` names the SITL binary (`arducopter`, ArduPilot's
//! software-in-the-loop build of its Copter firmware, which this project does not ship); the
//! autopilot's default parameters for its test vehicle are read from
//! `DRONECINE_ARDUCOPTER_DEFAULTS`, or from `Tools/autotest/default_params/copter.parm` of the
//! source tree the binary was built in. Without the variable every test here says it is
//! skipped and passes.
//!
//! SITL listens on every network interface: each flight runs SITL and `dronecine` together in
//! a network namespace of their own (`unshare --net`, inside a user namespace for a user other
//! than root; only the loopback up).

use std::path::{Path, PathBuf};
use std::process::Command;

use crate::common::{temp_dir, workspace};

/// The parameters flying on motion capture needs, on top of the test vehicle's defaults.
const EXTERNAL_NAV_PARAMS: &str = "VISO_TYPE 1\nGPS1_TYPE 0\nEK3_SRC1_POSXY 6\n\
                                   EK3_SRC1_VELXY 6\nEK3_SRC1_POSZ 6\nEK3_SRC1_VELZ 6\n";

/// A camera mount on SITL's vehicle: a servo gimbal (MNT1_TYPE 1) on outputs 5 to 7, which
/// the gimbal protocol v2 drives and GIMBAL_DEVICE_ATTITUDE_STATUS reports.
const GIMBAL_PARAMS: &str = "MNT1_TYPE 1\nRC6_OPTION 213\nSERVO5_FUNCTION 8\n\
                             SERVO6_FUNCTION 7\nSERVO7_FUNCTION 6\n";

/// Where SITL's vehicle is on Earth (latitude, longitude in degrees, altitude in metres):
/// its home, and the EKF origin the flight sets (the compass is checked against the Earth's
/// field there).
const SITL_HOME: &str = "-35.363261,149.165230,584";

/// The position error a flight through SITL must keep under (RMS, m), and its ratio to the
/// embedded simulator's on the same script.
const MAX_RMS_M: f64 = 0.10;
const MAX_RATIO_TO_SIMULATOR: f64 = 2.0;

/// The SITL binary and its defaults file, or `None` (the test is skipped, saying why).
fn sitl(test: &str) -> Option<(PathBuf, PathBuf)> {
    let Some(binary) = std::env::var_os("DRONECINE_ARDUCOPTER_SITL").map(PathBuf::from) else {
        eprintln!(
            "{test}: skipped: DRONECINE_ARDUCOPTER_SITL does not name an ArduCopter SITL binary"
        );
        return None;
    };
    assert!(
        binary.is_file(),
        "DRONECINE_ARDUCOPTER_SITL: {binary:?} is not a file"
    );
    let defaults = std::env::var_os("DRONECINE_ARDUCOPTER_DEFAULTS")
        .map(PathBuf::from)
        .unwrap_or_else(|| {
            // build/sitl/bin/arducopter in the source tree.
            let tree = binary.ancestors().nth(4).unwrap_or(Path::new("/"));
            tree.join("Tools/autotest/default_params/copter.parm")
        });
    assert!(
        defaults.is_file(),
        "no ArduCopter defaults at {defaults:?}: set DRONECINE_ARDUCOPTER_DEFAULTS"
    );
    Some((binary, defaults))
}

/// `shots/NAME` with its drone line made `drone arducopter-quad`, written into `dir`.
fn for_arducopter(name: &str, dir: &Path) -> PathBuf {
    let text = std::fs::read_to_string(workspace().join("shots").join(name)).unwrap();
    let (drone_line, _) = text
        .lines()
        .enumerate()
        .find(|(_, l)| l.trim_start().starts_with("drone "))
        .expect("a drone line");
    let lines: Vec<&str> = text.lines().collect();
    let mut out = String::new();
    for (i, l) in lines.iter().enumerate() {
        out += if i == drone_line {
            "drone arducopter-quad"
        } else {
            l
        };
        out += "\n";
    }
    let path = dir.join(name);
    std::fs::write(&path, out).unwrap();
    path
}

/// Runs `dronecine ARGS` beside a fresh SITL (the test vehicle's defaults, the external
/// navigation's parameters and `more_params`) in a network namespace of its own, in `dir`:
/// its standard output goes to `dir/out`, its errors to `dir/err`. Fails the test, quoting
/// those errors, when it exits unsuccessfully.
fn in_sitl(sitl: &(PathBuf, PathBuf), dir: &Path, more_params: &str, args: &str) {
    let params = dir.join("external-nav.parm");
    std::fs::write(&params, format!("{EXTERNAL_NAV_PARAMS}{more_params}")).unwrap();
    let (binary, defaults) = sitl;
    let inside = format!(
        "ip link set lo up || exit 1; cd '{dir}' || exit 1; \
         '{binary}' --model quad --speedup 1 --wipe --defaults '{defaults},{params}' -I0 \
           --home {SITL_HOME},0 > sitl.log 2>&1 & sitl=$!; sleep 2; \
         '{dronecine}' {args} > out 2> err; rc=$?; \
         kill $sitl; wait $sitl 2>/dev/null; exit $rc",
        dir = dir.display(),
        binary = binary.display(),
        defaults = defaults.display(),
        params = params.display(),
        dronecine = env!("CARGO_BIN_EXE_dronecine"),
    );
    // Root makes the network namespace itself (and the flight gets the real-time scheduling
    // it asks for); anyone else makes it inside a user namespace of their own.
    // SAFETY: geteuid takes nothing and cannot fail.
    let root = unsafe { libc::geteuid() } == 0;
    let unshare: &[&str] = if root {
        &["--net"]
    } else {
        &["--net", "--map-root-user"]
    };
    let status = Command::new("unshare")
        .args(unshare)
        .args(["bash", "-c", &inside])
        .env("NO_COLOR", "1")
        .status()
        .expect("unshare runs (util-linux)");
    let err = std::fs::read_to_string(dir.join("err")).unwrap_or_default();
    assert!(
        status.success(),
        "dronecine {args} beside SITL failed: {err}"
    );
}

/// The vehicle's address inside the namespace, with the EKF origin the flight sets.
fn sitl_drone() -> String {
    format!("'mavlink://tcp:127.0.0.1:5760?origin={SITL_HOME}' --mocap sitl")
}

/// The JSON report of `script` flown through SITL (fresh parameters and `more_params`, a new
/// namespace).
fn fly_sitl(
    sitl: &(PathBuf, PathBuf),
    script: &Path,
    dir: &Path,
    more_params: &str,
) -> serde_json::Value {
    let args = format!(
        "shoot '{script}' --drone {drone} --report json -q --log '{dir}/flight.mcap'",
        script = script.display(),
        drone = sitl_drone(),
        dir = dir.display(),
    );
    in_sitl(sitl, dir, more_params, &args);
    let report = std::fs::read_to_string(dir.join("out")).unwrap();
    serde_json::from_str(&report).unwrap_or_else(|e| panic!("{e}: {report}"))
}

/// The JSON report of `script` flown on the embedded simulator (seed 1).
fn fly_simulator(script: &Path, dir: &Path) -> serde_json::Value {
    let log = dir.join("simulated.mcap");
    let o = crate::common::dronecine(&[
        "shoot",
        script.to_str().unwrap(),
        "--seed",
        "1",
        "--report",
        "json",
        "-q",
        "--log",
        log.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", crate::common::stderr(&o));
    serde_json::from_slice(&o.stdout).unwrap()
}

/// A one-actor shot the quad can frame: it keeps a metre from actors, so the framings are
/// medium long shots (1.37 m away with its lens) rather than the AR.Drone's medium shots.
const ONE_ACTOR: &str = "stage 8m x 6m x 3m\ndrone arducopter-quad\n\
                         actor A height 1.80m at (0, 0) facing 0deg\n\
                         MLS on A front for 4s\n\
                         then dolly to MLS on A 34backright over 6s\n\
                         then hold for 4s\n";

/// `shots/NAME` (or [`ONE_ACTOR`] for `one-actor.psl`) through SITL: completed, its path held
/// within [`MAX_RMS_M`] RMS and no worse than [`MAX_RATIO_TO_SIMULATOR`] times the embedded
/// simulator's figure.
fn flies_through_sitl(name: &str) {
    let Some(sitl) = sitl(name) else {
        return;
    };
    let dir = temp_dir(&format!("sitl-{name}"));
    let script = if name == "one-actor.psl" {
        let path = dir.path().join(name);
        std::fs::write(&path, ONE_ACTOR).unwrap();
        path
    } else {
        for_arducopter(name, dir.path())
    };
    let simulated = fly_simulator(&script, dir.path());
    let flown = fly_sitl(&sitl, &script, dir.path(), "");
    let rms = |r: &serde_json::Value| r["rms_position_error_m"].as_f64().unwrap();
    eprintln!(
        "{name} through SITL: {:.1} cm RMS ({:.1} cm max), heading {:.2}° RMS, saturated \
         {:.1} %, framing {}; the embedded simulator: {:.1} cm RMS",
        rms(&flown) * 100.0,
        flown["max_position_error_m"].as_f64().unwrap() * 100.0,
        flown["rms_heading_error_rad"]
            .as_f64()
            .unwrap()
            .to_degrees(),
        flown["saturated_fraction"].as_f64().unwrap() * 100.0,
        flown["rms_framing_error"],
        rms(&simulated) * 100.0
    );
    assert_eq!(flown["completed"], true, "{flown}");
    assert!(rms(&flown) <= MAX_RMS_M, "{flown}");
    assert!(
        rms(&flown) <= MAX_RATIO_TO_SIMULATOR * rms(&simulated),
        "{} against the simulator's {}",
        rms(&flown),
        rms(&simulated)
    );
}

#[test]
fn the_square_flies_through_arducopter_sitl() {
    flies_through_sitl("square.psl");
}

#[test]
fn the_helix_flies_through_arducopter_sitl() {
    flies_through_sitl("helix.psl");
}

#[test]
fn a_one_actor_shot_flies_through_arducopter_sitl() {
    flies_through_sitl("one-actor.psl");
}

/// A high angle on one actor through SITL with its camera mount: the flight commands the
/// mount's pitch every tick (the gimbal protocol v2), the mount follows within 3° RMS of the
/// pitch asked (read back from the log's `/gimbal`, from 2 s after the first command), and
/// the actor is framed within 0.05 of the frame (RMS, measured with the pitch reported).
#[test]
fn a_high_angle_points_sitls_camera_mount() {
    let Some(sitl) = sitl("high angle") else {
        return;
    };
    let dir = temp_dir("sitl-gimbal");
    let script = dir.path().join("high-angle.psl");
    let text = "stage 8m x 6m x 3m\ndrone arducopter-quad\n\
                actor A height 1.80m at (0, 0) facing 0deg\n\
                high angle MLS on A front for 6s\nthen hold for 4s\n";
    std::fs::write(&script, text).unwrap();
    let flown = fly_sitl(&sitl, &script, dir.path(), GIMBAL_PARAMS);
    assert_eq!(flown["completed"], true, "{flown}");
    assert!(
        flown["rms_position_error_m"].as_f64().unwrap() <= MAX_RMS_M,
        "{flown}"
    );
    let framing = flown["rms_framing_error"].as_f64().unwrap();
    assert!(framing <= 0.05, "{flown}");
    let bytes = std::fs::read(dir.path().join("flight.mcap")).unwrap();
    let gimbal: Vec<_> = mcap::MessageStream::new(&bytes)
        .unwrap()
        .map(|m| m.unwrap())
        .filter(|m| m.channel.topic == "/gimbal")
        .map(|m| dronecine_mcap::log::plots::decode_gimbal(&m.data).unwrap())
        .collect();
    let first_s = gimbal.first().expect("/gimbal in the log").0;
    let errors_deg: Vec<f64> = (gimbal.iter())
        .filter(|(t_s, _)| *t_s > first_s + 2.0)
        .filter_map(|(_, g)| g.reported_rad.map(|r| (r - g.asked_rad).to_degrees()))
        .collect();
    assert!(errors_deg.len() > 100, "{} reports", errors_deg.len());
    let rms_deg = (errors_deg.iter().map(|e| e * e).sum::<f64>() / errors_deg.len() as f64).sqrt();
    eprintln!(
        "high angle through SITL: the mount within {rms_deg:.2}° RMS of the pitch asked \
         ({} reports), framing {framing:.3}, {:.1} cm RMS",
        errors_deg.len(),
        flown["rms_position_error_m"].as_f64().unwrap() * 100.0
    );
    assert!(rms_deg <= 3.0, "{rms_deg}°");
}

/// `calibrate` through the MAVLink backend on SITL's vehicle: every axis fitted (the command
/// refuses a fit below its R² bar), each gain and time constant near the built-in profile's
/// (which is this vehicle's calibration), and the square flown with the calibrated profile
/// within [`MAX_RMS_M`].
#[test]
fn calibrate_fits_sitls_vehicle_and_the_fit_flies() {
    let Some(sitl) = sitl("calibrate") else {
        return;
    };
    let dir = temp_dir("sitl-calibrate");
    let fitted = dir.path().join("fitted.toml");
    let args = format!(
        "calibrate --profile arducopter-quad --drone {drone} -o '{fitted}'",
        drone = sitl_drone(),
        fitted = fitted.display(),
    );
    let calibration = dir.path().join("calibration");
    std::fs::create_dir_all(&calibration).unwrap();
    in_sitl(&sitl, &calibration, "", &args);
    let got = dronecine_profile::Profile::load(&fitted).unwrap().0;
    let want = dronecine_profile::Profile::builtin("arducopter-quad").unwrap();
    let (g, w) = (&got.model, &want.model);
    let pairs = [
        (
            "K_roll",
            g.gain_roll_mps_per_rad,
            w.gain_roll_mps_per_rad,
            0.15,
        ),
        (
            "K_pitch",
            g.gain_pitch_mps_per_rad,
            w.gain_pitch_mps_per_rad,
            0.15,
        ),
        ("tau_roll", g.tau_roll_s, w.tau_roll_s, 0.25),
        ("tau_pitch", g.tau_pitch_s, w.tau_pitch_s, 0.25),
        ("K_vz", g.gain_vz, w.gain_vz, 0.15),
        ("tau_vz", g.tau_vz_s, w.tau_vz_s, 0.30),
        ("K_yaw", g.gain_yaw, w.gain_yaw, 0.15),
    ];
    for (name, got, want, share) in pairs {
        eprintln!("calibrate through SITL: {name} {got:.3} (the built-in profile's {want:.3})");
        assert!(
            (got - want).abs() <= share * want,
            "{name}: {got} against {want} (±{share})"
        );
    }
    let square = for_arducopter("square.psl", dir.path());
    let text = std::fs::read_to_string(&square).unwrap().replace(
        "drone arducopter-quad",
        &format!("drone \"{}\"", fitted.display()),
    );
    std::fs::write(&square, text).unwrap();
    let flight = dir.path().join("flight");
    std::fs::create_dir_all(&flight).unwrap();
    let flown = fly_sitl(&sitl, &square, &flight, "");
    let rms_m = flown["rms_position_error_m"].as_f64().unwrap();
    eprintln!(
        "the square through SITL with the calibrated profile: {:.1} cm RMS, saturated {:.1} %",
        rms_m * 100.0,
        flown["saturated_fraction"].as_f64().unwrap() * 100.0
    );
    assert_eq!(flown["completed"], true, "{flown}");
    assert!(rms_m <= MAX_RMS_M, "{flown}");
}
