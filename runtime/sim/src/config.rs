//! The simulator's configuration: which effects are on ([`Effects`]) and the numbers of each
//! ([`SimConfig`]), with their defaults and sources, and the check that rejects bad values.

use serde::{Deserialize, Serialize};
use std::fmt;

/// An effect's switch in [`Effects`]: the field it is.
pub type EffectSwitch = fn(&mut Effects) -> &mut bool;

/// The effects the simulated AR.Drone, mocap and actors add to the servo's model. All off
/// ([`Effects::none`]) leaves exactly the servo's model (`dronecine_servo::model`); each one
/// switches on independently.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Effects {
    /// Attitude follows the command with a first-order lag (`θ̇ = a·(θ_cmd − θ)`) and thrust
    /// tilts by `sin` of the true attitude (off: the attitude is the command and the model is
    /// linear in it).
    pub attitude_lag: bool,
    /// The firmware's limits: roll and pitch clamped to `tilt_max_rad`, vertical speed to
    /// `vz_max_mps`, yaw rate to `yaw_rate_max_radps` (the profile's limits).
    pub tilt_saturation: bool,
    /// Quadratic air drag on the horizontal air-relative velocity, on top of the model's
    /// linear drag (the `−v/τ` term).
    pub drag: bool,
    /// Descent commands act `descent_gain_factor` times stronger than climb commands.
    pub asymmetric_vz: bool,
    /// The yaw rate follows the command with a first-order lag.
    pub yaw_lag: bool,
    /// Command packets arrive `latency_s` after they are sent.
    pub latency: bool,
    /// A share of the command packets is lost (the drone keeps flying the previous one).
    pub radio_loss: bool,
    /// Gaussian noise on every mocap position and heading.
    pub mocap_noise: bool,
    /// Mocap bodies untracked in short bursts of frames.
    pub mocap_dropouts: bool,
    /// Horizontal wind gusts (a smooth Ornstein–Uhlenbeck process).
    pub wind: bool,
    /// Actors deviate smoothly from the script (place, facing, timing).
    pub actor_deviation: bool,
    /// The battery drains in flight; an empty battery lands the drone.
    pub battery: bool,
}

impl Effects {
    pub fn all() -> Effects {
        Effects {
            attitude_lag: true,
            tilt_saturation: true,
            drag: true,
            asymmetric_vz: true,
            yaw_lag: true,
            latency: true,
            radio_loss: true,
            mocap_noise: true,
            mocap_dropouts: true,
            wind: true,
            actor_deviation: true,
            battery: true,
        }
    }

    /// Each effect's name on the command line (`shoot --sim-off wind,battery`) and in the
    /// flight log's header, and its switch: the one table both go through.
    pub const NAMES: [(&'static str, EffectSwitch); 12] = [
        ("attitude-lag", |e| &mut e.attitude_lag),
        ("tilt-saturation", |e| &mut e.tilt_saturation),
        ("drag", |e| &mut e.drag),
        ("asymmetric-vz", |e| &mut e.asymmetric_vz),
        ("yaw-lag", |e| &mut e.yaw_lag),
        ("latency", |e| &mut e.latency),
        ("radio-loss", |e| &mut e.radio_loss),
        ("mocap-noise", |e| &mut e.mocap_noise),
        ("mocap-dropouts", |e| &mut e.mocap_dropouts),
        ("wind", |e| &mut e.wind),
        ("actor-deviation", |e| &mut e.actor_deviation),
        ("battery", |e| &mut e.battery),
    ];

    /// Switches the effect called `name` (one of [`Effects::NAMES`]); `false` if there is none
    /// of that name.
    pub fn set(&mut self, name: &str, on: bool) -> bool {
        match Self::NAMES.iter().find(|(n, _)| *n == name) {
            Some((_, switch)) => {
                *switch(self) = on;
                true
            }
            None => false,
        }
    }

    /// The names of the effects that are off, in [`Effects::NAMES`]' order.
    pub fn off(&self) -> Vec<&'static str> {
        let mut e = *self;
        Self::NAMES
            .iter()
            .filter(|(_, switch)| !*switch(&mut e))
            .map(|(n, _)| *n)
            .collect()
    }

