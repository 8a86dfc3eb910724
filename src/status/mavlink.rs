//! `dronecine status --drone mavlink://…`: what a person checks before flying an ArduPilot
//! Copter: its mode, arming, battery, the EKF and whether it navigates on the motion capture,
//! its pre-arm checks, the parameters flying on motion capture needs (each wrong one with the
//! value it needs), the limits the commands are scaled to, and the gimbal if there is one.
//!
//! Reads only: no parameter is written and no mode, arming or set-point is sent (the link
//! asks the vehicle for its telemetry streams, as any ground station does).

use std::process::ExitCode;
use std::time::Duration;

use dronecine_mavlink::messages::copter_mode;

use super::{fail, verdict, watch};
use dronecine_mavlink::{MavlinkDrone, MavlinkOptions, MavlinkUrl, ParamCheck, VehicleLimits};

/// The longest the first read-out waits for the vehicle's EKF and SYS_STATUS reports (asked
/// for at 2 Hz when the link opens; an autopilot takes a moment to start streaming them).
const FIRST_READOUT: Duration = Duration::from_secs(4);

/// One read-out.
struct Readout {
    state: dronecine_mavlink::VehicleState,
    external_nav: bool,
    check: ParamCheck,
    limits: Result<VehicleLimits, String>,
}

impl Readout {
    /// What makes the vehicle unfit to fly a dronecine flight now.
    fn problems(&self) -> Vec<String> {
        let mut out: Vec<String> = self.check.wrong.iter().map(|w| w.to_string()).collect();
        if let Err(e) = &self.limits {
            out.push(e.clone());
        }
        if !self.external_nav {
            out.push(
                "the EKF does not navigate on the motion capture (`shoot` forwards it and \
                 waits for it)"
                    .into(),
            );
        }
        if self.state.prearm_ok == Some(false) {
            out.push("the autopilot's pre-arm checks fail".into());
        }
        if self.state.battery_percent.is_none() {
            out.push("the battery level is unknown".into());
        }
        out
    }

    fn text(&self, url: &MavlinkUrl) -> String {
        let s = &self.state;
        let mode = s.heartbeat.map_or("unknown".to_string(), |h| {
            copter_mode::name(h.custom_mode).to_string()
        });
        let armed = s.heartbeat.is_some_and(|h| h.armed);
        let yes = |b: bool| if b { "yes" } else { "no" };
        let mut t = format!("ArduPilot at {url}\n");
        t += &format!("  mode: {mode}, armed: {}\n", yes(armed));
        t += &format!(
            "  battery: {}\n",
            s.battery_percent
                .map_or("unknown".into(), |b| format!("{b:.0} %"))
        );
        t += &format!(
            "  EKF flags: {}, navigates on the motion capture: {}\n",
            s.ekf_flags
                .map_or("none received".into(), |f| format!("{f:#06x}")),
            yes(self.external_nav)
        );
        t += &format!(
            "  pre-arm checks: {}\n",
            match s.prearm_ok {
                Some(true) => "pass",
                Some(false) => "FAIL",
                None => "not reported",
            }
        );
        if let Some([roll, pitch, yaw]) = s.attitude_rad {
            t += &format!(
                "  attitude: roll {:.1}°, pitch {:.1}°, yaw {:.1}°\n",
                roll.to_degrees(),
                pitch.to_degrees(),
                yaw.to_degrees()
            );
        }
        match s.gimbal_pitch_rad {
            Some(p) => t += &format!("  gimbal: pitch {:.1}°\n", p.to_degrees()),
            None => t += "  gimbal: none reported\n",
        }
        t += "  parameters:\n";
        for (name, value) in &self.check.read {
            let wrong = self.check.wrong.iter().find(|w| &w.name == name);
            match wrong {
                Some(w) => t += &format!("    {name} = {value}  WRONG: {}\n", w.needed),
                None => t += &format!("    {name} = {value}  ok\n"),
            }
        }
        for w in self.check.wrong.iter().filter(|w| w.value.is_none()) {
            t += &format!("    {}: not answered ({})\n", w.name, w.needed);
        }
        match &self.limits {
            Ok(l) => {
                t += &format!(
                    "  limits: climb {:.2} m/s, descent {:.2} m/s, tilt {:.1}°, yaw rate {}, \
                     set-points time out after {:.1} s\n",
                    l.climb_max_mps,
                    l.descent_max_mps,
                    l.tilt_max_rad.to_degrees(),
                    l.yaw_rate_max_radps
                        .map_or("no limit of its own".into(), |r| format!(
                            "{:.0}°/s",
                            r.to_degrees()
                        )),
                    l.guided_timeout_s
                )
            }
            Err(e) => t += &format!("  limits: {e}\n"),
        }
        for p in self.problems() {
            t += &format!("  problem: {p}\n");
        }
        t
    }

