//! The OptiTrack NatNet wire codecs (protocols.md §4.1): pure functions, no sockets.
//!
//! - [`frame`]: the server-info handshake (`NAT_CONNECT` → `NAT_SERVERINFO` with the
//!   NatNet version), frame-of-data decoding and encoding for NatNet 3.0–4.1, and the
//!   conversion of Motive's Y-up / Z-up axes to the world frame of `frames.rs`.
//!
//! The backend that wires these to sockets (command port 1510, data port 1511, multicast
//! group 239.255.42.99 or unicast, keep-alives) lives elsewhere.

pub mod client;
pub mod frame;
pub mod rig;