    pub fn none() -> Effects {
        Effects {
            attitude_lag: false,
            tilt_saturation: false,
            drag: false,
            asymmetric_vz: false,
            yaw_lag: false,
            latency: false,
            radio_loss: false,
            mocap_noise: false,
            mocap_dropouts: false,
            wind: false,
            actor_deviation: false,
            battery: false,
        }
    }
}

/// Everything the simulator needs besides the profile and the scene. [`SimConfig::new`] gives
/// the defaults documented on each field (sources: the tum_ardrone state estimator of Engel,
/// Sturm & Cremers, the AR.Drone Developer Guide, OptiTrack's specifications; estimates are
/// marked as such).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SimConfig {
    /// Seeds every random process (each has its own stream).
    pub seed: u64,
    pub effects: Effects,
    /// Mocap frame rate. Default 100 Hz.
    pub mocap_rate_hz: f64,
    /// The plant's fixed integration step, on a grid from t = 0. Default 5 ms (the AR.Drone
    /// firmware's 200 Hz control loop); commands take effect at the first step that starts
    /// at or after their arrival.
    pub step_s: f64,
    /// Where the drone stands before take-off: x and y are used, the drone stands on the
    /// floor (z is ignored). Default the origin.
    pub start_position_m: [f64; 3],
    /// Heading before take-off (counter-clockwise from +x). Default 0.
    pub start_heading_rad: f64,
    /// Height the take-off climbs to. Default 0.8 m (the AR.Drone's).
    pub takeoff_height_m: f64,
    /// With no command packet for this long, the firmware hovers. Default 2 s (AR.Drone
    /// Developer Guide §6: two commands more than 2 s apart and the link counts as lost).
    pub watchdog_s: f64,
    /// The firmware's hover (optical-flow velocity hold) brings the ground velocity to zero
    /// with this time constant; it also holds the altitude. Default 0.5 s (an estimate: it
    /// holds position loosely, drifting with the wind).
    pub hover_velocity_tau_s: f64,
    /// Attitude lag rate `a` in `θ̇ = a·(θ_cmd − θ)`. Default 7 /s (tum_ardrone).
    pub attitude_rate_per_s: f64,
    /// Yaw-rate lag rate `b` in `ψ̈ = b·(ψ̇_cmd − ψ̇)`. Default 25 /s (tum_ardrone).
    pub yaw_rate_lag_per_s: f64,
    /// Quadratic drag `c` in `a = −c·|v_rel|·v_rel` (horizontal, air-relative). Default
    /// 0.07 /m: an estimate, `ρ·C_d·A/(2m)` with ρ = 1.2 kg/m³, C_d·A ≈ 0.05 m² (indoor
    /// hull), m = 0.42 kg.
    pub drag_quadratic_per_m: f64,
    /// Descent commands act this many times stronger than climb commands (steady-state
    /// `ż = K_ż·factor·u` for `u < 0`). Default 2 (tum_ardrone's vertical model:
    /// `z̈ = 0.8·(0.6·u·(2 if u < 0 else 1) − ż)`).
    pub descent_gain_factor: f64,
    /// Command latency. Default 40 ms (WiFi round trip and firmware: an estimate, within the
    /// tens of milliseconds these take).
    pub latency_s: f64,
    /// Probability that a command packet is lost. Default 0.01.
    pub radio_loss_probability: f64,
    /// Mocap position noise σ per axis. Default 0.3 mm (OptiTrack: sub-millimetre).
    pub mocap_position_sigma_m: f64,
    /// Mocap heading noise σ. Default 0.1°.
    pub mocap_heading_sigma_rad: f64,
    /// Share of the frames in which a body is untracked. Default 0.005.
    pub mocap_dropout_fraction: f64,
    /// Mean length of a dropout burst, in frames (≥ 1). Default 3.
    pub mocap_dropout_burst_frames: f64,
    /// Wind gust σ per horizontal axis. Default 0.3 m/s.
    pub wind_sigma_mps: f64,
    /// Wind gust correlation time. Default 3 s.
    pub wind_tau_s: f64,
    /// Actors' place offset: σ per axis, correlation time and bound. Defaults 6 cm, 2.5 s,
    /// 15 cm.
    pub actor_offset_sigma_m: f64,
    pub actor_offset_tau_s: f64,
    pub actor_offset_max_m: f64,
    /// Actors' facing wobble: σ, correlation time, bound. Defaults 3°, 1.5 s, 8°.
    pub actor_facing_sigma_rad: f64,
    pub actor_facing_tau_s: f64,
    pub actor_facing_max_rad: f64,
    /// Actors' timing lag or lead on the script: σ, correlation time, bound. Defaults
    /// 0.1 s, 4 s, 0.2 s.
    pub actor_timing_sigma_s: f64,
    pub actor_timing_tau_s: f64,
    pub actor_timing_max_s: f64,
    /// Knots per correlation time of the actors' deviation splines (`smooth.rs`). Default 2:
    /// an actor drifts off the mark on the scale of the correlation time, and the offset's
    /// acceleration stays that of a person shifting their weight (≈ 0.1 m/s² RMS per axis
    /// at the defaults). 8, the wind's setting, keeps the OU's rough tail up to 8/τ and
    /// makes a 6 cm drift accelerate at ≈ 0.7 m/s² RMS — a fidget no camera should chase.
    pub actor_knots_per_tau: f64,
    /// Battery at start. Default 100 %.
    pub battery_start_percent: f64,
    /// Drain while airborne. Default 7 %/min (≈ 13 min of flight on the 1000 mAh pack,
    /// Parrot's 12 min figure).
    pub battery_drain_percent_per_min: f64,
    /// Take-off is refused below this charge. Default 20 % (an estimate of the firmware's
    /// low-battery lock).
    pub battery_min_takeoff_percent: f64,
    /// The actors stand at their opening marks until the flight loop calls "action!"
    /// (`Mocap::action`), then walk the script from its time 0 — as on set. Default false:
    /// the script's clock is the world's from t = 0.
    pub wait_for_action: bool,
    /// The simulated motion capture offers the flight its actors' future
    /// (`Mocap::actors_ahead`: they do not depend on the drone), and the flight steps its
    /// director on a second thread, ahead of the loop: the same flight, bit for bit
    /// (`runtime/tests/it/ahead.rs`), in less time when the machine has a core for that thread
    /// (`dronecine_runtime::director_thread_pays`). Default false: the director is stepped on
    /// the loop's thread, as with a real motion capture.
    #[serde(default)]
    pub actors_ahead: bool,
}

