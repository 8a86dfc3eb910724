//! A motion capture made from a simulator's truth: ArduPilot's SITL reports the vehicle's
//! true position and attitude as SIM_STATE, which [`TruthMocap`] gives the flight as motion
//! capture frames of the drone (no actors). With it, a flight through SITL is judged on
//! where the simulated vehicle really was, and the autopilot's EKF is fed that truth.
//!
//! The stage frame: the vehicle's position at the first SIM_STATE received is the stage
//! point given at construction; east, north and up from there are the stage's axes as
//! [`crate::frames`] maps NED to them.

use std::sync::Arc;
use std::time::Instant;

use dronecine_backend::{BackendError, BodyPose, Mocap, MocapFrame};

use crate::frames::ned_to_pose;
use crate::link::Link;

/// The WGS-84 equatorial radius: the flat-earth step from degrees to metres over a stage.
const EARTH_RADIUS_M: f64 = 6_378_137.0;

/// The vehicle's true pose from SIM_STATE, as motion capture frames.
pub struct TruthMocap {
    link: Arc<Link>,
    at_m: [f64; 3],
    epoch: Instant,
    /// Latitude, longitude (degrees) and altitude (m) of the first SIM_STATE.
    reference: Option<[f64; 3]>,
    last: Option<Instant>,
    frame: u64,
}

impl TruthMocap {
    /// Frames timed on a clock started at `epoch`; the first SIM_STATE's position is `at_m`.
    pub fn new(link: Arc<Link>, at_m: [f64; 3], epoch: Instant) -> TruthMocap {
        TruthMocap {
            link,
            at_m,
            epoch,
            reference: None,
            last: None,
            frame: 0,
        }
    }
}

/// North, east and down (m) of `p` from `reference` (latitude, longitude in degrees,
/// altitude in m), on a flat earth.
pub fn ned_from_geodetic_m(reference: [f64; 3], p: [f64; 3]) -> [f64; 3] {
    let north = (p[0] - reference[0]).to_radians() * EARTH_RADIUS_M;
    let east = (p[1] - reference[1]).to_radians()
        * EARTH_RADIUS_M
        * dronecine_math::cos(reference[0].to_radians());
    [north, east, reference[2] - p[2]]
}

impl Mocap for TruthMocap {
    fn poll(&mut self, frame: &mut MocapFrame) -> Result<bool, BackendError> {
        let Some(sim) = self.link.state().sim else {
            return Ok(false);
        };
        if self.last == Some(sim.received) {
            return Ok(false);
        }
        self.last = Some(sim.received);
        let here = [sim.lat_deg, sim.lon_deg, sim.alt_m];
        let reference = *self.reference.get_or_insert(here);
        let ned_m = ned_from_geodetic_m(reference, here);
        let pose = ned_to_pose(ned_m, sim.attitude_rad[2]);
        let t_s = sim
            .received
            .saturating_duration_since(self.epoch)
            .as_secs_f64();
        self.frame += 1;
        frame.t_s = t_s;
        frame.received_s = t_s;
        frame.frame = self.frame;
        frame.drone = Some(BodyPose {
            position_m: [
                pose.position_m[0] + self.at_m[0],
                pose.position_m[1] + self.at_m[1],
                pose.position_m[2] + self.at_m[2],
            ],
            heading_rad: pose.heading_rad,
        });
        frame.actors.clear();
        Ok(true)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A metre north and a metre east of the reference, and a metre up, at 47° N.
    #[test]
    fn geodetic_steps_are_metres_north_east_down() {
        let r = [47.0, 8.0, 500.0];
        let m_per_deg_lat = EARTH_RADIUS_M * std::f64::consts::PI / 180.0;
        let north = ned_from_geodetic_m(r, [47.0 + 1.0 / m_per_deg_lat, 8.0, 500.0]);
        assert!(
            (north[0] - 1.0).abs() < 1e-9 && north[1].abs() < 1e-12,
            "{north:?}"
        );
        let east_deg = 1.0 / (m_per_deg_lat * dronecine_math::cos(47f64.to_radians()));
        let east = ned_from_geodetic_m(r, [47.0, 8.0 + east_deg, 501.0]);
        assert!(
            (east[1] - 1.0).abs() < 1e-9 && east[0].abs() < 1e-12,
            "{east:?}"
        );
        assert!(
            (east[2] + 1.0).abs() < 1e-12,
            "up is negative down: {east:?}"
        );
    }
}
