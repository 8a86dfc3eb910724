//! The Crazyflie + OptiTrack emulator behind `dronecine emulate crazyflie`: the embedded
//! simulator in real time behind CRTP over UDP (one packet per datagram, as cflib's UDP
//! driver and the Crazyflie simulators speak it) and NatNet, so the Crazyflie backend (or a
//! cflib client) flies it over loopback with the motion capture from the same world.
//!
//! The simulator is flown with the script's drone profile (its model and limits), its
//! take-off height set to 0.1 m (the lift-off of a Crazyflie whose motors start: the climb
//! above is the client's) and its watchdog to the firmware's 0.5 s. Every
//! [`CrazyflieEmulatorConfig::step_s`] of wall time its loop:
//!
//! 1. drains the CRTP port: each datagram goes to the emulated firmware ([`crate::crazyflie`]),
//!    whose answers go back to the sender, which becomes the client;
//! 2. answers the NatNet command port;
//! 3. advances the simulator to the wall time since its start;
//! 4. lets the firmware's time pass (estimate, watchdog) and sends the log samples due to the
//!    client; a drone whose motors were cut in the air is rebuilt, landed, where it rests;
//! 5. sends the newest motion-capture frame (rigid body 1 the drone, 2, 3, … the actors);
//! 6. publishes its status ([`CrazyflieHandle::status`]): the counters, the truth, and the
//!    set-points received while flying, for the rate a client commands at.

use std::io;
use std::net::{IpAddr, Ipv4Addr, SocketAddr, UdpSocket};
use std::time::Instant;

use dronecine_backend::FlightState;
use dronecine_crazyflie::crtp::Packet;
use dronecine_grammar::script::Scene;
use dronecine_profile::Profile;
use dronecine_sim::{SimConfig, Truth};

use crate::crazyflie::{CrazyflieCounters, CrazyflieFirmware};
use crate::natnet_io::{NatNetCounts, NatNetIo};
use crate::running::{check_step_s, Paced, Published, Running};
use crate::stage::Stage;
use crate::{bind, EmulatorError, NatNetConfig, NatNetData};

/// cflib's first UDP port.
pub const CRTP_PORT: u16 = 19850;
/// The simulated lift-off's height: the motors' start lifts the drone this high.
pub const LIFT_OFF_M: f64 = 0.1;
/// The firmware's watchdog: no set-point for this long, and it levels out.
pub const LEVEL_OUT_S: f64 = 0.5;

/// Everything [`CrazyflieEmulator::start`] needs.
#[derive(Clone, Debug)]
pub struct CrazyflieEmulatorConfig {
    /// The address the CRTP and NatNet command sockets bind to.
    pub host: IpAddr,
    /// 0 binds an ephemeral port ([`CrazyflieHandle::addr`] tells which).
    pub port: u16,
    pub natnet: Option<NatNetConfig>,
    pub sim: SimConfig,
    pub profile: Profile,
    pub scene: Scene,
    /// The CRTP protocol version the firmware announces (12 by default).
    pub protocol: u8,
    /// The loop's period (wall clock). Default 5 ms.
    pub step_s: f64,
}

impl CrazyflieEmulatorConfig {
    /// 127.0.0.1:19850, NatNet on Motive's defaults, protocol 12, all the simulator's
    /// effects seeded by `seed`, with the lift-off height and the watchdog above.
    pub fn new(profile: Profile, scene: Scene, seed: u64) -> Self {
        CrazyflieEmulatorConfig {
            host: IpAddr::V4(Ipv4Addr::LOCALHOST),
            port: CRTP_PORT,
            natnet: Some(NatNetConfig::default()),
            sim: crazyflie_sim(SimConfig::new(seed)),
            profile,
            scene,
            protocol: 12,
            step_s: 0.005,
        }
    }
}

/// `sim` with the emulated Crazyflie's lift-off height and watchdog.
pub fn crazyflie_sim(sim: SimConfig) -> SimConfig {
    SimConfig {
        takeoff_height_m: LIFT_OFF_M,
        watchdog_s: LEVEL_OUT_S,
        ..sim
    }
}