impl SimConfig {
    /// All effects on, the defaults above.
    pub fn new(seed: u64) -> SimConfig {
        SimConfig {
            seed,
            effects: Effects::all(),
            mocap_rate_hz: 100.0,
            step_s: 0.005,
            start_position_m: [0.0; 3],
            start_heading_rad: 0.0,
            takeoff_height_m: 0.8,
            watchdog_s: 2.0,
            hover_velocity_tau_s: 0.5,
            attitude_rate_per_s: 7.0,
            yaw_rate_lag_per_s: 25.0,
            drag_quadratic_per_m: 0.07,
            descent_gain_factor: 2.0,
            latency_s: 0.04,
            radio_loss_probability: 0.01,
            mocap_position_sigma_m: 0.0003,
            mocap_heading_sigma_rad: 0.1f64.to_radians(),
            mocap_dropout_fraction: 0.005,
            mocap_dropout_burst_frames: 3.0,
            wind_sigma_mps: 0.3,
            wind_tau_s: 3.0,
            actor_offset_sigma_m: 0.06,
            actor_offset_tau_s: 2.5,
            actor_offset_max_m: 0.15,
            actor_facing_sigma_rad: 3f64.to_radians(),
            actor_facing_tau_s: 1.5,
            actor_facing_max_rad: 8f64.to_radians(),
            actor_timing_sigma_s: 0.1,
            actor_timing_tau_s: 4.0,
            actor_timing_max_s: 0.2,
            actor_knots_per_tau: 2.0,
            battery_start_percent: 100.0,
            battery_drain_percent_per_min: 7.0,
            battery_min_takeoff_percent: 20.0,
            wait_for_action: false,
            actors_ahead: false,
        }
    }

