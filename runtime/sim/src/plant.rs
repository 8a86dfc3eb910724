//! The true AR.Drone: its flight physics, its firmware (take-off, hover, landing, limits,
//! watchdog) and the radio link that carries its commands.
//!
//! The plant advances on a fixed grid of `step_s`. Per step `k` (from `t_k` to `t_k + h`),
//! with the heading `c_k` frozen for the translation (as the servo model's `M_D[k]`):
//!
//! - attitude: `θ_{k+1} = θ_cmd + (θ_k − θ_cmd)·e^{−a·h}` (exact for a held command) when
//!   `attitude_lag` is on, and the thrust tilts by `sin θ_k`; off, `θ = θ_cmd` and the thrust
//!   input is `θ_cmd` itself;
//! - translation: the air-relative velocity in the body frame lags the commanded body
//!   velocity `G·u`, `G = INPUT_TO_BODY·diag(K_φ, K_θ, K_ż)`, exactly:
//!   `v_b' = G·u + (v_b − G·u)·e^{−h/τ}` per body axis (`frames::body_taus_s`), `v_b = M_Dᵀ(v − w)`,
//!   `v' = M_D·v_b' + w` (w the wind); quadratic drag `−c·|v_rel|·v_rel·h` on top; position
//!   `p' = p + h·v` — with every effect off this is the servo model's `A1`, `B1` with
//!   `T_D = diag(1 − e^{−h/τ})`, exactly;
//! - vertical input `u_z = ż_cmd`, times `descent_gain_factor` when negative and
//!   `asymmetric_vz` is on;
//! - heading: `c' = c + h·K_ψ·frames::heading_rate_radps(r)`, `r` the yaw rate: the command,
//!   or with `yaw_lag` the lagged rate `r' = r_cmd + (r − r_cmd)·e^{−b·h}`.
//!
//! Between grid points the position moves linearly with the step's velocity (as the model's
//! `p' = p + h·v`) and the heading with the last yaw rate; mocap and truth read it there.

use dronecine_math as math;
use nalgebra::{Matrix3, Vector3};

use super::config::{Effects, SimConfig, SimError};
use super::wrap;
use dronecine_backend::frames::{self, Command};
use dronecine_backend::FlightState;
use dronecine_profile::Profile;

/// Events closer than this are simultaneous (grid times are `k·h` in floating point).
pub const TIME_EPS_S: f64 = 1e-9;
const GRAVITY_MPS2: f64 = 9.81;
/// Take-off and hover altitude hold: vertical speed command per metre of height error.
const ALTITUDE_GAIN_PER_S: f64 = 0.5;
/// Largest vertical speed the take-off and hover altitude hold command.
const ALTITUDE_SPEED_MAX_MPS: f64 = 0.5;
/// Take-off ends when the drone is this close below the take-off height.
const TAKEOFF_DONE_M: f64 = 0.05;
/// Vertical speed the landing commands.
const LANDING_SPEED_MPS: f64 = 0.4;
/// Largest number of command packets in flight (latency); a send beyond replaces the newest.
pub const LINK_CAPACITY: usize = 256;

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Packet {
    /// AT*PCMD with the progressive flag: fly these set-points.
    Command(Command),
    /// AT*PCMD without it: hover.
    Hover,
}

/// The uplink: a fixed ring of packets waiting for their arrival time.
#[derive(Clone, Debug)]
pub struct Link {
    at_s: [f64; LINK_CAPACITY],
    packet: [Packet; LINK_CAPACITY],
    head: usize,
    len: usize,
    pub sent: u64,
    pub lost: u64,
    pub delivered: u64,
}

impl Link {
    pub fn new() -> Link {
        Link {
            at_s: [0.0; LINK_CAPACITY],
            packet: [Packet::Hover; LINK_CAPACITY],
            head: 0,
            len: 0,
            sent: 0,
            lost: 0,
            delivered: 0,
        }
    }

