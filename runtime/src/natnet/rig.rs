//! The rig file: which Motive rigid body is the drone and which is each actor, which axis
//! Motive streams as up, and where the mocap origin sits on the stage.
//!
//! ```toml
//! up = "y"              # Motive's up axis: "y" (its default) or "z"
//! drone = 1             # the drone's rigid-body streaming id
//! origin_m = [0.5, -1.0, 0.0]  # optional: the mocap origin in stage coordinates
//! yaw_deg = 90.0        # optional: the mocap x axis, counter-clockwise from stage x
//!
//! [actors]              # one rigid body per scene actor, by the script's names
//! Alice = 2
//! Bob = 3
//! ```
//!
//! A pose goes mocap → world (`natnet::frame::to_world`, by `up`) → stage:
//! `p_stage = origin_m + Rz(yaw)·p_world`, `heading_stage = wrap(heading + yaw)`.
//! Ids must be distinct; unknown keys are refused (a misspelt `orgin_m` is an error, not a
//! silently ignored offset).

use crate::math;
use std::collections::BTreeMap;
use std::fmt;
use std::path::Path;

use serde::Deserialize;

use crate::backend::BodyPose;
use crate::frames::wrap_angle_rad;
use crate::natnet::frame::UpAxis;

/// A parsed, checked rig file.
#[derive(Clone, Debug, PartialEq)]
pub struct Rig {
    pub up: UpAxis,
    pub drone_id: i32,
    /// Actor name → rigid-body id.
    pub actors: BTreeMap<String, i32>,
    pub origin_m: [f64; 3],
    pub yaw_rad: f64,
}

/// Why a rig file was refused (the message names the file when loaded from one).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RigError(pub String);

impl fmt::Display for RigError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for RigError {}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawRig {
    up: String,
    drone: i64,
    #[serde(default)]
    actors: BTreeMap<String, i64>,
    #[serde(default)]
    origin_m: Option<[f64; 3]>,
    #[serde(default)]
    yaw_deg: Option<f64>,
}

fn id(v: i64, what: &str) -> Result<i32, RigError> {
    i32::try_from(v).map_err(|_| {
        RigError(format!(
            "{what}: rigid-body id {v} is out of range (Motive's streaming ids are 32-bit)"
        ))
    })
}

impl Rig {
    /// Parses and checks a rig file's text.
    pub fn from_toml(src: &str) -> Result<Rig, RigError> {
        let raw: RawRig = toml::from_str(src).map_err(|e| RigError(e.to_string()))?;
        let up = match raw.up.to_ascii_lowercase().as_str() {
            "y" => UpAxis::Y,
            "z" => UpAxis::Z,
            other => {
                return Err(RigError(format!(
                    "up = \"{other}\": Motive streams \"y\" (its default) or \"z\" as up"
                )))
            }
        };
        let drone_id = id(raw.drone, "drone")?;
        let mut actors = BTreeMap::new();
        let mut seen: BTreeMap<i32, String> = BTreeMap::new();
        seen.insert(drone_id, "the drone".into());
        for (name, v) in raw.actors {
            let i = id(v, &format!("actors.{name}"))?;
            if let Some(other) = seen.get(&i) {
                return Err(RigError(format!(
                    "actors.{name} = {i}: rigid body {i} is already {other}; each body \
                     tracks one thing"
                )));
            }
            seen.insert(i, format!("actor `{name}`"));
            actors.insert(name, i);
        }
        let origin_m = raw.origin_m.unwrap_or([0.0; 3]);
        if !origin_m.iter().all(|v| v.is_finite()) {
            return Err(RigError(format!(
                "origin_m = {origin_m:?}: the offset must be finite metres"
            )));
        }
        let yaw_deg = raw.yaw_deg.unwrap_or(0.0);
        if !yaw_deg.is_finite() {
            return Err(RigError(format!("yaw_deg = {yaw_deg}: must be finite")));
        }
        Ok(Rig {
            up,
            drone_id,
            actors,
            origin_m,
            yaw_rad: wrap_angle_rad(yaw_deg.to_radians()),
        })
    }

