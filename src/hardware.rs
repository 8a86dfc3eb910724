//! `--drone URL --mocap URL [--rig FILE]`, shared by `shoot` and `calibrate`: both or neither,
//! the URLs parsed, the rig loaded (or the emulator's numbered layout, with a note).

use std::path::Path;

use dronecine_diag as diag;
use dronecine_natnet::rig::{Rig, RigError};
use dronecine_runtime::{DroneUrl, HardwareTarget, MocapUrl};

/// A real drone and its motion capture.
pub type Target = HardwareTarget;

/// `None` without `--drone` and `--mocap` (the command flies the simulator); the error
/// message (without `error: `) when only one is given, when `--rig` comes without them, a
/// URL is malformed or the rig file is bad (its diagnostics printed first, in `color`).
/// `actors`: the scene's actor names in order (`None` for a command that flies no scene),
/// numbered 2, 3, … when there is no rig file.
pub fn target(
    command: &str,
    drone: Option<&str>,
    mocap: Option<&str>,
    rig: Option<&Path>,
    actors: Option<&[&str]>,
    color: bool,
) -> Result<Option<Target>, String> {
    match (drone, mocap) {
        (None, None) => match rig {
            // A rig file without the hardware it describes is a forgotten --drone/--mocap,
            // not something to ignore: the flight would silently be simulated.
            Some(path) => Err(format!(
                "--rig {} needs --drone and --mocap: it names a real flight's rigid bodies \
                 (without both, {command} flies the simulator)",
                path.display()
            )),
            None => Ok(None),
        },
        (Some(d), Some(m)) => {
            let drone = DroneUrl::parse(d).map_err(|e| format!("--drone: {e}"))?;
            let mocap = MocapUrl::parse(m).map_err(|e| format!("--mocap: {e}"))?;
            let rig = match rig {
                // ArduPilot's simulator's truth has no rigid bodies.
                None if mocap == MocapUrl::SitlTruth => Rig::numbered(actors.unwrap_or(&[])),
                Some(path) => match Rig::load(path) {
                    Ok(rig) => rig,
                    Err(RigError::Invalid {
                        source,
                        diagnostics,
                    }) => {
                        let name = path.display().to_string();
                        err!("{}", diag::render(&name, &source, &diagnostics, color, 100));
                        return Err(format!("the rig file `{name}` is not valid"));
                    }
                    Err(e) => return Err(e.to_string()),
                },
                None => {
                    let names = actors.unwrap_or(&[]);
                    if actors.is_some() {
                        errln!(
                            "note: no --rig: the drone is rigid body 1 and the actors 2, 3, … in \
                             the script's order, Y up (the layout of `dronecine emulate`)"
                        );
                    } else {
                        errln!(
                            "note: no --rig: the drone is rigid body 1, Y up (the layout of \
                             `dronecine emulate`)"
                        );
                    }
                    Rig::numbered(names)
                }
            };
            Ok(Some(Target {
                drone,
                mocap,
                rig,
                forward_mocap: true,
            }))
        }
        (Some(_), None) => {
            Err("--drone needs --mocap: the servo flies on motion-capture positions".into())
        }
        (None, Some(_)) => Err(format!(
            "--mocap needs --drone (without both, {command} flies the simulator)"
        )),
    }
}
