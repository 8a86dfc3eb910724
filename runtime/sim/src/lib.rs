//! The embedded AR.Drone 2.0 simulator: a world with the true drone, the motion-capture
//! system and the live actors, behind the [`Drone`], [`Mocap`] and [`Clock`] traits, so the
//! flight loop flies it exactly as it flies the hardware, as fast as the CPU allows.
//!
//! The simulated drone is harder than the servo's model: attitude lag, firmware limits,
//! quadratic drag, asymmetric vertical response, yaw-rate lag, command latency, radio loss,
//! mocap noise and dropouts, wind gusts, actors who do not walk the script exactly, battery
//! drain — each switchable in [`Effects`], each seeded. With [`Effects::none`] the plant is
//! exactly the servo's model (see `plant.rs`).
//!
//! When the profile has a pitch gimbal, so has the simulated camera ([`SimGimbal`]): it turns
//! toward the pitch last asked ([`Drone::point_camera`]) at the profile's rate, within its
//! range, step by step with the plant, and reports where it is
//! ([`Drone::camera_pitch_rad`]). Without one the camera is fixed and reports nothing.
//!
//! One [`Simulator`] owns the world; [`SimDrone`], [`SimMocap`] and [`SimClock`] are handles on
//! it (`Rc<RefCell<_>>`, single-threaded). [`SimClock::sleep_until`] advances the physics; the
//! mocap produces a frame every `1/mocap_rate_hz` of world time, whether or not anyone polls.
//! Nothing allocates per tick. Same seed and same calls give bit-identical results. The
//! actors and the mocap's noise do not depend on the drone: [`SimMocap`] can hand out a copy
//! of them that runs ahead of the world on another thread (`ActorWorld`, through
//! `Mocap::actors_ahead`, when [`SimConfig::actors_ahead`] asks), on the same schedule
//! (`next_event`) and with the same random draws. While the flight takes the actors from that
//! copy (`Mocap::actors_from_feed`), the world's own frames leave them out and only draw their
//! noise, so the actors are computed once per flight, not twice.
//!
//! Modules: `config` (settings, defaults, validation), `plant` (physics, firmware, radio link),
//! `actors`, `smooth` (smooth OU processes), `rng` (xoshiro256++ and the ziggurat).

mod actors;
mod config;
mod plant;
mod rng;
mod smooth;

pub use config::{Effects, SimConfig, SimError};
pub use plant::{LINK_CAPACITY, TIME_EPS_S};

use std::cell::RefCell;
use std::rc::Rc;

use dronecine_backend::frames::{self, Command};
use dronecine_backend::{
    ActorFeed, BackendError, BodyPose, Clock, Drone, FlightState, Mocap, MocapFrame, Telemetry,
};
use dronecine_compiler::reference::ActorPose;
use dronecine_grammar::script::Scene;
use dronecine_profile::{Gimbal, Profile};

use actors::Actors;
use plant::{Link, Mode, Packet, Plant};
use rng::{Rng, Ziggurat};
use smooth::SmoothOu;

/// Random stream ids (see `rng.rs`; actors use theirs from 1000 on).
const STREAM_RADIO: u64 = 1;
const STREAM_WIND_X: u64 = 2;
const STREAM_WIND_Y: u64 = 3;
const STREAM_MOCAP_NOISE: u64 = 4;
const STREAM_MOCAP_DROPOUT: u64 = 5;

/// The true state of the world, for tests and metrics (what no backend can tell).
#[derive(Clone, Debug, PartialEq)]
pub struct Truth {
    pub t_s: f64,
    pub position_m: [f64; 3],
    pub velocity_mps: [f64; 3],
    /// True attitude, in the command's signs (`frames::Command`).
    pub roll_rad: f64,
    pub pitch_rad: f64,
    /// Counter-clockwise from +x, wrapped to (−π, π].
    pub heading_rad: f64,
    /// `ċ`, counter-clockwise positive.
    pub heading_rate_radps: f64,
    /// The horizontal wind the last plant step felt.
    pub wind_mps: [f64; 2],
    pub state: FlightState,
    pub battery_percent: f64,
    /// Where each actor truly is (feet on the floor), in the script's order.
    pub actors: Vec<ActorPose>,
}