    pub fn push(&mut self, at_s: f64, packet: Packet) {
        if self.len == LINK_CAPACITY {
            let last = (self.head + self.len - 1) % LINK_CAPACITY;
            self.at_s[last] = at_s;
            self.packet[last] = packet;
            return;
        }
        let i = (self.head + self.len) % LINK_CAPACITY;
        self.at_s[i] = at_s;
        self.packet[i] = packet;
        self.len += 1;
    }

    #[inline]
    fn pop_due(&mut self, t_s: f64) -> Option<(f64, Packet)> {
        if self.len > 0 && self.at_s[self.head] <= t_s + TIME_EPS_S {
            let out = (self.at_s[self.head], self.packet[self.head]);
            self.head = (self.head + 1) % LINK_CAPACITY;
            self.len -= 1;
            self.delivered += 1;
            Some(out)
        } else {
            None
        }
    }

    pub fn clear(&mut self) {
        self.len = 0;
    }
}

/// What the firmware flies while `Flying`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Mode {
    Hover,
    Progressive(Command),
}

#[derive(Clone, Debug)]
pub struct Plant {
    pub effects: Effects,
    pub h: f64,
    /// Grid index: the state below is at `k·h`.
    pub k: u64,
    pub p: [f64; 3],
    pub v: [f64; 3],
    /// True roll and pitch (AR.Drone signs).
    pub tilt: [f64; 2],
    /// True yaw rate (AR.Drone sign: clockwise positive).
    pub yaw_rate: f64,
    pub heading: f64,
    pub state: FlightState,
    pub mode: Mode,
    pub last_rx_s: f64,
    pub z_hold: f64,
    pub battery: f64,
    // Constants.
    g: [[f64; 3]; 3],
    g_inv: [[f64; 3]; 3],
    e_body: [f64; 3],
    hover_gain: [f64; 2],
    e_att: f64,
    e_yaw: f64,
    gain_yaw: f64,
    tilt_max: f64,
    vz_max: f64,
    yaw_max: f64,
    drag_c: f64,
    descent_factor: f64,
    watchdog_s: f64,
    takeoff_height: f64,
    drain_per_s: f64,
    pub min_takeoff_battery: f64,
}

fn rows(m: &Matrix3<f64>) -> [[f64; 3]; 3] {
    [
        [m[(0, 0)], m[(0, 1)], m[(0, 2)]],
        [m[(1, 0)], m[(1, 1)], m[(1, 2)]],
        [m[(2, 0)], m[(2, 1)], m[(2, 2)]],
    ]
}

#[inline]
fn mul(m: &[[f64; 3]; 3], x: [f64; 3]) -> [f64; 3] {
    [
        m[0][0] * x[0] + m[0][1] * x[1] + m[0][2] * x[2],
        m[1][0] * x[0] + m[1][1] * x[1] + m[1][2] * x[2],
        m[2][0] * x[0] + m[2][1] * x[1] + m[2][2] * x[2],
    ]
}