/// A snapshot of the emulator, refreshed every step.
#[derive(Clone, Debug, Default)]
pub struct CrazyflieStatus {
    pub firmware: CrazyflieCounters,
    pub natnet_requests: u64,
    pub natnet_rejected: u64,
    pub frames_sent: u64,
    pub send_errors: u64,
    /// Simulators rebuilt after a fall.
    pub rests: u64,
    pub truth: Truth,
    /// Where the answers and samples go (the last sender).
    pub client: Option<SocketAddr>,
    /// Wall seconds the drone spent flying (its state `Flying`), and the set-points
    /// (altHold and position) received meanwhile.
    pub flying_s: f64,
    pub setpoints_flying: u64,
    pub locked: bool,
    pub estimator: u8,
    pub uptime_s: f64,
}

impl CrazyflieStatus {
    /// The set-points a second received while flying.
    pub fn setpoint_rate_hz(&self) -> Option<f64> {
        (self.flying_s > 0.0).then(|| self.setpoints_flying as f64 / self.flying_s)
    }
}

/// The emulator: see the module docs.
pub struct CrazyflieEmulator;

/// The running emulator. Dropping it stops it.
pub struct CrazyflieHandle {
    addr: SocketAddr,
    natnet_command_addr: Option<SocketAddr>,
    natnet_data: Option<NatNetData>,
    running: Running<CrazyflieStatus>,
}

impl CrazyflieHandle {
    /// The bound CRTP address.
    pub fn addr(&self) -> SocketAddr {
        self.addr
    }

    pub fn natnet_command_addr(&self) -> Option<SocketAddr> {
        self.natnet_command_addr
    }

    pub fn natnet_data(&self) -> Option<NatNetData> {
        self.natnet_data
    }

    pub fn status(&self) -> CrazyflieStatus {
        self.running.read(CrazyflieStatus::clone)
    }

    /// Whether the loop still runs.
    pub fn is_running(&self) -> bool {
        self.running.is_running()
    }

    /// Waits until the loop ends (it runs until dropped or the process ends).
    pub fn wait(mut self) -> Result<(), EmulatorError> {
        self.running.join()
    }
}

impl CrazyflieEmulator {
    /// Binds the sockets, builds the simulator and starts the loop.
    pub fn start(config: CrazyflieEmulatorConfig) -> Result<CrazyflieHandle, EmulatorError> {
        check_step_s(config.step_s)?;
        config.sim.validate().map_err(EmulatorError::Sim)?;
        let at = SocketAddr::new(config.host, config.port);
        let crtp = bind("CRTP", at)?;
        let addr = crtp.local_addr().map_err(|error| EmulatorError::Socket {
            what: "CRTP",
            addr: at,
            error,
        })?;
        let (natnet, natnet_command_addr) =
            NatNetIo::bind_configured(config.host, config.natnet.as_ref())?;
        let natnet_data = config.natnet.map(|n| n.data);
        let running = Running::spawn(move |shared| CfLoop::new(config, crtp, natnet, shared))?;
        Ok(CrazyflieHandle {
            addr,
            natnet_command_addr,
            natnet_data,
            running,
        })
    }
}

/// Largest datagram read (a CRTP packet is at most 31 bytes; more is read to reject it).
const RECV_BUF: usize = 2048;
/// At most this many datagrams per step (the others wait for the next step).
const MAX_DATAGRAMS_PER_STEP: usize = 512;

struct CfLoop {
    cfg: CrazyflieEmulatorConfig,
    crtp: UdpSocket,
    fw: CrazyflieFirmware,
    stage: Stage,
    client: Option<SocketAddr>,
    truth: Truth,
    out: Vec<Packet>,
    status: CrazyflieStatus,
    shared: Published<CrazyflieStatus>,
    start: Instant,
    last_step_s: f64,
    rx: Vec<u8>,
    tx: Vec<u8>,
}

