//! The flight's diagnostic codes (`preflight::`): why a flight did not start. Each refusal
//! leaves the drone on the ground (or lands it, when take-off itself fails). Add a code at the
//! end; never rename one.

use dronecine_diag::{Diagnostic, Span};

use crate::FlightError;

dronecine_diag::codes! {
    /// Why a flight did not start (`preflight::`).
    pub enum PreflightCode {
        BadRate => "preflight::bad_rate": "The control rate is not in (0, 1000] Hz.",
        NoShots => "preflight::no_shots": "The script has no shots to fly.",
        DroneUntracked => "preflight::drone_untracked": "The motion capture does not see the drone.",
        DronePoseInvalid => "preflight::drone_pose_invalid": "The drone's tracked pose is not a number.",
        DroneOutsideStage => "preflight::drone_outside_stage": "The drone stands outside the stage.",
        ActorUntracked => "preflight::actor_untracked": "The motion capture does not see an actor.",
        DroneTooClose => "preflight::drone_too_close": "The drone stands inside an actor's safety distance.",
        BatteryLow => "preflight::battery_low": "The battery is below the level needed to fly.",
        FirstFramingUnsolved => "preflight::first_framing_unsolved": "The first framing cannot be solved against the actors as they stand.",
        FirstFramingOutsideStage => "preflight::first_framing_outside_stage": "The first framing puts the drone outside the stage.",
        FirstFramingNearActor => "preflight::first_framing_near_actor": "The first framing puts the drone inside an actor's safety distance as the actors stand.",
        TakeOffEmergency => "preflight::take_off_emergency": "The drone went into emergency during take-off.",
        TakeOffTimeout => "preflight::take_off_timeout": "The drone did not report flying within the take-off timeout.",
        Interrupted => "preflight::interrupted": "The operator interrupted the flight before take-off (Ctrl-C, SIGTERM or SIGHUP).",
        TelemetryImplausible => "preflight::telemetry_implausible": "The drone reports a value no drone has (a battery level outside 0–100 %).",
    }
}

/// A refusal about the set, not the script: no place in the text.
pub(crate) fn refusal(code: PreflightCode, message: String, help: &str) -> FlightError {
    FlightError::Preflight(vec![
        Diagnostic::error(code, Span::NOWHERE, message).with_help(help)
    ])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codes_are_unique_and_in_the_preflight_namespace() {
        let mut seen = std::collections::HashSet::new();
        for c in PreflightCode::ALL {
            assert_eq!(c.code().namespace(), "preflight", "{c}");
            assert!(seen.insert(c.as_str()), "duplicate code {c}");
        }
    }
}