impl Plant {
    pub fn new(cfg: &SimConfig, profile: &Profile) -> Result<Plant, SimError> {
        let m = &profile.model;
        let l = &profile.limits;
        SimError::profile("model.gain_roll_mps_per_rad", m.gain_roll_mps_per_rad)?;
        SimError::profile("model.gain_pitch_mps_per_rad", m.gain_pitch_mps_per_rad)?;
        SimError::profile("model.gain_vz", m.gain_vz)?;
        SimError::profile("model.tau_roll_s", m.tau_roll_s)?;
        SimError::profile("model.tau_pitch_s", m.tau_pitch_s)?;
        SimError::profile("model.tau_vz_s", m.tau_vz_s)?;
        SimError::profile("model.gain_yaw", m.gain_yaw)?;
        SimError::profile("limits.tilt_max_rad", l.tilt_max_rad)?;
        SimError::profile("limits.vz_max_mps", l.vz_max_mps)?;
        SimError::profile("limits.yaw_rate_max_radps", l.yaw_rate_max_radps)?;
        let h = cfg.step_s;
        let g = frames::INPUT_TO_BODY
            * Matrix3::from_diagonal(&Vector3::new(
                m.gain_roll_mps_per_rad,
                m.gain_pitch_mps_per_rad,
                m.gain_vz,
            ));
        let g_inv = g.try_inverse().ok_or(SimError::BadProfile {
            field: "model",
            value: 0.0,
            expected: "gains giving an invertible input map".to_string(),
        })?;
        let taus = frames::body_taus_s(m.tau_roll_s, m.tau_pitch_s, m.tau_vz_s);
        let e_body = taus.map(|tau| math::exp(-h / tau));
        // Hover: commanded body speed −g·v makes v decay with τ/(1 + g) = hover τ.
        let hover_gain = [0, 1].map(|j| (taus[j] / cfg.hover_velocity_tau_s - 1.0).max(0.0));
        let battery = cfg.battery_start_percent;
        Ok(Plant {
            effects: cfg.effects,
            h,
            k: 0,
            p: [cfg.start_position_m[0], cfg.start_position_m[1], 0.0],
            v: [0.0; 3],
            tilt: [0.0; 2],
            yaw_rate: 0.0,
            heading: frames::wrap_angle_rad(cfg.start_heading_rad),
            state: FlightState::Landed,
            mode: Mode::Hover,
            last_rx_s: 0.0,
            z_hold: cfg.takeoff_height_m,
            battery,
            g: rows(&g),
            g_inv: rows(&g_inv),
            e_body,
            hover_gain,
            e_att: math::exp(-cfg.attitude_rate_per_s * h),
            e_yaw: math::exp(-cfg.yaw_rate_lag_per_s * h),
            gain_yaw: m.gain_yaw,
            tilt_max: l.tilt_max_rad,
            vz_max: l.vz_max_mps,
            yaw_max: l.yaw_rate_max_radps,
            drag_c: cfg.drag_quadratic_per_m,
            descent_factor: cfg.descent_gain_factor,
            watchdog_s: cfg.watchdog_s,
            takeoff_height: cfg.takeoff_height_m,
            drain_per_s: cfg.battery_drain_percent_per_min / 60.0,
            min_takeoff_battery: cfg.battery_min_takeoff_percent,
        })
    }

    #[inline]
    pub fn t_k(&self) -> f64 {
        self.k as f64 * self.h
    }

    /// Position at `t_s` within the current step (`t_k ≤ t_s ≤ t_k + h`).
    #[inline]
    pub fn position_at(&self, t_s: f64) -> [f64; 3] {
        let s = t_s - self.t_k();
        let mut p = [
            self.p[0] + s * self.v[0],
            self.p[1] + s * self.v[1],
            self.p[2] + s * self.v[2],
        ];
        if p[2] < 0.0 {
            p[2] = 0.0;
        }
        p
    }

    /// The heading rate `ċ` the heading moves at now.
    #[inline]
    pub fn heading_rate(&self) -> f64 {
        match self.state {
            FlightState::Landed | FlightState::Emergency => 0.0,
            _ => self.gain_yaw * frames::heading_rate_radps(self.yaw_rate),
        }
    }

    #[inline]
    pub fn heading_at(&self, t_s: f64) -> f64 {
        let c = self.heading + (t_s - self.t_k()) * self.heading_rate();
        wrap(c)
    }

    fn enter_hover(&mut self) {
        self.mode = Mode::Hover;
        self.z_hold = self.p[2];
    }

    pub fn take_off(&mut self) {
        self.state = FlightState::TakingOff;
        self.mode = Mode::Hover;
        self.z_hold = self.takeoff_height;
    }

