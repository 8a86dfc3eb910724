//! What the director and the monitor found against the live actors, told as events: each at
//! the shot it is about, with the script's line and the fix, as `compile` tells them.

use dronecine_compiler::CompileCode;
use dronecine_diag::{Diagnostic, LineIndex};
use dronecine_mcap::record::Event;

use crate::flight::Flight;

impl Flight<'_, '_> {
    /// A finding of the director's against the live actors, as an event: its message after
    /// the shot it is about, the script's line of that shot and its fix, so that a director on
    /// set reads which line to change and how.
    pub(crate) fn director_finding(&mut self, t_s: f64, d: &Diagnostic) {
        let shot = (self.setup.script.timeline.iter())
            .position(|s| s.span == d.span)
            .map_or(String::new(), |i| format!("shot {}: ", i + 1));
        // A repositioning flight is the plan working as written: logged, not printed over
        // the progress display.
        let level = match d.is_error() {
            true => "error",
            false if d.code == CompileCode::Reposition => "info",
            false => "warning",
        };
        let held = if d.code == CompileCode::Unframeable {
            "; the drone holds where it is until it solves"
        } else {
            ""
        };
        let source = self.setup.source;
        let line = (!d.span.is_empty() && d.span.start <= source.len()).then(|| {
            let (line, _) = LineIndex::new(source).line_col(source, d.span.start);
            u32::try_from(line).unwrap_or(u32::MAX)
        });
        self.tell(Event {
            t_s,
            level: level.to_string(),
            kind: d.code.as_str().to_string(),
            message: format!("{shot}{}{held}", d.message),
            line,
            help: d.help.clone(),
        });
    }

    /// What the director's monitor found over shot `index`, now that it is over (the
    /// reference's lag behind the framing and its limits, a framing out of the stage or held
    /// at its margin, the camera near an actor), told as the director's own findings are.
    ///
    /// And the drone's own closest to an actor in it, as measured, when that is inside their
    /// safety distance (`drone_near_actor`): the reference keeps the profile's tracking
    /// margin more on set, and a drone that still comes inside tracks worse than its profile
    /// says. Else, when the drone strayed toward an actor by more than the margin where the
    /// reference was near the line it keeps (`tracking_margin_exceeded`,
    /// [`CutIn`](crate::report::CutIn)): it did not come inside this time, but a reference
    /// held at the line would have had it inside.
    pub(crate) fn tell_findings(&mut self, t_s: f64, findings: &[Diagnostic], index: usize) {
        for d in findings {
            self.director_finding(t_s, d);
        }
        let safety = &self.setup.profile.safety;
        let profile = &self.setup.profile.name;
        let name = |actor: usize| {
            let actors = &self.setup.scene.actors;
            actors.get(actor).map_or("an actor", |a| a.name.as_str())
        };
        let inside = self
            .metrics
            .shot_closest(index)
            .filter(|c| c.distance_m < safety.actor_distance_m);
        let strayed = self
            .metrics
            .shot_cut_in(index)
            .filter(|c| c.cut_in_m > safety.tracking_margin_m);
        // The drone's distances in millimetres: at two decimals a drone 0.4996 m from an actor
        // read "came 0.50 m from Bob" against "keeps 0.50 m".
        let (kind, message, help) = if let Some(c) = inside {
            let message = format!(
                "shot {}: the drone came {:.3} m from {} at {:.2} s (as measured); {profile} \
                 keeps {:.2} m from actors",
                index + 1,
                c.distance_m,
                name(c.actor),
                c.t_s,
                safety.actor_distance_m
            );
            let inside = short_distance(safety.actor_distance_m - c.distance_m);
            let help = format!(
                "on set the reference keeps the profile's `tracking_margin_m` ({:.2} m) \
                 more than that from actors, and the drone strayed {inside} beyond it: \
                 raise the margin, or frame the shot wider",
                safety.tracking_margin_m,
            );
            ("drone_near_actor", message, help)
        } else if let Some(c) = strayed {
            let message = format!(
                "shot {}: the drone came {:.3} m nearer {} than its reference at {:.2} s (as \
                 measured), the reference {:.2} m from them; {profile}'s `tracking_margin_m` \
                 is {:.2} m",
                index + 1,
                c.cut_in_m,
                name(c.actor),
                c.t_s,
                c.reference_m,
                safety.tracking_margin_m
            );
            let help = format!(
                "on set the reference keeps {:.2} m from actors so that a drone straying by up \
                 to the margin keeps their {:.2} m; this one strayed more, and with the \
                 reference at that line it would have come inside: raise `[safety] \
                 tracking_margin_m` to {:.2} m or more in the profile",
                safety.on_set_m(),
                safety.actor_distance_m,
                (c.cut_in_m * 100.0).ceil() / 100.0
            );
            ("tracking_margin_exceeded", message, help)
        } else {
            return;
        };
        let line = self.setup.script.timeline.get(index).map(|s| {
            let source = self.setup.source;
            let (line, _) = LineIndex::new(source).line_col(source, s.span.start);
            u32::try_from(line).unwrap_or(u32::MAX)
        });
        self.tell(Event {
            t_s,
            level: "warning".into(),
            kind: kind.into(),
            message,
            line,
            help: Some(help),
        });
    }
}

/// A distance as a warning says it: in metres to the centimetre, or under a centimetre in
/// millimetres (a drone 0.3 mm inside an actor's distance strayed "0.3 mm", not "0.00 m").
fn short_distance(m: f64) -> String {
    if m.abs() < 0.01 {
        format!("{:.1} mm", m * 1000.0)
    } else {
        format!("{m:.2} m")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_short_distance_is_said_in_millimetres() {
        assert_eq!(short_distance(0.0003), "0.3 mm");
        assert_eq!(short_distance(0.0099), "9.9 mm");
        assert_eq!(short_distance(0.01), "0.01 m");
        assert_eq!(short_distance(0.456), "0.46 m");
    }
}
