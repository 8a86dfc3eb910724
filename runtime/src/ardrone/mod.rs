//! The AR.Drone 2.0 wire codecs (protocols.md §1): pure functions, no sockets, no threads.
//!
//! - [`at`]: AT commands (client → drone, UDP 5556): the encoder with its one sequence
//!   counter, the generic command → `AT*PCMD` mapping with a profile's limits, the
//!   start-up `AT*CONFIG` lines, and a tolerant parser for the emulator.
//! - [`navdata`]: navdata packets (drone → client, UDP 5554): the decoder (header, state
//!   bits, options, checksum, demo option), a packet writer, and the sequence rule.
//!
//! The backend that wires these to sockets (navdata kick `01 00 00 00` to 5554, the
//! `general:navdata_demo` / `AT*CTRL=…,5,0` handshake, the 30 ms command tick, the
//! watchdog) lives elsewhere.

pub mod at;
pub mod client;
pub mod navdata;