impl Default for Truth {
    fn default() -> Truth {
        Truth {
            t_s: 0.0,
            position_m: [0.0; 3],
            velocity_mps: [0.0; 3],
            roll_rad: 0.0,
            pitch_rad: 0.0,
            heading_rad: 0.0,
            heading_rate_radps: 0.0,
            wind_mps: [0.0; 2],
            state: FlightState::Landed,
            battery_percent: 0.0,
            actors: Vec::new(),
        }
    }
}

/// The simulated camera's pitch gimbal: it turns toward the pitch asked at its rate, within
/// its range. It starts level (clamped into its range).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SimGimbal {
    pub min_rad: f64,
    pub max_rad: f64,
    pub rate_radps: f64,
    /// Where the camera points now (up positive).
    pub pitch_rad: f64,
    /// The pitch last asked, clamped into the range.
    pub target_rad: f64,
}

impl SimGimbal {
    /// The gimbal of a profile, level; `None` for a camera fixed to the body.
    pub fn of(gimbal: &Gimbal) -> Option<SimGimbal> {
        match *gimbal {
            Gimbal::None => None,
            Gimbal::Pitch {
                min_rad,
                max_rad,
                rate_radps,
            } => {
                let level = 0f64.clamp(min_rad, max_rad);
                Some(SimGimbal {
                    min_rad,
                    max_rad,
                    rate_radps,
                    pitch_rad: level,
                    target_rad: level,
                })
            }
        }
    }

    /// Asks for `pitch_rad`, held inside the range; a pitch that is not a number is ignored.
    pub fn point(&mut self, pitch_rad: f64) {
        if !pitch_rad.is_nan() {
            self.target_rad = pitch_rad.clamp(self.min_rad, self.max_rad);
        }
    }

    /// Turns toward the pitch asked for `dt_s`, at most its rate.
    pub fn step(&mut self, dt_s: f64) {
        let most = self.rate_radps * dt_s;
        let to_go = self.target_rad - self.pitch_rad;
        self.pitch_rad = if to_go.abs() <= most {
            self.target_rad
        } else {
            self.pitch_rad + most.copysign(to_go)
        };
    }
}

/// What happened to the command packets so far.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LinkStats {
    /// Packets sent while flying (commands and hovers).
    pub sent: u64,
    /// Lost by the radio.
    pub lost: u64,
    /// Arrived at the drone.
    pub delivered: u64,
}

#[derive(Clone)]
struct MocapGen {
    rate_hz: f64,
    /// Index of the next frame to produce (frame `n` is at `n / rate`).
    next: u64,
    noise_rng: Rng,
    dropout_rng: Rng,
    noise: bool,
    dropouts: bool,
    sigma_p: f64,
    sigma_h: f64,
    p_enter: f64,
    p_exit: f64,
    /// In a dropout burst: the drone, then each actor.
    burst: Vec<bool>,
    latest: MocapFrame,
}

/// The shared world behind the handles.
struct World {
    now_s: f64,
    plant: Plant,
    link: Link,
    radio_rng: Rng,
    latency_s: f64,
    loss_p: f64,
    wind: [SmoothOu; 2],
    wind_on: bool,
    last_wind: [f64; 2],
    actors: Actors,
    mocap: MocapGen,
    battery_on: bool,
    /// The camera's gimbal, when the profile has one.
    gimbal: Option<SimGimbal>,
    /// [`SimConfig::actors_ahead`].
    actors_ahead: bool,
    /// The flight takes the actors' part of the frames from the copy ahead
    /// ([`Mocap::actors_from_feed`]): the frames leave it out.
    actors_from_feed: bool,
    zig: &'static Ziggurat,
}

/// What the world does next on its way to `t_s`: the mocap frame due before the plant's next
/// step ends, else that step, else nothing (the world is at `t_s`). One schedule, for the
/// world and its actors-only copy ([`ActorWorld`]): the frames come at the same moments of
/// the physics in both.
enum Event {
    Frame(f64),
    Step,
    Done,
}

