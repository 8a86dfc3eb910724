//! The emulators' simulated world on the wall clock, shared by the AR.Drone and the
//! Crazyflie emulators: the simulator (rebuilt, landed, where a drone in emergency rests),
//! the offsets that keep its clock and frame numbers going on across a rebuild, and the
//! motion capture it sends.

use dronecine_backend::{Clock, Mocap, MocapFrame};
use dronecine_grammar::script::Scene;
use dronecine_profile::Profile;
use dronecine_sim::{SimClock, SimConfig, SimDrone, SimError, SimMocap, Simulator, Truth};

use crate::natnet_io::{NatNetCounts, NatNetIo};
use crate::EmulatorError;

/// The simulator and its handles.
struct World {
    sim: Simulator,
    drone: SimDrone,
    mocap: SimMocap,
    clock: SimClock,
}

impl World {
    fn new(cfg: &SimConfig, profile: &Profile, scene: &Scene) -> Result<World, SimError> {
        let sim = Simulator::new(cfg, profile, scene)?;
        Ok(World {
            drone: sim.drone(),
            mocap: sim.mocap(),
            clock: sim.clock(),
            sim,
        })
    }
}

/// The world an emulator's loop advances: simulated time is `(wall − offset) · time_scale`.
pub(crate) struct Stage {
    world: World,
    natnet: Option<NatNetIo>,
    /// Simulated seconds per wall second (1: real time).
    time_scale: f64,
    /// Wall time at which the current simulator's t = 0 was.
    sim_offset_s: f64,
    /// Added to the current simulator's frame numbers.
    frame_offset: u64,
    last_frame_number: Option<u64>,
    frame: MocapFrame,
}

impl Stage {
    /// The world at wall time 0, its frames sent through `natnet` if given.
    pub(crate) fn new(
        cfg: &SimConfig,
        profile: &Profile,
        scene: &Scene,
        natnet: Option<NatNetIo>,
        time_scale: f64,
    ) -> Result<Stage, EmulatorError> {
        Ok(Stage {
            world: World::new(cfg, profile, scene).map_err(EmulatorError::Sim)?,
            natnet,
            time_scale,
            sim_offset_s: 0.0,
            frame_offset: 0,
            last_frame_number: None,
            frame: MocapFrame::default(),
        })
    }

    /// The drone's handle, for the emulated firmware to command.
    pub(crate) fn drone(&mut self) -> &mut SimDrone {
        &mut self.world.drone
    }

    /// Whether the simulator applies a command (it is flown, not left to its watchdog).
    pub(crate) fn commanded(&self) -> bool {
        self.world.sim.applied_command().is_some()
    }

    /// Advances the simulator to wall time `now_s` and reads its truth into `truth`.
    pub(crate) fn advance(&mut self, now_s: f64, truth: &mut Truth) {
        let sim_s = (now_s - self.sim_offset_s) * self.time_scale;
        self.world.clock.sleep_until(sim_s);
        self.world.sim.truth_into(truth);
    }

    /// Rebuilds the world with its drone landed where it stands, with its heading and battery
    /// (the simulator cannot leave its emergency state itself), its clock starting again at
    /// wall time `now_s` and its frame numbers going on; `truth` then reads the new world.
    /// False (the world unchanged) if the simulator refuses the new start.
    pub(crate) fn rest(
        &mut self,
        cfg: &SimConfig,
        profile: &Profile,
        scene: &Scene,
        now_s: f64,
        truth: &mut Truth,
    ) -> bool {
        let t = self.world.sim.truth();
        let mut cfg = cfg.clone();
        cfg.start_position_m = t.position_m;
        cfg.start_heading_rad = t.heading_rad;
        cfg.battery_start_percent = t.battery_percent.clamp(0.0, 100.0);
        let Ok(world) = World::new(&cfg, profile, scene) else {
            return false;
        };
        self.world = world;
        self.sim_offset_s = now_s;
        self.frame_offset = self.last_frame_number.map_or(0, |n| n + 1);
        self.world.sim.truth_into(truth);
        true
    }

    /// Answers the NatNet command port.
    pub(crate) fn drain_natnet(&mut self, rx: &mut [u8], tx: &mut [u8]) -> NatNetCounts {
        let mut counts = NatNetCounts::default();
        if let Some(io) = &mut self.natnet {
            io.drain(rx, tx, &mut counts);
        }
        counts
    }

    /// Sends the newest motion-capture frame, if the simulator made one since the last call,
    /// stamped with the wall time it was captured at.
    pub(crate) fn send_frame(&mut self, now_s: f64, tx: &mut [u8]) -> NatNetCounts {
        let mut counts = NatNetCounts::default();
        if !matches!(self.world.mocap.poll(&mut self.frame), Ok(true)) {
            return counts;
        }
        let number = self.frame_offset + self.frame.frame;
        self.last_frame_number = Some(number);
        if let Some(io) = &mut self.natnet {
            let capture = self.sim_offset_s + self.frame.t_s / self.time_scale;
            io.send_frame(&self.frame, number, capture, now_s, tx, &mut counts);
        }
        counts
    }
}
