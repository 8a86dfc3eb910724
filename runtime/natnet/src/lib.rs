//! The OptiTrack NatNet backend: its wire codecs, pure functions with byte-layout tests, the
//! rig file, and the [`Mocap`](dronecine_backend::Mocap) over UDP.
//!
//! - [`frame`]: the server-info handshake (`NAT_CONNECT` → `NAT_SERVERINFO` with the
//!   NatNet version), frame-of-data decoding and encoding for NatNet 3.0–4.1, and the
//!   conversion of Motive's Y-up / Z-up axes to the world frame.
//! - [`rig`]: which rigid body is the drone and which each actor (`rig::` diagnostics).
//! - [`client`]: the motion capture over UDP, unicast or multicast, frames timestamped on
//!   arrival on the flight's clock.
//! - [`url`]: the address, `natnet://SERVER[:PORT][?multicast=GROUP|unicast][&data_port=N]`.

pub mod client;
pub mod frame;
pub mod rig;
pub mod url;