    /// How far the simulated drone may drift on the wind while it takes off (the firmware's
    /// take-off holds its velocity near zero, not its position, for the ~4 s of the climb):
    /// four times the gusts' σ over a second, 1.2 m at the default 0.3 m/s; none without
    /// wind. The simulated drone waits at least this far inside the stage's walls
    /// (`dronecine_runtime::start_pose`): one that takes off nearer a wall, below a first
    /// framing on the stage's margin, can drift out of the stage before the servo takes over,
    /// and the flight ends in the stage failsafe.
    pub fn takeoff_drift_m(&self) -> f64 {
        // Four σ of the gusts, held for a second.
        const HELD_S: f64 = 1.0;
        if self.effects.wind {
            4.0 * self.wind_sigma_mps.max(0.0) * HELD_S
        } else {
            0.0
        }
    }

    /// How far from their marks the simulated actors may be measured standing: the place
    /// offset's bound on both floor axes (when the actors deviate) and four σ of the mocap's
    /// noise. The simulated drone waits at least this much further from every mark than
    /// the actor distance (`dronecine_runtime::start_pose`), so that the pre-flight check, which
    /// measures both, passes.
    pub fn actor_reach_m(&self) -> f64 {
        let offset_m = if self.effects.actor_deviation {
            std::f64::consts::SQRT_2 * self.actor_offset_max_m.max(0.0)
        } else {
            0.0
        };
        let noise_m = if self.effects.mocap_noise {
            4.0 * self.mocap_position_sigma_m.max(0.0)
        } else {
            0.0
        };
        offset_m + noise_m
    }

