//! The ArduPilot Copter backend: the vehicle over MAVLink 2 (UDP, TCP or a serial port)
//! behind the [`Drone`](dronecine_backend::Drone) trait, with the motion capture forwarded
//! to the autopilot's EKF and a camera gimbal driven through the gimbal protocol v2.
//!
//! - [`url`]: the address, `mavlink://udp:HOST:PORT`, `mavlink://udpin:HOST:PORT`,
//!   `mavlink://tcp:HOST:PORT` or `mavlink:///dev/PORT?baud=N`.
//! - [`frames`]: **the stage's frames ↔ MAVLink's** (NED, FRD, quaternions) and the generic
//!   command → SET_ATTITUDE_TARGET mapping.
//! - [`messages`]: every message the backend sends, one function each, and ArduCopter's
//!   mode numbers.
//! - [`state`]: the vehicle as its messages describe it, and its events.
//! - [`link`]: the connection, the reader thread and our 1 Hz heartbeat.
//! - [`params`]: parameter reads, the pre-flight parameter check, the limits.
//! - [`drone`]: [`MavlinkDrone`], the [`Drone`](dronecine_backend::Drone), and the
//!   [`PoseForwarder`] that sends it the motion capture.
//! - [`truth`]: a motion capture made from a simulator's truth (SIM_STATE), for software in
//!   the loop.

pub mod drone;
pub mod frames;
pub mod link;
pub mod messages;
pub mod params;
pub mod state;
pub mod truth;
pub mod url;

pub use drone::{GeoOrigin, MavlinkDrone, MavlinkOptions, Phase, PoseForwarder};
pub use params::{ParamCheck, VehicleLimits, WrongParam};
pub use state::{VehicleEvent, VehicleState};
pub use url::MavlinkUrl;