impl Paced for CfLoop {
    fn step(&mut self) {
        CfLoop::step(self);
    }

    fn step_s(&self) -> f64 {
        self.cfg.step_s
    }

    fn now_s(&self) -> f64 {
        self.start.elapsed().as_secs_f64()
    }
}

impl CfLoop {
    fn new(
        cfg: CrazyflieEmulatorConfig,
        crtp: UdpSocket,
        natnet: Option<NatNetIo>,
        shared: Published<CrazyflieStatus>,
    ) -> Result<CfLoop, EmulatorError> {
        let stage = Stage::new(&cfg.sim, &cfg.profile, &cfg.scene, natnet, 1.0)?;
        Ok(CfLoop {
            fw: CrazyflieFirmware::new(cfg.protocol),
            cfg,
            crtp,
            stage,
            client: None,
            truth: Truth::default(),
            out: Vec::with_capacity(64),
            status: CrazyflieStatus::default(),
            shared,
            start: Instant::now(),
            last_step_s: 0.0,
            rx: vec![0; RECV_BUF],
            tx: vec![0; 65_536],
        })
    }

    fn step(&mut self) {
        let setpoints_before = self.setpoints();
        self.drain_crtp();
        let counts = self.stage.drain_natnet(&mut self.rx, &mut self.tx);
        self.count(counts);
        let now = Paced::now_s(self);
        self.stage.advance(now, &mut self.truth);
        let outcome = self
            .fw
            .tick(now, self.stage.drone(), &self.truth, &mut self.out);
        self.send_out();
        if outcome.rest {
            self.rest(now);
        }
        let counts = self.stage.send_frame(now, &mut self.tx);
        self.count(counts);
        if self.truth.state == FlightState::Flying {
            self.status.flying_s += now - self.last_step_s;
            self.status.setpoints_flying += self.setpoints() - setpoints_before;
        }
        self.last_step_s = now;
        self.publish(now);
    }

    fn setpoints(&self) -> u64 {
        let c = self.fw.counters();
        c.alt_holds + c.positions
    }

    fn drain_crtp(&mut self) {
        for _ in 0..MAX_DATAGRAMS_PER_STEP {
            let (n, from) = match self.crtp.recv_from(&mut self.rx) {
                Ok(r) => r,
                Err(e) if e.kind() == io::ErrorKind::WouldBlock => break,
                Err(_) => continue,
            };
            self.client = Some(from);
            let now = Paced::now_s(self);
            self.fw.datagram(
                &self.rx[..n],
                now,
                self.stage.drone(),
                &self.truth,
                &mut self.out,
            );
            self.send_out();
        }
    }

    /// Sends the firmware's packets to the client.
    fn send_out(&mut self) {
        let Some(client) = self.client else {
            self.out.clear();
            return;
        };
        for p in self.out.drain(..) {
            if self.crtp.send_to(p.as_bytes(), client).is_err() {
                self.status.send_errors += 1;
            }
        }
    }

    /// The drone whose motors were cut rests on the floor: landed there, a new world, whose
    /// state the status published this step carries with the rest.
    fn rest(&mut self, now: f64) {
        let cfg = &self.cfg;
        if self
            .stage
            .rest(&cfg.sim, &cfg.profile, &cfg.scene, now, &mut self.truth)
        {
            self.status.rests += 1;
        }
    }

    fn count(&mut self, c: NatNetCounts) {
        self.status.natnet_requests += c.requests;
        self.status.natnet_rejected += c.rejected;
        self.status.frames_sent += c.frames;
        self.status.send_errors += c.send_errors;
    }

    fn publish(&mut self, now: f64) {
        self.status.firmware = self.fw.counters();
        self.status.truth.clone_from(&self.truth);
        self.status.client = self.client;
        self.status.locked = self.fw.locked();
        self.status.estimator = self.fw.estimator();
        self.status.uptime_s = now;
        if let Ok(mut s) = self.shared.lock() {
            s.clone_from(&self.status);
        }
    }
}