    /// Every value checked; the first bad one is reported.
    pub fn validate(&self) -> Result<(), SimError> {
        use Expect::*;
        let checks: [(&'static str, f64, Expect); 33] = [
            ("mocap_rate_hz", self.mocap_rate_hz, Range(1e-3, 1e4)),
            ("step_s", self.step_s, Range(1e-5, 0.05)),
            ("start_position_m[0]", self.start_position_m[0], Finite),
            ("start_position_m[1]", self.start_position_m[1], Finite),
            ("start_position_m[2]", self.start_position_m[2], Finite),
            ("start_heading_rad", self.start_heading_rad, Finite),
            ("takeoff_height_m", self.takeoff_height_m, Range(0.1, 100.0)),
            ("watchdog_s", self.watchdog_s, Positive),
            ("hover_velocity_tau_s", self.hover_velocity_tau_s, Positive),
            ("attitude_rate_per_s", self.attitude_rate_per_s, Positive),
            ("yaw_rate_lag_per_s", self.yaw_rate_lag_per_s, Positive),
            (
                "drag_quadratic_per_m",
                self.drag_quadratic_per_m,
                NonNegative,
            ),
            ("descent_gain_factor", self.descent_gain_factor, Positive),
            ("latency_s", self.latency_s, Range(0.0, 10.0)),
            (
                "radio_loss_probability",
                self.radio_loss_probability,
                Range(0.0, 1.0),
            ),
            (
                "mocap_position_sigma_m",
                self.mocap_position_sigma_m,
                NonNegative,
            ),
            (
                "mocap_heading_sigma_rad",
                self.mocap_heading_sigma_rad,
                NonNegative,
            ),
            (
                "mocap_dropout_fraction",
                self.mocap_dropout_fraction,
                Range(0.0, 0.99),
            ),
            (
                "mocap_dropout_burst_frames",
                self.mocap_dropout_burst_frames,
                Range(1.0, 1e6),
            ),
            ("wind_sigma_mps", self.wind_sigma_mps, NonNegative),
            ("wind_tau_s", self.wind_tau_s, Positive),
            (
                "actor_offset_sigma_m",
                self.actor_offset_sigma_m,
                NonNegative,
            ),
            ("actor_offset_tau_s", self.actor_offset_tau_s, Positive),
            ("actor_offset_max_m", self.actor_offset_max_m, NonNegative),
            (
                "actor_facing_sigma_rad",
                self.actor_facing_sigma_rad,
                NonNegative,
            ),
            ("actor_facing_tau_s", self.actor_facing_tau_s, Positive),
            (
                "actor_facing_max_rad",
                self.actor_facing_max_rad,
                Range(0.0, std::f64::consts::FRAC_PI_2),
            ),
            (
                "actor_timing_sigma_s",
                self.actor_timing_sigma_s,
                NonNegative,
            ),
            ("actor_timing_tau_s", self.actor_timing_tau_s, Positive),
            (
                "actor_timing_max_s",
                self.actor_timing_max_s,
                Range(0.0, 5.0),
            ),
            (
                "actor_knots_per_tau",
                self.actor_knots_per_tau,
                Range(0.5, 64.0),
            ),
            (
                "battery_start_percent",
                self.battery_start_percent,
                Range(0.0, 100.0),
            ),
            (
                "battery_drain_percent_per_min",
                self.battery_drain_percent_per_min,
                NonNegative,
            ),
        ];
        for (field, value, expect) in checks {
            expect.check(field, value)?;
        }
        Range(0.0, 100.0).check(
            "battery_min_takeoff_percent",
            self.battery_min_takeoff_percent,
        )
    }
}

#[derive(Clone, Copy)]
enum Expect {
    Finite,
    Positive,
    NonNegative,
    /// Inclusive.
    Range(f64, f64),
}

impl Expect {
    fn check(self, field: &'static str, value: f64) -> Result<(), SimError> {
        let ok = value.is_finite()
            && match self {
                Expect::Finite => true,
                Expect::Positive => value > 0.0,
                Expect::NonNegative => value >= 0.0,
                Expect::Range(lo, hi) => (lo..=hi).contains(&value),
            };
        if ok {
            return Ok(());
        }
        let expected = match self {
            Expect::Finite => "a finite number".to_string(),
            Expect::Positive => "a finite number > 0".to_string(),
            Expect::NonNegative => "a finite number ≥ 0".to_string(),
            Expect::Range(lo, hi) => format!("a number in [{lo}, {hi}]"),
        };
        Err(SimError::BadConfig {
            field,
            value,
            expected,
        })
    }
}

/// Why a simulator could not be built.
#[derive(Clone, Debug, PartialEq)]
pub enum SimError {
    /// A [`SimConfig`] value out of its range (or NaN / infinite).
    BadConfig {
        field: &'static str,
        value: f64,
        expected: String,
    },
    /// A profile value the plant cannot use (a gain or time constant that is not a positive
    /// finite number, a limit that is not positive).
    BadProfile {
        field: &'static str,
        value: f64,
        expected: String,
    },
}

impl SimError {
    pub(crate) fn profile(field: &'static str, value: f64) -> Result<(), SimError> {
        if value.is_finite() && value > 0.0 {
            Ok(())
        } else {
            Err(SimError::BadProfile {
                field,
                value,
                expected: "a finite number > 0".to_string(),
            })
        }
    }
}

impl fmt::Display for SimError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SimError::BadConfig {
                field,
                value,
                expected,
            } => write!(
                f,
                "simulator setting {field} = {value}: expected {expected}"
            ),
            SimError::BadProfile {
                field,
                value,
                expected,
            } => write!(f, "profile value {field} = {value}: expected {expected}"),
        }
    }
}

impl std::error::Error for SimError {}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every effect has one name and every name one effect: switching each on from none gives
    /// twelve different configurations, and all of them on is `Effects::all()`.
    #[test]
    fn each_effect_has_exactly_one_name() {
        let mut every = Effects::none();
        let mut seen = Vec::new();
        for (name, _) in Effects::NAMES {
            let mut one = Effects::none();
            assert!(one.set(name, true), "{name}");
            assert_ne!(one, Effects::none(), "{name} switches nothing");
            assert!(
                !seen.contains(&one),
                "{name} switches what another name does"
            );
            seen.push(one);
            assert!(every.set(name, true));
            assert_eq!(one.off().len(), Effects::NAMES.len() - 1);
        }
        assert_eq!(every, Effects::all());
        assert!(Effects::all().off().is_empty());
        let all: Vec<&str> = Effects::NAMES.iter().map(|(n, _)| *n).collect();
        assert_eq!(Effects::none().off(), all);
        let mut e = Effects::all();
        assert!(!e.set("gravity", false));
        assert_eq!(e, Effects::all());
        assert!(e.set("battery", false) && e.set("wind", false));
        assert_eq!(e.off(), ["wind", "battery"]);
    }
}