    fn json(&self) -> serde_json::Value {
        let s = &self.state;
        serde_json::json!({
            "mode": s.heartbeat.map(|h| copter_mode::name(h.custom_mode)),
            "armed": s.heartbeat.map(|h| h.armed),
            "battery_percent": s.battery_percent,
            "ekf_flags": s.ekf_flags,
            "external_nav": self.external_nav,
            "prearm_ok": s.prearm_ok,
            "attitude_deg": s.attitude_rad.map(|a| a.map(f64::to_degrees)),
            "gimbal_pitch_deg": s.gimbal_pitch_rad.map(f64::to_degrees),
            "parameters": self.check.read.iter().map(|(n, v)| serde_json::json!({
                "name": n,
                "value": v,
                "ok": !self.check.wrong.iter().any(|w| &w.name == n),
            })).collect::<Vec<_>>(),
            "wrong_parameters": self.check.wrong.iter().map(|w| w.to_string()).collect::<Vec<_>>(),
            "limits": self.limits.as_ref().ok().map(|l| serde_json::json!({
                "climb_max_mps": l.climb_max_mps,
                "descent_max_mps": l.descent_max_mps,
                "tilt_max_deg": l.tilt_max_rad.to_degrees(),
                "yaw_rate_max_degps": l.yaw_rate_max_radps.map(f64::to_degrees),
                "guided_timeout_s": l.guided_timeout_s,
            })),
            "problems": self.problems(),
        })
    }
}

fn read(drone: &mut MavlinkDrone) -> Result<Readout, String> {
    let check = drone.check_parameters().map_err(|e| e.to_string())?;
    let limits = drone.limits().map_err(|e| e.to_string());
    Ok(Readout {
        state: drone.vehicle_state(),
        external_nav: drone.uses_external_nav(),
        check,
        limits,
    })
}

fn print(url: &MavlinkUrl, r: &Readout, json: bool) {
    if json {
        outln!("{}", r.json());
    } else {
        out!("{}", r.text(url));
    }
}

/// How `status` reads the vehicle: once (or every `interval_s` with `watch`), as text or
/// JSON lines, waiting `timeout_s` for its heartbeat.
pub struct Args {
    pub watch: bool,
    pub json: bool,
    pub timeout_s: f64,
    pub interval_s: f64,
}

/// `status` of an ArduPilot vehicle at `url`.
pub fn run(a: &Args, url: &MavlinkUrl) -> ExitCode {
    let options = MavlinkOptions {
        heartbeat_timeout: Duration::from_secs_f64(a.timeout_s),
        param_timeout: Duration::from_secs_f64(a.timeout_s.min(5.0)),
        ..MavlinkOptions::default()
    };
    let mut drone = match MavlinkDrone::connect(url, options) {
        Ok(d) => d,
        Err(e) => return fail(e.to_string()),
    };
    let reported = |s: &dronecine_mavlink::VehicleState| {
        s.ekf_flags.is_some() && s.prearm_ok.is_some() && s.battery_percent.is_some()
    };
    // A vehicle that never sends them is read out as it is: its read-out says what is missing.
    let _ = drone.link().wait_for(FIRST_READOUT, || Ok(()), reported);
    let mut readout = match read(&mut drone) {
        Ok(r) => r,
        Err(e) => return fail(e),
    };
    print(url, &readout, a.json);
    if !a.watch {
        let problems = readout.problems().len();
        return verdict(problems, "the vehicle", "do not fly it yet");
    }
    watch(a.interval_s, a.json, || {
        readout.state = drone.vehicle_state();
        readout.external_nav = drone.uses_external_nav();
        print(url, &readout, a.json);
    })
}
