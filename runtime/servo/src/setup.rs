//! Which controller flies, and how it is set up: what a flight log records, so that replay
//! builds the same controller again.

use dronecine_profile::Profile;
use serde::{Deserialize, Serialize};

use crate::control::Controller;
use crate::lqg::{LqgServo, ServoOptions};
use crate::pid::PidController;

/// Which controller flew, and how it was set up: enough to build it again.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ControllerSetup {
    /// `"lqg"` or `"pid"`.
    pub kind: String,
    /// LQG: the paper's pre-filter without the acceleration feed-forward.
    pub paper_prefilter: bool,
    /// LQG: solve the DARE at every tick instead of rotating the body-frame gains.
    pub per_tick_solve: bool,
}

impl ControllerSetup {
    /// The controller `kind` (`"lqg"` or `"pid"`) as `shoot` flies it by default: LQG with
    /// the acceleration feed-forward and its gains rotated each tick.
    pub fn new(kind: &str) -> ControllerSetup {
        ControllerSetup {
            kind: kind.into(),
            paper_prefilter: false,
            per_tick_solve: false,
        }
    }
}

/// Builds the controller a flight (or a log) asks for.
pub fn controller_for(
    setup: &ControllerSetup,
    profile: &Profile,
    rate_hz: f64,
) -> Result<Box<dyn Controller>, String> {
    match setup.kind.as_str() {
        "lqg" => {
            let options = ServoOptions {
                paper_prefilter: setup.paper_prefilter,
                per_tick_solve: setup.per_tick_solve,
                nominal_dt_s: 1.0 / rate_hz,
            };
            LqgServo::new(profile, options)
                .map(|s| Box::new(s) as Box<dyn Controller>)
                .map_err(|e| e.to_string())
        }
        "pid" => Ok(Box::new(PidController::new(profile))),
        other => Err(format!(
            "unknown controller `{other}`: this dronecine knows `lqg` and `pid`"
        )),
    }
}