    /// The firmware's own set-points: hold the ground velocity at zero (optical flow), climb or
    /// descend at `vz`.
    fn hover_command(&self, vz_mps: f64, m: &Matrix3<f64>) -> Command {
        // Ground velocity in the body frame.
        let vb = [
            m[(0, 0)] * self.v[0] + m[(1, 0)] * self.v[1],
            m[(0, 1)] * self.v[0] + m[(1, 1)] * self.v[1],
            0.0,
        ];
        let want = [
            -self.hover_gain[0] * vb[0],
            -self.hover_gain[1] * vb[1],
            0.0,
        ];
        let u = mul(&self.g_inv, want);
        Command {
            roll_rad: u[0],
            pitch_rad: u[1],
            yaw_rate_radps: 0.0,
            vz_mps,
        }
    }

    fn altitude_hold(&self, target_m: f64) -> f64 {
        (ALTITUDE_GAIN_PER_S * (target_m - self.p[2]))
            .clamp(-ALTITUDE_SPEED_MAX_MPS, ALTITUDE_SPEED_MAX_MPS)
    }

    /// One step of the plant from `t_k` to `t_k + h`, delivering the packets due at `t_k`.
    #[inline]
    pub fn step(&mut self, link: &mut Link, wind: [f64; 2]) {
        let t = self.t_k();
        while let Some((at, packet)) = link.pop_due(t) {
            if self.state == FlightState::Flying {
                match packet {
                    Packet::Command(c) => self.mode = Mode::Progressive(c),
                    Packet::Hover => {
                        if self.mode != Mode::Hover {
                            self.enter_hover()
                        }
                    }
                }
                self.last_rx_s = at;
            }
        }
        if self.state == FlightState::Flying
            && matches!(self.mode, Mode::Progressive(_))
            && t - self.last_rx_s > self.watchdog_s + TIME_EPS_S
        {
            self.enter_hover();
        }
        match self.state {
            FlightState::Landed => {}
            FlightState::Emergency => self.fall(wind),
            _ => self.fly(wind),
        }
        self.k += 1;
    }