/// The schedule's next [`Event`] from step `k` (of `h` seconds) on the way to `t_s`, with the
/// next frame due at `t_frame` ([`MocapGen::next_frame_s`], which changes only when a frame
/// is taken: the loops that follow the schedule compute it once per frame, not per step).
fn next_event(k: u64, h: f64, t_frame: f64, t_s: f64) -> Event {
    let t_end = (k + 1) as f64 * h;
    if t_frame <= t_s + TIME_EPS_S && t_frame < t_end - TIME_EPS_S {
        Event::Frame(t_frame)
    } else if t_end <= t_s + TIME_EPS_S {
        Event::Step
    } else {
        Event::Done
    }
}

impl MocapGen {
    /// When the next frame is due.
    fn next_frame_s(&self) -> f64 {
        self.next as f64 / self.rate_hz
    }

    /// The newest frame into `frame` if it is not `last_returned` (which it becomes): what a
    /// poll returns, each frame once.
    fn take_latest(&self, last_returned: &mut Option<u64>, frame: &mut MocapFrame) -> bool {
        let latest = &self.latest;
        if *last_returned == Some(latest.frame) {
            return false;
        }
        *last_returned = Some(latest.frame);
        frame.t_s = latest.t_s;
        frame.received_s = latest.t_s;
        frame.frame = latest.frame;
        frame.drone = latest.drone;
        frame.actors.clone_from(&latest.actors);
        true
    }

    /// Takes the frame at `t_s` into `latest`: the drone where `drone_at` says (asked only
    /// when it is tracked in this frame), every actor where they are, each with its noise and
    /// dropouts. The random draws do not depend on where the bodies are, so an actors-only
    /// copy that passes any `drone_at` draws the same numbers and finds the same actors; and
    /// without `actors` (the flight takes them from that copy: [`Mocap::actors_from_feed`])
    /// the actors are left out (`None`), their noise drawn all the same.
    fn emit(
        &mut self,
        t_s: f64,
        mut actors: Option<&mut Actors>,
        zig: &Ziggurat,
        drone_at: impl FnOnce() -> ([f64; 3], f64),
    ) {
        let m = self;
        let n = m.next;
        m.next += 1;
        m.latest.t_s = t_s;
        m.latest.frame = n;
        // Dropout chains (Gilbert): enter a burst with p_enter, leave with p_exit = 1/length.
        if m.dropouts {
            for b in m.burst.iter_mut() {
                let u = m.dropout_rng.uniform();
                *b = if *b { u >= m.p_exit } else { u < m.p_enter };
            }
        }
        m.latest.drone = (!m.burst[0]).then(|| m.seen(drone_at(), zig));
        for i in 0..m.latest.actors.len() {
            // Actors move whether tracked or not: read every frame, forward in time.
            let at = actors.as_mut().map(|a| {
                let p = a.pose(i, t_s, zig);
                (p.position_m, p.facing_rad)
            });
            m.latest.actors[i] = match at {
                _ if m.burst[i + 1] => None,
                Some(at) => Some(m.seen(at, zig)),
                None => {
                    m.left_out(zig);
                    None
                }
            };
        }
    }

    /// A body tracked in this frame at `at` (position, heading), with the mocap's noise: the
    /// same draws wherever it is.
    #[inline(always)]
    fn seen(&mut self, at: ([f64; 3], f64), zig: &Ziggurat) -> BodyPose {
        let (mut p, mut c) = at;
        if self.noise {
            for x in &mut p {
                *x += self.sigma_p * self.noise_rng.normal(zig);
            }
            c = wrap(c + self.sigma_h * self.noise_rng.normal(zig));
        }
        BodyPose {
            position_m: p,
            heading_rad: c,
        }
    }

    /// [`MocapGen::seen`]'s draws for a tracked body the frame leaves out.
    #[inline(always)]
    fn left_out(&mut self, zig: &Ziggurat) {
        if self.noise {
            for _ in 0..4 {
                self.noise_rng.normal(zig);
            }
        }
    }
}

impl World {
    fn advance_to(&mut self, t_s: f64) {
        if !t_s.is_finite() || t_s <= self.now_s {
            return;
        }
        let mut t_frame = self.mocap.next_frame_s();
        loop {
            match next_event(self.plant.k, self.plant.h, t_frame, t_s) {
                Event::Frame(t) => {
                    self.emit_frame(t);
                    t_frame = self.mocap.next_frame_s();
                }
                Event::Step => {
                    if self.wind_on {
                        let t = self.plant.t_k();
                        self.last_wind = [
                            self.wind[0].value(t, self.zig),
                            self.wind[1].value(t, self.zig),
                        ];
                    }
                    self.plant.step(&mut self.link, self.last_wind);
                    if let Some(g) = &mut self.gimbal {
                        g.step(self.plant.h);
                    }
                }
                Event::Done => break,
            }
        }
        self.now_s = t_s;
    }

