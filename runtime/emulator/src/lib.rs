//! The emulators behind `dronecine emulate`: the embedded simulator (`sim`) run in real
//! time behind the real wire protocols, so the backends (and the drones' own clients) fly it
//! over UDP. This module is the AR.Drone 2.0 + OptiTrack one (`dronecine emulate ardrone`:
//! AT commands, navdata, NatNet); [`crazyflie_emulator`] is the Crazyflie + OptiTrack one
//! (`dronecine emulate crazyflie`: CRTP over UDP, NatNet), its firmware in [`crazyflie`].
//!
//! [`Emulator::start`] binds the sockets (errors come back at once), then one thread owns the
//! simulator (which is single-threaded) and the sockets, non-blocking, and loops every
//! [`EmulatorConfig::step_s`] (5 ms) of wall time:
//!
//! 1. drain the AT port: each datagram goes to the emulated firmware ([`firmware`]);
//! 2. drain the navdata port: a datagram of 1–4 bytes is the client's trigger (`01 00 00 00`,
//!    or NAD's single `01`); its sender becomes the navdata destination, replied to from
//!    the navdata port (the drone answers the trigger's source address) — longer ones are
//!    counted and dropped;
//! 3. drain the NatNet command port ([`motive`]), answering each requester;
//! 4. advance the simulator to the wall time since start (`SimClock::sleep_until`), times
//!    [`EmulatorConfig::time_scale`] (1: real time);
//! 5. send the newest mocap frame, if the simulator made one, to the data address (unicast
//!    or a multicast group); several frames made in one step (a late step) send only the
//!    newest, the frame-number gap showing the loss, as with a real network;
//! 6. send navdata when due (15 Hz bootstrap and demo, 200 Hz full; no burst after a late
//!    step);
//! 7. publish the counters and the truth for [`EmulatorHandle::status`], then sleep to the
//!    next step.
//!
//! An emergency toggled off (REF bit 8 in emergency) rebuilds the simulator where the drone
//! stands (landed, same heading and battery; the simulator itself cannot leave its emergency
//! state); its clock then restarts, so the actors' blocking restarts from the script's t = 0.
//! Nothing on the network can panic the loop: every datagram is parsed by the codecs'
//! error-returning decoders and a bad one is counted.

pub mod crazyflie;
pub mod crazyflie_emulator;
pub mod firmware;
pub mod motive;
mod natnet_io;
mod running;
mod stage;

use std::fmt;
use std::io;
use std::net::{IpAddr, Ipv4Addr, SocketAddr, SocketAddrV4, UdpSocket};
use std::time::Instant;

use dronecine_grammar::script::Scene;
use dronecine_profile::Profile;

use dronecine_natnet::frame::{
    NatNetError, UpAxis, Version, COMMAND_PORT, DATA_PORT, MULTICAST_GROUP,
};
use dronecine_sim::{SimConfig, SimError, Truth};

pub use crazyflie_emulator::{
    CrazyflieEmulator, CrazyflieEmulatorConfig, CrazyflieHandle, CrazyflieStatus,
};
pub use firmware::{AtCounters, Firmware, Limits, NavdataMode};
pub use motive::{Motive, ACTOR_ID_BASE, DRONE_ID};
use natnet_io::{NatNetCounts, NatNetIo};
use running::{check_step_s, Paced, Published, Running};
use stage::Stage;

/// The AR.Drone's AT command port.
pub const AT_PORT: u16 = 5556;
/// The AR.Drone's navdata port.
pub const NAVDATA_PORT: u16 = 5554;

/// Where NatNet frames go.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum NatNetData {
    /// To one address (a client's data socket).
    Unicast(SocketAddr),
    /// To a multicast group (Motive's default: 239.255.42.99:1511).
    Multicast(SocketAddrV4),
}

impl NatNetData {
    /// An address: multicast when its IP is a multicast address.
    pub fn from_addr(addr: SocketAddr) -> NatNetData {
        match addr {
            SocketAddr::V4(a) if a.ip().is_multicast() => NatNetData::Multicast(a),
            a => NatNetData::Unicast(a),
        }
    }

    pub fn addr(&self) -> SocketAddr {
        match *self {
            NatNetData::Unicast(a) => a,
            NatNetData::Multicast(a) => SocketAddr::V4(a),
        }
    }
}

/// The NatNet side: the command port bound on the emulator's host, the data destination,
/// the NatNet version announced and streamed, and Motive's up axis.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct NatNetConfig {
    pub command_port: u16,
    pub data: NatNetData,
    pub version: Version,
    pub up_axis: UpAxis,
}