    #[inline]
    fn fly(&mut self, wind: [f64; 2]) {
        let h = self.h;
        let eff = self.effects;
        let m = frames::body_to_world(self.heading);
        let mut cmd = match (self.state, self.mode) {
            (FlightState::Flying, Mode::Progressive(c)) => c,
            (FlightState::Flying, Mode::Hover) => {
                self.hover_command(self.altitude_hold(self.z_hold), &m)
            }
            (FlightState::TakingOff, _) => {
                self.hover_command(self.altitude_hold(self.takeoff_height), &m)
            }
            _ => self.hover_command(-LANDING_SPEED_MPS, &m),
        };
        if eff.tilt_saturation {
            cmd.roll_rad = cmd.roll_rad.clamp(-self.tilt_max, self.tilt_max);
            cmd.pitch_rad = cmd.pitch_rad.clamp(-self.tilt_max, self.tilt_max);
            cmd.vz_mps = cmd.vz_mps.clamp(-self.vz_max, self.vz_max);
            cmd.yaw_rate_radps = cmd.yaw_rate_radps.clamp(-self.yaw_max, self.yaw_max);
        }
        let (thrust_roll, thrust_pitch) = if eff.attitude_lag {
            let s = (math::sin(self.tilt[0]), math::sin(self.tilt[1]));
            self.tilt[0] = cmd.roll_rad + (self.tilt[0] - cmd.roll_rad) * self.e_att;
            self.tilt[1] = cmd.pitch_rad + (self.tilt[1] - cmd.pitch_rad) * self.e_att;
            s
        } else {
            self.tilt = [cmd.roll_rad, cmd.pitch_rad];
            (cmd.roll_rad, cmd.pitch_rad)
        };
        let uz = if eff.asymmetric_vz && cmd.vz_mps < 0.0 {
            cmd.vz_mps * self.descent_factor
        } else {
            cmd.vz_mps
        };
        let yaw_rate = if eff.yaw_lag {
            let r = self.yaw_rate;
            self.yaw_rate = cmd.yaw_rate_radps + (r - cmd.yaw_rate_radps) * self.e_yaw;
            r
        } else {
            self.yaw_rate = cmd.yaw_rate_radps;
            cmd.yaw_rate_radps
        };
        let target = mul(&self.g, [thrust_roll, thrust_pitch, uz]);
        let w = [wind[0], wind[1], 0.0];
        let rel = [self.v[0] - w[0], self.v[1] - w[1], self.v[2]];
        let mut vb_new = [0.0; 3];
        for (j, out) in vb_new.iter_mut().enumerate() {
            // Body axis j: column j of M_D.
            let vb = m[(0, j)] * rel[0] + m[(1, j)] * rel[1] + m[(2, j)] * rel[2];
            *out = target[j] + (vb - target[j]) * self.e_body[j];
        }
        let mut v = [
            m[(0, 0)] * vb_new[0] + m[(0, 1)] * vb_new[1] + m[(0, 2)] * vb_new[2] + w[0],
            m[(1, 0)] * vb_new[0] + m[(1, 1)] * vb_new[1] + m[(1, 2)] * vb_new[2] + w[1],
            m[(2, 0)] * vb_new[0] + m[(2, 1)] * vb_new[1] + m[(2, 2)] * vb_new[2],
        ];
        if eff.drag {
            let speed = (rel[0] * rel[0] + rel[1] * rel[1]).sqrt();
            v[0] -= h * self.drag_c * speed * rel[0];
            v[1] -= h * self.drag_c * speed * rel[1];
        }
        for i in 0..3 {
            self.p[i] += h * self.v[i];
        }
        self.v = v;
        self.heading =
            wrap(self.heading + h * self.gain_yaw * frames::heading_rate_radps(yaw_rate));
        if eff.battery {
            self.battery -= self.drain_per_s * h;
            if self.battery <= 0.0 {
                self.battery = 0.0;
                if matches!(self.state, FlightState::Flying | FlightState::TakingOff) {
                    self.state = FlightState::Landing;
                }
            }
        }
        match self.state {
            FlightState::TakingOff if self.p[2] >= self.takeoff_height - TAKEOFF_DONE_M => {
                self.state = FlightState::Flying;
                self.mode = Mode::Hover;
                self.z_hold = self.takeoff_height;
            }
            FlightState::Landing if self.p[2] <= 0.0 => self.touch_down(FlightState::Landed),
            _ => {
                if self.p[2] < 0.0 {
                    // Ground contact in flight: the floor stops the descent.
                    self.p[2] = 0.0;
                    self.v[2] = self.v[2].max(0.0);
                }
            }
        }
    }

    /// Motors cut: the drone falls, the air slows it horizontally.
    fn fall(&mut self, wind: [f64; 2]) {
        if self.p[2] <= 0.0 && self.v == [0.0; 3] {
            return;
        }
        let h = self.h;
        let m = frames::body_to_world(self.heading);
        let rel = [self.v[0] - wind[0], self.v[1] - wind[1]];
        let mut v = [0.0; 3];
        for j in 0..2 {
            let vb = m[(0, j)] * rel[0] + m[(1, j)] * rel[1];
            let vb_new = vb * self.e_body[j];
            v[0] += m[(0, j)] * vb_new;
            v[1] += m[(1, j)] * vb_new;
        }
        v[0] += wind[0];
        v[1] += wind[1];
        v[2] = self.v[2] - GRAVITY_MPS2 * h;
        for i in 0..3 {
            self.p[i] += h * self.v[i];
        }
        self.v = v;
        if self.p[2] <= 0.0 {
            self.touch_down(FlightState::Emergency);
        }
    }

    fn touch_down(&mut self, state: FlightState) {
        self.p[2] = 0.0;
        self.v = [0.0; 3];
        self.tilt = [0.0; 2];
        self.yaw_rate = 0.0;
        self.state = state;
        self.mode = Mode::Hover;
    }
}
