//! [`LiveWorld`]: the world as it stands, without a flight loop (`emulate --live`: the
//! simulator's truth, the drone and the actors where they truly are), on the flight log's
//! scene topics, `/actors` and `/tf`. Written by the caller's thread (the emulator's own
//! thread never waits for it).

use std::io;

use dronecine_compiler::reference::ActorPose;
use dronecine_mcap::log::{FlightTopics, LogOptions, LogScene};

use crate::server::{LiveOut, LiveServer};

/// The world's poses on a [`LiveServer`] (see the module doc).
pub struct LiveWorld {
    topics: FlightTopics<LiveOut>,
}

impl LiveWorld {
    /// Registers the flight log's topics on `server` and writes the static scene.
    pub fn start(server: &LiveServer, scene: &LogScene, gimbal: bool) -> io::Result<LiveWorld> {
        let topics = FlightTopics::open(server.out(), scene, gimbal, LogOptions::default())?;
        Ok(LiveWorld { topics })
    }

    /// The world at `t_s`: the drone's position and heading, the camera's pitch, the actors.
    pub fn pose(
        &mut self,
        t_s: f64,
        drone: ([f64; 3], f64),
        camera_pitch_rad: f64,
        actors: &[ActorPose],
    ) {
        // The live channels cannot fail a write.
        let _ = self
            .topics
            .write_world(t_s, drone, camera_pitch_rad, actors);
    }
}