impl Default for NatNetConfig {
    /// Motive's defaults: command port 1510, multicast 239.255.42.99:1511, NatNet 4.1, Y-up.
    fn default() -> Self {
        NatNetConfig {
            command_port: COMMAND_PORT,
            data: NatNetData::Multicast(SocketAddrV4::new(
                Ipv4Addr::from(MULTICAST_GROUP),
                DATA_PORT,
            )),
            version: Version::V4_1,
            up_axis: UpAxis::Y,
        }
    }
}

/// Everything [`Emulator::start`] needs.
#[derive(Clone, Debug)]
pub struct EmulatorConfig {
    /// The address the AT, navdata and NatNet command sockets bind to.
    pub host: IpAddr,
    /// Port 0 binds an ephemeral port ([`EmulatorHandle::at_addr`] tells which).
    pub at_port: u16,
    pub navdata_port: u16,
    /// `None`: no NatNet.
    pub natnet: Option<NatNetConfig>,
    /// The simulator's settings (seed, effects).
    pub sim: SimConfig,
    pub profile: Profile,
    /// The actors come from its scene; an empty scene has none.
    pub scene: Scene,
    /// The loop's period (wall clock). Default 5 ms.
    pub step_s: f64,
    /// Simulated seconds per wall second. Default 1 (real time); tests fly faster. The
    /// protocol timings (navdata rates, watchdog, sequence reset) stay on the wall clock.
    pub time_scale: f64,
}

impl EmulatorConfig {
    /// Standard ports (5556, 5554, NatNet 1510 → multicast 1511) on 127.0.0.1, all the
    /// simulator's effects, seeded by `seed`.
    pub fn new(profile: Profile, scene: Scene, seed: u64) -> Self {
        EmulatorConfig {
            host: IpAddr::V4(Ipv4Addr::LOCALHOST),
            at_port: AT_PORT,
            navdata_port: NAVDATA_PORT,
            natnet: Some(NatNetConfig::default()),
            sim: SimConfig::new(seed),
            profile,
            scene,
            step_s: 0.005,
            time_scale: 1.0,
        }
    }
}

/// A scene with no actors (the emulator without a script): an 8 × 8 × 3 m stage.
pub fn empty_scene() -> Scene {
    Scene {
        stage: dronecine_grammar::script::Stage {
            size_m: [8.0, 8.0, 3.0],
        },
        lens: None,
        drone: None,
        actors: Vec::new(),
        blocking: Vec::new(),
    }
}

/// Why the emulator could not start (or stopped).
#[derive(Debug)]
pub enum EmulatorError {
    /// A socket could not be bound or set up.
    Socket {
        what: &'static str,
        addr: SocketAddr,
        error: io::Error,
    },
    Sim(SimError),
    NatNet(NatNetError),
    /// A bad setting (the step).
    Config(String),
    /// The emulator's thread died.
    Thread(String),
}

impl fmt::Display for EmulatorError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            EmulatorError::Socket { what, addr, error } => {
                write!(f, "cannot set up the {what} socket on {addr}: {error}")
            }
            EmulatorError::Sim(e) => write!(f, "{e}"),
            EmulatorError::NatNet(e) => write!(f, "NatNet: {e:?}"),
            EmulatorError::Config(m) => write!(f, "{m}"),
            EmulatorError::Thread(m) => write!(f, "the emulator's thread failed: {m}"),
        }
    }
}

impl std::error::Error for EmulatorError {}

/// What the emulator did so far.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Counters {
    pub at: AtCounters,
    /// Trigger packets received on the navdata port.
    pub navdata_triggers: u64,
    /// Datagrams on the navdata port that are not a trigger.
    pub navdata_rejected: u64,
    pub navdata_sent: u64,
    /// NatNet command datagrams answered (or accepted, keep-alives).
    pub natnet_requests: u64,
    /// NatNet command datagrams that are not NatNet messages.
    pub natnet_rejected: u64,
    pub frames_sent: u64,
    /// Sends that failed (the destination unreachable, …).
    pub send_errors: u64,
    /// Emergencies cleared (simulator rebuilt).
    pub emergency_resets: u64,
    /// Loop steps run.
    pub steps: u64,
}

/// A snapshot of the emulator, refreshed every step.
#[derive(Clone, Debug, Default)]
pub struct Status {
    pub counters: Counters,
    /// The simulator's true state (world frame, `frames.rs`).
    pub truth: Truth,
    /// Whether the drone flies a progressive command (not its own hover).
    pub commanded: bool,
    pub navdata_mode: Option<NavdataMode>,
    pub command_ack: bool,
    pub com_watchdog: bool,
    pub limits: Option<Limits>,
    /// Where navdata goes (the last trigger's sender).
    pub navdata_client: Option<SocketAddr>,
    /// Seconds of wall time since the start.
    pub uptime_s: f64,
    /// When the first REF that asked the drone to land arrived (processed on receipt).
    pub first_land_at: Option<Instant>,
    /// When the first REF that cut the motors arrived.
    pub first_cut_at: Option<Instant>,
}

