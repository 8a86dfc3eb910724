//! The compiler's diagnostic codes (`compile::`): what it finds in a script it compiles, and
//! what the director finds against live actors on set. Add a code at the end; never rename
//! one.

dronecine_diag::codes! {
    /// The compiler's diagnostic codes (`compile::`): what it finds in a script it compiles, and what the director finds against live actors.
    pub enum CompileCode {
        NoScene => "compile::no_scene": "The script is a film annotation without a scene set-up; it cannot be flown.",
        TooClose => "compile::too_close": "A framing puts the camera inside an actor's safety distance.",
        Infeasible => "compile::infeasible": "The reference exceeds a limit of the drone profile (speed, acceleration, tilt, vertical speed, yaw rate).",
        LeavesStage => "compile::leaves_stage": "The reference leaves the stage volume.",
        CutTooShort => "compile::cut_too_short": "A cut to a pinned shot leaves too little time for the drone to fly to its first framing.",
        Reposition => "compile::reposition": "A cut needs a repositioning flight, inserted before the shot.",
        AngleNotRendered => "compile::angle_not_rendered": "The drone has no gimbal; the camera angle comes from altitude alone or not at all.",
        Unframeable => "compile::unframeable": "No roll-free camera orientation puts the actors at the requested screen positions.",
        FramingOff => "compile::framing_off": "A hold's actors land away from the screen points the script gives them.",
        ActorsCollide => "compile::actors_collide": "The blocking walks two actors into each other.",
        SizeOff => "compile::size_off": "A two-actor framing cannot give the size the script names: the actors too far apart for it in one frame, written screen positions that fix the distance, or an over-the-shoulder's background actor out of its reach.",
        InMargin => "compile::in_margin": "A framing puts the camera inside the stage's safety margin: the drone is held at the margin, off its framing.",
        BeyondReach => "compile::beyond_reach": "An over-the-shoulder's background size is out of reach where the actors stand: the profiles keep the camera nearer, and the actor is framed larger.",
        TooShortForRate => "compile::too_short_for_rate": "A shot is shorter than one control period at the rate it is compiled or flown at: it has no tick of its own.",
        CoverageOverruns => "compile::coverage_overruns": "A coverage's repositioning flights leave its shots less than their shortest hold: it lasts longer than written.",
        NoCamera => "compile::no_camera": "The drone carries no camera: the shots are framed for its profile's nominal lens, and nothing is filmed.",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codes_are_unique_and_in_the_compile_namespace() {
        let mut seen = std::collections::HashSet::new();
        for c in CompileCode::ALL {
            assert_eq!(c.code().namespace(), "compile", "{c}");
            assert!(seen.insert(c.as_str()), "duplicate code {c}");
        }
    }
}
