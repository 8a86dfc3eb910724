//! The Bitcraze Crazyflie backend: the drone over CRTP, through a Crazyradio
//! (`crazyflie-link`) or UDP (a simulator, `dronecine emulate crazyflie`), behind the
//! [`Drone`](dronecine_backend::Drone) trait, with the motion capture sent to its estimator.
//!
//! - [`url`]: the address, `crazyflie+radio://N/CHANNEL/RATE/ADDRESS` or
//!   `crazyflie+udp://HOST:PORT`.
//! - [`crtp`]: the packets, both ways (pure codecs).
//! - [`frames`]: **the stage's signs ↔ the Crazyflie's**: the generic command as the altHold
//!   set-point, the motion capture as the external pose.
//! - [`log`]: the log blocks the backend reads (estimate, attitude, battery, supervisor).
//! - [`link`]: the transport, its reader and the state it fills.
//! - [`connect`]: the set-up exchanges (protocol version, log TOC, blocks, parameters).
//! - [`drone`]: [`CrazyflieDrone`], and the [`PoseForwarder`] that sends it the motion
//!   capture.

pub mod connect;
pub mod crtp;
pub mod drone;
pub mod frames;
pub mod link;
pub mod log;
#[cfg(feature = "radio")]
mod radio;
mod state;
pub mod url;

pub use drone::{CrazyflieDrone, CrazyflieOptions, Phase, PoseForwarder};
pub use url::CrazyflieUrl;