    fn emit_frame(&mut self, t_s: f64) {
        let plant = &self.plant;
        let actors = (!self.actors_from_feed).then_some(&mut self.actors);
        self.mocap.emit(t_s, actors, self.zig, || {
            (plant.position_at(t_s), plant.heading_at(t_s))
        });
    }

    fn truth_into(&mut self, out: &mut Truth) {
        let t = self.now_s;
        let p = &self.plant;
        out.t_s = t;
        out.position_m = p.position_at(t);
        out.velocity_mps = p.v;
        out.roll_rad = p.tilt[0];
        out.pitch_rad = p.tilt[1];
        out.heading_rad = p.heading_at(t);
        out.heading_rate_radps = p.heading_rate();
        out.wind_mps = self.last_wind;
        out.state = p.state;
        out.battery_percent = p.battery;
        out.actors.clear();
        for i in 0..self.actors.len() {
            out.actors.push(self.actors.pose(i, t, self.zig));
        }
    }

    fn send(&mut self, packet: Packet) {
        if self.plant.state != FlightState::Flying {
            return;
        }
        self.link.sent += 1;
        if self.loss_p > 0.0 && self.radio_rng.uniform() < self.loss_p {
            self.link.lost += 1;
            return;
        }
        self.link.push(self.now_s + self.latency_s, packet);
    }
}

/// `frames::wrap_angle_rad`, skipped when the angle is already in (−π, π].
#[inline]
pub(crate) fn wrap(c: f64) -> f64 {
    if c > std::f64::consts::PI || c <= -std::f64::consts::PI {
        frames::wrap_angle_rad(c)
    } else {
        c
    }
}

/// The simulator: owns the world and hands out the backend handles.
pub struct Simulator {
    world: Rc<RefCell<World>>,
}

impl Simulator {
    /// A world at t = 0: the drone landed at `start_position_m`, the actors at their start
    /// marks, mocap frame 0 taken. Bad settings or profile values are an error.
    pub fn new(
        config: &SimConfig,
        profile: &Profile,
        scene: &Scene,
    ) -> Result<Simulator, SimError> {
        config.validate()?;
        let zig = Ziggurat::get();
        let plant = Plant::new(config, profile)?;
        let eff = config.effects;
        let actors = Actors::new(config, scene, zig);
        let n_actors = actors.len();
        let f = config.mocap_dropout_fraction;
        let len = config.mocap_dropout_burst_frames;
        let mocap = MocapGen {
            rate_hz: config.mocap_rate_hz,
            next: 0,
            noise_rng: Rng::stream(config.seed, STREAM_MOCAP_NOISE),
            dropout_rng: Rng::stream(config.seed, STREAM_MOCAP_DROPOUT),
            noise: eff.mocap_noise,
            dropouts: eff.mocap_dropouts && f > 0.0,
            sigma_p: config.mocap_position_sigma_m,
            sigma_h: config.mocap_heading_sigma_rad,
            // Stationary share in a burst: p_enter / (p_enter + p_exit) = f.
            p_enter: f / (len * (1.0 - f)),
            p_exit: 1.0 / len,
            burst: vec![false; n_actors + 1],
            latest: MocapFrame {
                t_s: 0.0,
                received_s: 0.0,
                frame: 0,
                drone: None,
                actors: vec![None; n_actors],
            },
        };
        let wind = [STREAM_WIND_X, STREAM_WIND_Y].map(|s| {
            SmoothOu::new(
                Rng::stream(config.seed, s),
                config.wind_sigma_mps,
                config.wind_tau_s,
                f64::INFINITY,
                // Turbulence keeps its OU spectrum (Dryden's first-order roll-off) to 8/τ.
                8.0,
                zig,
            )
        });
        let mut world = World {
            now_s: 0.0,
            plant,
            link: Link::new(),
            radio_rng: Rng::stream(config.seed, STREAM_RADIO),
            latency_s: if eff.latency { config.latency_s } else { 0.0 },
            loss_p: if eff.radio_loss {
                config.radio_loss_probability
            } else {
                0.0
            },
            wind,
            wind_on: eff.wind,
            last_wind: [0.0; 2],
            actors,
            mocap,
            battery_on: eff.battery,
            gimbal: SimGimbal::of(&profile.camera.gimbal),
            actors_ahead: config.actors_ahead,
            actors_from_feed: false,
            zig,
        };
        world.emit_frame(0.0);
        Ok(Simulator {
            world: Rc::new(RefCell::new(world)),
        })
    }

