//! The MCAP files dronecine writes and reads: the compiled reference of `dronecine compile`
//! ([`output`]) and the flight log of `dronecine shoot` ([`log`]), both opening in Foxglove.
//! Their per-tick topics are CDR with `ros2msg` schemas, through one CDR writer and reader
//! ([`output::cdr`]); what a flight records each tick is [`record`], the contract between the
//! flight loop, the log and `replay`.
//!
//! Invariant: a topic's schema text, its encoder and its decoder sit side by side and change
//! together; the tests decode every topic with the `mcap` crate's reader, and CI decodes every
//! CDR message with the mcap project's Python ROS 2 support, as Foxglove would.

pub mod log;
pub mod output;
pub mod record;