    /// Reads and parses a rig file; errors name the file.
    /// The layout `dronecine emulate` streams: the drone is rigid body 1, the actors 2, 3, …
    /// in the script's order, Y up, the mocap's origin at the stage's.
    pub fn numbered<S: AsRef<str>>(actor_names: &[S]) -> Rig {
        Rig {
            up: UpAxis::Y,
            drone_id: 1,
            actors: actor_names
                .iter()
                .enumerate()
                .map(|(i, n)| (n.as_ref().to_string(), i as i32 + 2))
                .collect(),
            origin_m: [0.0; 3],
            yaw_rad: 0.0,
        }
    }

    pub fn load(path: &Path) -> Result<Rig, RigError> {
        let src = std::fs::read_to_string(path)
            .map_err(|e| RigError(format!("cannot read the rig file {}: {e}", path.display())))?;
        Rig::from_toml(&src).map_err(|e| RigError(format!("rig file {}: {e}", path.display())))
    }

    /// The rigid-body ids of `names` (the scene's actors, in its order); an actor without a
    /// body is an error naming it and the bodies the rig has.
    pub fn actor_ids<I>(&self, names: I) -> Result<Vec<i32>, RigError>
    where
        I: IntoIterator,
        I::Item: AsRef<str>,
    {
        names
            .into_iter()
            .map(|n| {
                let n = n.as_ref();
                self.actors.get(n).copied().ok_or_else(|| {
                    let known: Vec<&str> = self.actors.keys().map(String::as_str).collect();
                    RigError(format!(
                        "actor `{n}` has no rigid body in the rig (its [actors] are: {})",
                        if known.is_empty() {
                            "none".to_string()
                        } else {
                            known.join(", ")
                        }
                    ))
                })
            })
            .collect()
    }

    /// A world-frame pose (mocap origin) in stage coordinates.
    pub fn to_stage(&self, pose: BodyPose) -> BodyPose {
        let (s, c) = math::sin_cos(self.yaw_rad);
        let [x, y, z] = pose.position_m;
        BodyPose {
            position_m: [
                self.origin_m[0] + c * x - s * y,
                self.origin_m[1] + s * x + c * y,
                self.origin_m[2] + z,
            ],
            heading_rad: wrap_angle_rad(pose.heading_rad + self.yaw_rad),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::FRAC_PI_2;

    #[test]
    fn parses_a_full_rig() {
        let rig = Rig::from_toml(
            "up = \"Z\"\ndrone = 7\norigin_m = [1.0, 2.0, 0.0]\nyaw_deg = 90\n\
             [actors]\nAlice = 2\nBob = 3\n",
        )
        .unwrap();
        assert_eq!(rig.up, UpAxis::Z);
        assert_eq!(rig.drone_id, 7);
        assert_eq!(rig.actor_ids(["Bob", "Alice"]).unwrap(), vec![3, 2]);
        // Mocap +x is stage +y after a 90° yaw; the origin is added.
        let p = rig.to_stage(BodyPose {
            position_m: [1.0, 0.0, 0.5],
            heading_rad: 0.0,
        });
        assert!((p.position_m[0] - 1.0).abs() < 1e-12);
        assert!((p.position_m[1] - 3.0).abs() < 1e-12);
        assert_eq!(p.position_m[2], 0.5);
        assert!((p.heading_rad - FRAC_PI_2).abs() < 1e-12);
    }

    #[test]
    fn refuses_bad_rigs_with_clear_messages() {
        for (src, needle) in [
            ("up = \"x\"\ndrone = 1\n", "\"y\" (its default) or \"z\""),
            ("drone = 1\n", "up"),
            (
                "up = \"y\"\ndrone = 1\n[actors]\nA = 1\n",
                "already the drone",
            ),
            (
                "up = \"y\"\ndrone = 1\n[actors]\nA = 2\nB = 2\n",
                "already actor `A`",
            ),
            ("up = \"y\"\ndrone = 1\norgin_m = [0, 0, 0]\n", "orgin_m"),
            ("up = \"y\"\ndrone = 5000000000\n", "out of range"),
            ("up = \"y\"\ndrone = 1\nyaw_deg = nan\n", "finite"),
        ] {
            let e = Rig::from_toml(src).unwrap_err().0;
            assert!(e.contains(needle), "{src:?}: {e}");
        }
        let rig = Rig::from_toml("up = \"y\"\ndrone = 1\n[actors]\nAlice = 2\n").unwrap();
        let e = rig.actor_ids(["Alice", "Bob"]).unwrap_err().0;
        assert!(e.contains("actor `Bob`") && e.contains("Alice"), "{e}");
    }
}