    pub fn drone(&self) -> SimDrone {
        SimDrone {
            world: Rc::clone(&self.world),
        }
    }

    pub fn mocap(&self) -> SimMocap {
        SimMocap {
            world: Rc::clone(&self.world),
            last_returned: None,
        }
    }

    pub fn clock(&self) -> SimClock {
        SimClock {
            world: Rc::clone(&self.world),
        }
    }

    /// The world time.
    pub fn now_s(&self) -> f64 {
        self.world.borrow().now_s
    }

    /// The true state now (allocates the actor vector; see [`Simulator::truth_into`]).
    pub fn truth(&self) -> Truth {
        let mut t = Truth::default();
        self.truth_into(&mut t);
        t
    }

    /// The true state now, written in place (no allocation once `out.actors` has room).
    pub fn truth_into(&self, out: &mut Truth) {
        self.world.borrow_mut().truth_into(out);
    }

    /// The set-points the drone's firmware is flying now: `Some` while flying a command
    /// (`Drone::send`), `None` when landed, taking off, landing, hovering on its own, or cut.
    pub fn applied_command(&self) -> Option<Command> {
        let w = self.world.borrow();
        match (w.plant.state, w.plant.mode) {
            (FlightState::Flying, Mode::Progressive(c)) => Some(c),
            _ => None,
        }
    }

    /// The camera's gimbal now, when the profile has one.
    pub fn gimbal(&self) -> Option<SimGimbal> {
        self.world.borrow().gimbal
    }

    pub fn link_stats(&self) -> LinkStats {
        let w = self.world.borrow();
        LinkStats {
            sent: w.link.sent,
            lost: w.link.lost,
            delivered: w.link.delivered,
        }
    }
}

/// The simulated drone ([`Drone`]). Take-off, landing and emergency (AT*REF, which the real
/// backend repeats until acknowledged) act at once; `send` and `hover` are command packets
/// (AT*PCMD) subject to radio loss and latency, and ignored unless the drone is `Flying`.
pub struct SimDrone {
    world: Rc<RefCell<World>>,
}

impl Drone for SimDrone {
    fn take_off(&mut self) -> Result<(), BackendError> {
        let mut w = self.world.borrow_mut();
        let p = &mut w.plant;
        match p.state {
            FlightState::Emergency => Err(BackendError::Refused(
                "the motors were cut (emergency); the simulated drone cannot fly again".into(),
            )),
            FlightState::Flying | FlightState::TakingOff => Ok(()),
            FlightState::Landed | FlightState::Landing => {
                if w.battery_on && w.plant.battery < w.plant.min_takeoff_battery {
                    return Err(BackendError::Refused(format!(
                        "battery at {:.0} %, below the take-off minimum",
                        w.plant.battery
                    )));
                }
                w.plant.take_off();
                w.link.clear();
                Ok(())
            }
        }
    }

    fn land(&mut self) -> Result<(), BackendError> {
        let mut w = self.world.borrow_mut();
        if matches!(w.plant.state, FlightState::Flying | FlightState::TakingOff) {
            w.plant.state = FlightState::Landing;
            w.plant.mode = Mode::Hover;
            w.link.clear();
        }
        Ok(())
    }

    fn emergency(&mut self) -> Result<(), BackendError> {
        let mut w = self.world.borrow_mut();
        w.plant.state = FlightState::Emergency;
        w.plant.mode = Mode::Hover;
        w.link.clear();
        Ok(())
    }