/// The emulator: see the module docs.
pub struct Emulator;

/// The running emulator. Dropping it stops it.
pub struct EmulatorHandle {
    at_addr: SocketAddr,
    navdata_addr: SocketAddr,
    natnet_command_addr: Option<SocketAddr>,
    natnet_data: Option<NatNetData>,
    running: Running<Status>,
}

impl EmulatorHandle {
    /// The bound AT command address.
    pub fn at_addr(&self) -> SocketAddr {
        self.at_addr
    }

    /// The bound navdata address (trigger to it; navdata comes from it).
    pub fn navdata_addr(&self) -> SocketAddr {
        self.navdata_addr
    }

    /// The bound NatNet command address.
    pub fn natnet_command_addr(&self) -> Option<SocketAddr> {
        self.natnet_command_addr
    }

    /// Where NatNet frames go.
    pub fn natnet_data(&self) -> Option<NatNetData> {
        self.natnet_data
    }

    pub fn status(&self) -> Status {
        self.running.read(Status::clone)
    }

    pub fn counters(&self) -> Counters {
        self.running.read(|s| s.counters)
    }

    pub fn truth(&self) -> Truth {
        self.running.read(|s| s.truth.clone())
    }

    /// Whether the loop still runs.
    pub fn is_running(&self) -> bool {
        self.running.is_running()
    }

    /// Stops the loop and waits for it.
    pub fn stop(mut self) -> Result<(), EmulatorError> {
        self.running.stop()
    }

    /// Waits until the loop ends (it runs until [`EmulatorHandle::stop`] or the process ends).
    pub fn wait(mut self) -> Result<(), EmulatorError> {
        self.running.join()
    }
}

pub(crate) fn bind(what: &'static str, addr: SocketAddr) -> Result<UdpSocket, EmulatorError> {
    let err = |error| EmulatorError::Socket { what, addr, error };
    let s = UdpSocket::bind(addr).map_err(err)?;
    s.set_nonblocking(true).map_err(err)?;
    Ok(s)
}

impl Emulator {
    /// Binds the sockets, builds the simulator and starts the loop.
    pub fn start(config: EmulatorConfig) -> Result<EmulatorHandle, EmulatorError> {
        check_step_s(config.step_s)?;
        if !(config.time_scale.is_finite() && config.time_scale > 0.0 && config.time_scale <= 100.0)
        {
            return Err(EmulatorError::Config(format!(
                "the emulator's time scale {} is outside (0, 100]",
                config.time_scale
            )));
        }
        config.sim.validate().map_err(EmulatorError::Sim)?;
        let at = bind("AT", SocketAddr::new(config.host, config.at_port))?;
        let nav = bind("navdata", SocketAddr::new(config.host, config.navdata_port))?;
        let local = |s: &UdpSocket, what| {
            s.local_addr().map_err(|error| EmulatorError::Socket {
                what,
                addr: SocketAddr::new(config.host, 0),
                error,
            })
        };
        let at_addr = local(&at, "AT")?;
        let navdata_addr = local(&nav, "navdata")?;
        let (natnet, natnet_command_addr) =
            NatNetIo::bind_configured(config.host, config.natnet.as_ref())?;
        let natnet_data = config.natnet.map(|n| n.data);
        let running = Running::spawn(move |status| {
            let mut lp = Loop::new(config, at, nav, natnet, status)?;
            lp.publish(0.0);
            Ok(lp)
        })?;
        Ok(EmulatorHandle {
            at_addr,
            navdata_addr,
            natnet_command_addr,
            natnet_data,
            running,
        })
    }
}

/// Largest datagram read.
const RECV_BUF: usize = 65_536;
/// At most this many datagrams per socket per step (the others wait for the next step).
pub(crate) const MAX_DATAGRAMS_PER_STEP: usize = 512;

struct Loop {
    cfg: EmulatorConfig,
    at: UdpSocket,
    nav: UdpSocket,
    fw: Firmware,
    stage: Stage,
    nav_dest: Option<SocketAddr>,
    next_nav_s: f64,
    truth: Truth,
    counters: Counters,
    status: Published<Status>,
    start: Instant,
    rx: Vec<u8>,
    tx: Vec<u8>,
}

impl Paced for Loop {
    fn step(&mut self) {
        Loop::step(self);
    }

    fn step_s(&self) -> f64 {
        self.cfg.step_s
    }

    fn now_s(&self) -> f64 {
        Loop::now_s(self)
    }
}

