//! `dronecine status --drone crazyflie+…://`: what a person checks before flying a
//! Crazyflie: its protocol version (and so the yaw-rate sign it takes), its battery, its
//! supervisor's state, its estimate and attitude, and the link's health.
//!
//! Reads only: no parameter is written and no set-point is sent (the two log blocks the
//! read-out comes from are created on the Crazyflie, as any client's are).

use std::process::ExitCode;
use std::time::Duration;

use dronecine_crazyflie::drone::monitor;
use dronecine_crazyflie::frames::{YawRateSign, CCW_YAW_RATE_PROTOCOL};
use dronecine_crazyflie::link::Link;
use dronecine_crazyflie::log::{supervisor, Field, Values};
use dronecine_crazyflie::{CrazyflieOptions, CrazyflieUrl};

use super::mavlink::Args;
use super::{fail, verdict, watch};

/// A link silent for longer than this is a problem.
const SILENT_S: f64 = 0.5;
/// `pm.state` of a battery too low to fly.
const PM_LOW: f64 = 3.0;

/// One read-out.
struct Readout {
    protocol: u8,
    values: Values,
    received: u64,
    rejected: u64,
    link_age_s: f64,
}

impl Readout {
    fn of(link: &Link, protocol: u8) -> Readout {
        let link_age_s = link.link_age_s();
        let s = link.state();
        Readout {
            protocol,
            values: s.values,
            received: s.received,
            rejected: s.rejected,
            link_age_s,
        }
    }

    /// What makes the Crazyflie unfit to fly a dronecine flight now.
    fn problems(&self) -> Vec<String> {
        let mut out = Vec::new();
        let info = self.values.supervisor().unwrap_or(0);
        let bad = info & (supervisor::LOCKED | supervisor::CRASHED | supervisor::TUMBLED);
        if bad != 0 {
            out.push(format!(
                "the supervisor says {}: restart the Crazyflie",
                supervisor::names(bad).join(", ")
            ));
        }
        if self.values.get(Field::PmState) >= PM_LOW {
            out.push("the battery is low: charge it".into());
        }
        if self.rejected > 0 {
            out.push(format!(
                "{} of {} packets did not decode",
                self.rejected,
                self.rejected + self.received
            ));
        }
        if self.link_age_s > SILENT_S {
            out.push(format!("nothing heard for {:.1} s", self.link_age_s));
        }
        out
    }

    fn text(&self, url: &CrazyflieUrl) -> String {
        let v = &self.values;
        let yaw = match YawRateSign::of_protocol(self.protocol) {
            YawRateSign::CounterClockwise => "counter-clockwise",
            YawRateSign::Clockwise => "clockwise",
        };
        let mut t = format!("Crazyflie at {url}\n");
        t += &format!(
            "  CRTP protocol: {} (altHold yaw rate {yaw} positive; {CCW_YAW_RATE_PROTOCOL} \
             and on: counter-clockwise)\n",
            self.protocol
        );
        t += &format!(
            "  battery: {:.2} V, {:.0} %, {}\n",
            v.get(Field::Vbat),
            v.get(Field::BatteryLevel),
            pm_state(v.get(Field::PmState))
        );
        t += &format!(
            "  supervisor: {}\n",
            v.supervisor()
                .map_or("not reported".into(), |i| supervisor::names(i).join(", "))
        );
        t += &format!(
            "  estimate: ({:.3}, {:.3}, {:.3}) m\n",
            v.get(Field::X),
            v.get(Field::Y),
            v.get(Field::Z)
        );
        t += &format!(
            "  attitude: roll {:.1}°, pitch {:.1}°, yaw {:.1}°\n",
            v.get(Field::Roll),
            v.get(Field::Pitch),
            v.get(Field::Yaw)
        );
        t += &format!(
            "  link: {} packets, {} rejected, last {:.0} ms ago\n",
            self.received,
            self.rejected,
            self.link_age_s * 1000.0
        );
        for p in self.problems() {
            t += &format!("  problem: {p}\n");
        }
        t
    }

    fn json(&self) -> serde_json::Value {
        let v = &self.values;
        let num = |f: Field| Some(v.get(f)).filter(|x| x.is_finite());
        serde_json::json!({
            "protocol_version": self.protocol,
            "battery_v": num(Field::Vbat),
            "battery_percent": num(Field::BatteryLevel),
            "pm_state": num(Field::PmState),
            "supervisor": v.supervisor().map(supervisor::names),
            "estimate_m": v.estimate_m(),
            "attitude_deg": [num(Field::Roll), num(Field::Pitch), num(Field::Yaw)],
            "packets": self.received,
            "rejected": self.rejected,
            "link_age_s": self.link_age_s,
            "problems": self.problems(),
        })
    }
}

/// `pm.state` for people.
fn pm_state(s: f64) -> &'static str {
    match s as i64 {
        0 => "on battery",
        1 => "charging",
        2 => "charged",
        3 => "LOW",
        4 => "shutting down",
        _ => "state unknown",
    }
}

fn print(url: &CrazyflieUrl, r: &Readout, json: bool) {
    if json {
        outln!("{}", r.json());
    } else {
        out!("{}", r.text(url));
    }
}

/// `status` of the Crazyflie at `url`.
pub fn run(a: &Args, url: &CrazyflieUrl) -> ExitCode {
    let options = CrazyflieOptions {
        connect_timeout: Duration::from_secs_f64(a.timeout_s),
        request_timeout: Duration::from_secs_f64(a.timeout_s.min(5.0)),
        ..CrazyflieOptions::default()
    };
    let (link, protocol) = match monitor(url, &options) {
        Ok(l) => l,
        Err(e) => return fail(e),
    };
    let readout = Readout::of(&link, protocol);
    print(url, &readout, a.json);
    if !a.watch {
        let problems = readout.problems().len();
        return verdict(problems, "the Crazyflie", "do not fly it yet");
    }
    watch(a.interval_s, a.json, || {
        print(url, &Readout::of(&link, protocol), a.json)
    })
}
