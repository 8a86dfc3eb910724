//! The language's diagnostic codes (`psl::`): what `check` finds in a script. Add a code at
//! the end, with a file in `tests/bad/` that raises it; never rename one.

use dronecine_diag::{Diagnostic, Span};

dronecine_diag::codes! {
    /// The language's diagnostic codes (`psl::`).
    pub enum PslCode {
        Syntax => "psl::syntax": "The line does not follow the grammar of PSL.",
        KeywordAsName => "psl::keyword_as_name": "A keyword (a size, a profile, `on`, `to`, …) stands where a name is needed.",
        UnitSpace => "psl::unit_space": "A unit is separated from its number by a space.",
        MissingUnit => "psl::missing_unit": "A number needs a unit (`m`, `s` or `deg`).",
        WrongUnit => "psl::wrong_unit": "A number has a unit other than the one this place needs.",
        OutOfRange => "psl::out_of_range": "A number is not finite or lies outside the range that makes sense here.",
        NonPositiveDuration => "psl::nonpositive_duration": "A duration is zero or negative.",
        MissingDuration => "psl::missing_duration": "A shot or movement has no duration.",
        DurationKeyword => "psl::duration_keyword": "`for` holds a composition, `over` times a move; the other one was written.",
        UnknownActor => "psl::unknown_actor": "An actor is used but never declared.",
        DuplicateActor => "psl::duplicate_actor": "An actor is declared twice.",
        ActorFramedTwice => "psl::actor_framed_twice": "One actor appears in two framings of one composition.",
        TwoShotSameActor => "psl::two_shot_same_actor": "The actors of a two-shot are the same actor.",
        TooManyActors => "psl::too_many_actors": "A composition frames more actors than a drone can (two).",
        MissingAttribute => "psl::missing_attribute": "An actor declaration lacks its height or position.",
        DuplicateAttribute => "psl::duplicate_attribute": "An attribute or path parameter is given twice.",
        MissingStage => "psl::missing_stage": "A scene has no `stage` line.",
        DuplicateSetting => "psl::duplicate_setting": "`stage`, `lens` or `drone` is set twice.",
        SetupAfterShots => "psl::setup_after_shots": "A scene set-up line comes after the first shot.",
        OutsideStage => "psl::outside_stage": "A position lies outside the stage volume.",
        OverlappingMovement => "psl::overlapping_movement": "Two movements of one actor overlap in time.",
        ThenWithoutShot => "psl::then_without_shot": "A `then` line has no shot before it to continue.",
        ThenAfterPath => "psl::then_after_path": "A `then` move follows a path, which has no composition to move from.",
        ThenToPath => "psl::then_to_path": "A `then` move leads into a path; paths start after a cut.",
        PinnedStartOverlaps => "psl::pinned_start_overlaps": "A shot pinned with `at Ns` starts before the previous shot ends.",
        UnknownDrone => "psl::unknown_drone": "The drone profile name is not a built-in profile.",
        FileNotFound => "psl::file_not_found": "A file named in the script cannot be read.",
        BadWaypoints => "psl::bad_waypoints": "A waypoints file has a line that is not three numbers x, y, z.",
        MissingPathParameter => "psl::missing_path_parameter": "A path lacks a parameter its shape needs.",
        UnexpectedPathParameter => "psl::unexpected_path_parameter": "A path has a parameter its shape does not take.",
        BadTimecode => "psl::bad_timecode": "A subtitle timecode is malformed or out of range.",
        TimecodeOrder => "psl::timecode_order": "A timed entry ends before it starts or overlaps the previous one.",
        MixedTiming => "psl::mixed_timing": "Timed (subtitle) entries and untimed shots are mixed in one file.",
        DurationInTimedEntry => "psl::duration_in_timed_entry": "A timed entry also gives a duration.",
        EmptyScript => "psl::empty_script": "The script has no shots.",
        BadAspect => "psl::bad_aspect": "A lens aspect ratio is not two positive numbers.",
        InvalidUtf8 => "psl::invalid_utf8": "The file is not UTF-8 text.",
        Internal => "psl::internal": "The parser met a case it does not handle; please report it.",
        ActorsOverlap => "psl::actors_overlap": "Two actors start in the same place.",
        TooShort => "psl::too_short": "A duration is shorter than 1 ms, the shortest control period dronecine flies at.",
        CoverageTooShort => "psl::coverage_too_short": "A coverage is too short for its five shots and the flights between them.",
        ThenToCoverage => "psl::then_to_coverage": "A `then` move leads into a coverage, which is a set of cuts.",
        ThenAfterCoverage => "psl::then_after_coverage": "A `then` line continues a coverage, whose last shot the compiler chooses.",
    }
}

/// A case the parser does not handle, as a diagnostic instead of a panic.
pub(crate) fn internal(span: Span, what: String) -> Diagnostic {
    Diagnostic::error(
        PslCode::Internal,
        span,
        format!("internal parser error: {what}"),
    )
    .with_help("this is a bug in dronecine; please report it with the script that caused it")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn codes_are_unique_and_in_the_psl_namespace() {
        let mut seen = std::collections::HashSet::new();
        for c in PslCode::ALL {
            assert_eq!(c.code().namespace(), "psl", "{c}");
            assert!(seen.insert(c.as_str()), "duplicate code {c}");
            assert!(!c.explain().is_empty());
        }
    }
}