impl Loop {
    fn new(
        cfg: EmulatorConfig,
        at: UdpSocket,
        nav: UdpSocket,
        natnet: Option<NatNetIo>,
        status: Published<Status>,
    ) -> Result<Loop, EmulatorError> {
        let stage = Stage::new(&cfg.sim, &cfg.profile, &cfg.scene, natnet, cfg.time_scale)?;
        let fw = Firmware::new(cfg.sim.battery_min_takeoff_percent);
        Ok(Loop {
            cfg,
            at,
            nav,
            fw,
            stage,
            nav_dest: None,
            next_nav_s: 0.0,
            truth: Truth::default(),
            counters: Counters::default(),
            status,
            start: Instant::now(),
            rx: vec![0; RECV_BUF],
            tx: vec![0; RECV_BUF],
        })
    }

    fn now_s(&self) -> f64 {
        self.start.elapsed().as_secs_f64()
    }

    fn step(&mut self) {
        self.drain_at();
        self.drain_navdata();
        self.drain_natnet();
        let now = self.now_s();
        self.fw.tick(now);
        self.stage.advance(now, &mut self.truth);
        let counts = self.stage.send_frame(now, &mut self.tx);
        self.count(counts);
        self.send_navdata(now);
        self.counters.steps += 1;
        self.publish(now);
    }

    fn drain_at(&mut self) {
        for _ in 0..MAX_DATAGRAMS_PER_STEP {
            let n = match self.at.recv_from(&mut self.rx) {
                Ok((n, _)) => n,
                Err(e) if e.kind() == io::ErrorKind::WouldBlock => break,
                Err(_) => continue,
            };
            let now = self.now_s();
            let before = self.fw.counters();
            let out = self.fw.datagram(&self.rx[..n], now, self.stage.drone());
            if out.clear_emergency {
                self.clear_emergency(now);
            }
            self.note_operator_commands(&before);
        }
    }

    /// The arrival of the first land and motor-cut commands, for who measures how soon the
    /// operator's command reached the drone.
    fn note_operator_commands(&mut self, before: &AtCounters) {
        let after = self.fw.counters();
        let Ok(mut s) = self.status.lock() else {
            return;
        };
        if after.land_requests > before.land_requests && s.first_land_at.is_none() {
            s.first_land_at = Some(Instant::now());
        }
        if after.motor_cuts > before.motor_cuts && s.first_cut_at.is_none() {
            s.first_cut_at = Some(Instant::now());
        }
    }

    fn clear_emergency(&mut self, now: f64) {
        let cfg = &self.cfg;
        if self
            .stage
            .rest(&cfg.sim, &cfg.profile, &cfg.scene, now, &mut self.truth)
        {
            self.counters.emergency_resets += 1;
        }
    }

    fn drain_navdata(&mut self) {
        for _ in 0..MAX_DATAGRAMS_PER_STEP {
            let (n, from) = match self.nav.recv_from(&mut self.rx) {
                Ok(r) => r,
                Err(e) if e.kind() == io::ErrorKind::WouldBlock => break,
                Err(_) => continue,
            };
            if (1..=4).contains(&n) {
                self.counters.navdata_triggers += 1;
                if self.nav_dest != Some(from) {
                    self.nav_dest = Some(from);
                    self.next_nav_s = 0.0; // at once
                }
            } else {
                self.counters.navdata_rejected += 1;
            }
        }
    }

    fn drain_natnet(&mut self) {
        let counts = self.stage.drain_natnet(&mut self.rx, &mut self.tx);
        self.count(counts);
    }

    fn count(&mut self, c: NatNetCounts) {
        self.counters.natnet_requests += c.requests;
        self.counters.natnet_rejected += c.rejected;
        self.counters.frames_sent += c.frames;
        self.counters.send_errors += c.send_errors;
    }

    fn send_navdata(&mut self, now: f64) {
        let Some(dest) = self.nav_dest else { return };
        if now < self.next_nav_s {
            return;
        }
        let period = 1.0 / self.fw.navdata_mode().rate_hz();
        self.next_nav_s = if self.next_nav_s + period < now {
            now + period
        } else {
            self.next_nav_s + period
        };
        let commanded = self.stage.commanded();
        match self.fw.navdata(&self.truth, commanded, now, &mut self.tx) {
            Ok(len) => match self.nav.send_to(&self.tx[..len], dest) {
                Ok(_) => self.counters.navdata_sent += 1,
                Err(_) => self.counters.send_errors += 1,
            },
            Err(_) => self.counters.send_errors += 1,
        }
    }

    fn publish(&mut self, now: f64) {
        let mut counters = self.counters;
        counters.at = self.fw.counters();
        let commanded = self.stage.commanded();
        if let Ok(mut s) = self.status.lock() {
            s.counters = counters;
            s.truth.clone_from(&self.truth);
            s.commanded = commanded;
            s.navdata_mode = Some(self.fw.navdata_mode());
            s.command_ack = self.fw.command_ack();
            s.com_watchdog = self.fw.com_watchdog();
            s.limits = Some(self.fw.limits());
            s.navdata_client = self.nav_dest;
            s.uptime_s = now;
        }
    }
}