    fn send(&mut self, command: &Command) -> Result<(), BackendError> {
        if !command.is_finite() {
            return Err(BackendError::Refused(
                "a command with a NaN or infinite set-point".into(),
            ));
        }
        self.world.borrow_mut().send(Packet::Command(*command));
        Ok(())
    }

    fn hover(&mut self) -> Result<(), BackendError> {
        self.world.borrow_mut().send(Packet::Hover);
        Ok(())
    }

    fn telemetry(&mut self) -> Telemetry {
        let w = self.world.borrow();
        Telemetry {
            state: w.plant.state,
            battery_percent: w.plant.battery,
            link_age_s: 0.0,
        }
    }

    fn point_camera(&mut self, pitch_rad: f64) -> Result<(), BackendError> {
        if let Some(g) = &mut self.world.borrow_mut().gimbal {
            g.point(pitch_rad);
        }
        Ok(())
    }

    fn camera_pitch_rad(&mut self) -> Option<f64> {
        self.world.borrow().gimbal.map(|g| g.pitch_rad)
    }
}

/// The simulated motion capture ([`Mocap`]): each handle returns every newest frame once.
pub struct SimMocap {
    world: Rc<RefCell<World>>,
    last_returned: Option<u64>,
}

impl Mocap for SimMocap {
    fn poll(&mut self, frame: &mut MocapFrame) -> Result<bool, BackendError> {
        Ok(self
            .world
            .borrow()
            .mocap
            .take_latest(&mut self.last_returned, frame))
    }

    fn action(&mut self, t_s: f64) {
        self.world.borrow_mut().actors.action(t_s);
    }

    fn actors_from_feed(&mut self, on: bool) {
        let mut w = self.world.borrow_mut();
        // Only with a copy to take them from (one taken, or one to take).
        w.actors_from_feed = on && w.actors_ahead;
    }

    fn actors_ahead(&self) -> Option<Box<dyn ActorFeed>> {
        let w = self.world.borrow();
        if !w.actors_ahead {
            return None;
        }
        Some(Box::new(ActorWorld {
            now_s: w.now_s,
            k: w.plant.k,
            h: w.plant.h,
            actors: w.actors.clone(),
            mocap: w.mocap.clone(),
            zig: w.zig,
            last_returned: self.last_returned,
        }))
    }
}

/// The world's actors and motion capture without the drone ([`Mocap::actors_ahead`]): a
/// copy taken from the world that goes on by the same schedule ([`next_event`]), stepping
/// the plant's clock but not its physics, and takes each frame as the world does, drawing
/// the same random numbers (the drone's noise included, added to nothing). Its frames'
/// actors are the world's, bit for bit (`runtime/tests/it/ahead.rs` flies both ways).
struct ActorWorld {
    now_s: f64,
    /// The plant's step count and step, as in the world.
    k: u64,
    h: f64,
    actors: Actors,
    mocap: MocapGen,
    zig: &'static Ziggurat,
    /// The last frame returned, as [`SimMocap`]'s.
    last_returned: Option<u64>,
}

impl ActorFeed for ActorWorld {
    fn poll_at(&mut self, t_s: f64, frame: &mut MocapFrame) -> bool {
        if t_s.is_finite() && t_s > self.now_s {
            let mut t_frame = self.mocap.next_frame_s();
            loop {
                match next_event(self.k, self.h, t_frame, t_s) {
                    Event::Frame(t) => {
                        let actors = Some(&mut self.actors);
                        self.mocap.emit(t, actors, self.zig, || ([0.0; 3], 0.0));
                        t_frame = self.mocap.next_frame_s();
                    }
                    Event::Step => self.k += 1,
                    Event::Done => break,
                }
            }
            self.now_s = t_s;
        }
        let taken = self.mocap.take_latest(&mut self.last_returned, frame);
        if taken {
            // The drone's place in it is nothing: the feed is the actors'.
            frame.drone = None;
        }
        taken
    }
}

/// The world's clock ([`Clock`]): `sleep_until` runs the physics up to that time.
pub struct SimClock {
    world: Rc<RefCell<World>>,
}

impl Clock for SimClock {
    fn now_s(&mut self) -> f64 {
        self.world.borrow().now_s
    }

    fn sleep_until(&mut self, t_s: f64) {
        self.world.borrow_mut().advance_to(t_s);
    }
}
