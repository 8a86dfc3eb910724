//! One test per grammar rule: what it accepts in full, and what it rejects.

use dronecine_grammar::rules::{PslParser, Rule};
use pest::Parser;

/// The rule matches the whole input.
fn full(rule: Rule, s: &str) -> bool {
    match PslParser::parse(rule, s) {
        Ok(mut pairs) => pairs.next().is_some_and(|p| p.as_span().end() == s.len()),
        Err(_) => false,
    }
}

fn accepts(rule: Rule, good: &[&str]) {
    for s in good {
        assert!(full(rule, s), "{rule:?} should accept {s:?}");
    }
}

fn rejects(rule: Rule, bad: &[&str]) {
    for s in bad {
        assert!(!full(rule, s), "{rule:?} should reject {s:?}");
    }
}

#[test]
fn size() {
    accepts(
        Rule::size,
        &["ECU", "BCU", "CU", "MCU", "MS", "MLS", "FS", "LS", "ELS"],
    );
    rejects(Rule::size, &["ms", "XS", "MSS", "M S", ""]);
}

#[test]
fn profile() {
    accepts(
        Rule::profile,
        &[
            "front",
            "34left",
            "left",
            "34backleft",
            "back",
            "34backright",
            "right",
            "34right",
        ],
    );
    rejects(
        Rule::profile,
        &["Front", "34", "frontal", "3/4left", "34 left"],
    );
}

#[test]
fn name_excludes_keywords() {
    accepts(
        Rule::name,
        &[
            "A", "Bob", "alice_2", "Zoé", "Front", "frontman", "onion", "B2",
        ],
    );
    rejects(
        Rule::name,
        &["front", "on", "and", "MS", "x", "to", "2B", "_a", "a-b"],
    );
}

#[test]
fn quantity_and_count() {
    accepts(
        Rule::quantity,
        &["4s", "1.80m", "84deg", "-3s", ".5m", "4", "2.", "4cm"],
    );
    rejects(Rule::quantity, &["4 s", "s", "--4s", "1e3m"]);
    accepts(Rule::count, &["2", "0.5", "-1"]);
}

#[test]
fn point() {
    accepts(Rule::point, &["(0, 0)", "(1,1.5)", "( -2.5m , 3m )"]);
    rejects(Rule::point, &["(0)", "(0, 0, 0)", "0, 0", "(a, b)"]);
}

#[test]
fn stage() {
    accepts(Rule::stage, &["stage 8m x 6m x 3m", "stage 8 x 6 x 3"]);
    rejects(Rule::stage, &["stage 8m x 6m", "stage 8mx6mx3m", "stage"]);
}

#[test]
fn lens() {
    accepts(
        Rule::lens,
        &["lens 84deg", "lens 84deg 4:3", "lens 92deg 16:9"],
    );
    rejects(Rule::lens, &["lens", "lens 4:3", "lens 84deg 4/3"]);
}

#[test]
fn drone() {
    accepts(
        Rule::drone,
        &[
            "drone ardrone2",
            "drone ardrone2-outdoor",
            "drone \"profiles/mine.toml\"",
        ],
    );
    rejects(Rule::drone, &["drone", "drone \"unterminated"]);
}

#[test]
fn actor_decl() {
    accepts(
        Rule::actor_decl,
        &[
            "actor A height 1.80m at (0, 0) facing 0deg",
            "actor B facing 180deg at (2.5, 0) height 1.65m",
            "actor C height 1.7m at (1, 1)",
        ],
    );
    rejects(
        Rule::actor_decl,
        &["actor front height 1.8m", "actor", "actor A tall 1.8m"],
    );
}

#[test]
fn blocking() {
    accepts(
        Rule::blocking,
        &[
            "at 6s A walks to (1, 1.5) over 4s",
            "at 12s B turns to 90deg over 1s",
            "at 6s A walks to (1, 1)",
        ],
    );
    rejects(
        Rule::blocking,
        &[
            "at 6s A walk to (1, 1) over 4s",
            "at 6s A runs to (1, 1)",
            "at A walks to (1,1)",
        ],
    );
}

#[test]
fn duration() {
    accepts(Rule::duration, &["for 4s", "over 6s", "for 4"]);
    rejects(Rule::duration, &["during 4s", "for", "for4s"]);
}

#[test]
fn camera_angle() {
    accepts(
        Rule::camera_angle,
        &["high angle", "low angle", "eye level", "high   angle"],
    );
    rejects(Rule::camera_angle, &["high", "angle high", "eye-level"]);
}

#[test]
fn screen() {
    accepts(
        Rule::screen,
        &[
            "screen left",
            "screen center",
            "screen centre",
            "screen right",
            "screen (0.2, -0.1)",
        ],
    );
    rejects(Rule::screen, &["screen", "screen top", "left"]);
}

#[test]
fn framing_and_composition() {
    accepts(
        Rule::framing,
        &[
            "MS on A",
            "MS A",
            "MS on A front",
            "MS on A and B",
            "CU on A 34left screen left and B screen right",
        ],
    );
    rejects(Rule::framing, &["MS on", "on A", "MS on A and"]);
    accepts(
        Rule::composition,
        &[
            "high angle MS on A and B",
            "MS B 34backright MLS A 34left screen right",
            "ELS on A",
        ],
    );
}

#[test]
fn transition() {
    accepts(
        Rule::transition,
        &[
            "cut to",
            "dissolve to",
            "then dolly to",
            "then follow A to",
            "then as A sits down pan to",
            "then as \"A sits\" crane to",
        ],
    );
    rejects(
        Rule::transition,
        &["cut", "then to", "then zoom to", "then follow to"],
    );
}

#[test]
fn event() {
    accepts(Rule::event, &["as A sits down", "as \"A pans the room\""]);
    // Free words stop before a camera move.
    assert!(!full(Rule::event, "as A sits pan"));
}

#[test]
fn shots() {
    accepts(
        Rule::shot,
        &[
            "MS on A front for 4s",
            "then dolly to MS on A 34backright over 6s",
            "cut to high angle MS on A and B for 5s",
            "cut to MS B 34backright MLS A 34left screen right for 3s",
            "then hold for 2s",
            "then as B leaves hold for 2s",
            "at 30s cut to MS on A front for 4s",
            "dissolve to CU on A front for 2s",
            "MS on A front",
        ],
    );
    rejects(
        Rule::shot,
        &[
            "cut to for 4s",
            "then hold to for 4s",
            "MS on A front for 4s extra",
        ],
    );
}

#[test]
fn coverage_shot() {
    accepts(
        Rule::coverage_shot,
        &[
            "coverage A and B for 24s",
            "coverage FS on Rick and Ilsa for 24s",
            "coverage MLS A and B for 20s",
            "coverage on A and B for 20s",
            "cut to coverage A and B for 24s",
            "dissolve to coverage A and B for 24s",
            // Parsed, to be refused with its fix (`psl::then_to_coverage`).
            "then dolly to coverage A and B for 24s",
            "coverage A and B",
        ],
    );
    rejects(
        Rule::coverage_shot,
        &[
            "coverage A for 24s",
            "coverage A and B and C for 24s",
            "coverage A B for 24s",
            "coverage A and coverage for 24s",
            "coverage front and B for 24s",
            "coverage FS on A 34left and B for 24s",
            "coveragea A and B for 24s",
        ],
    );
    accepts(Rule::shot, &["at 12s cut to coverage A and B for 24s"]);
    rejects(Rule::name, &["coverage"]);
}

#[test]
fn path_shot() {
    accepts(
        Rule::path_shot,
        &[
            "path square side 2m center (0, 0) altitude 1.5m for 20s",
            "path helix radius 1.5m center (0, 0) from 1m to 2.5m turns 2 for 24s",
            "path orbit around A radius 2m altitude 1.5m turns 1 clockwise for 20s",
            "path waypoints \"file.csv\" for 30s",
            "path square side 2m altitude 1.5m looking at A for 20s",
            "path square side 2m altitude 1.5m for 20s looking at A",
            "cut to path orbit center (1, 1) radius 1m altitude 2m for 10s",
        ],
    );
    rejects(
        Rule::path_shot,
        &[
            "path circle radius 1m for 2s",
            "path waypoints file.csv for 3s",
            "path square side for 2s",
        ],
    );
}

#[test]
fn timed_entry_and_timecode() {
    accepts(
        Rule::timed_entry,
        &[
            "12 00:01:03 --> 00:01:09  cut to low angle MCU Bob 34right",
            "1 00:00:01,500 --> 00:00:05.250 MS on Rick front",
            "3 01:03 --> 01:60 then hold",
        ],
    );
    rejects(
        Rule::timed_entry,
        &[
            "12 00:01:03 -> 00:01:09 MS Bob",
            "00:01:03 --> 00:01:09 MS Bob",
        ],
    );
    accepts(
        Rule::timecode,
        &["00:01:03", "1:02:03", "01:60", "00:00:01,500"],
    );
    rejects(Rule::timecode, &["1", "00-01-03", ":01:02"]);
}

#[test]
fn line_and_comment() {
    accepts(
        Rule::line,
        &[
            "",
            "# just a comment",
            "MS on A front for 4s # trailing",
            "   stage 8m x 6m x 3m   ",
            "\tMS on A for 4s",
        ],
    );
    rejects(Rule::line, &["MS on A front for 4s extra", "# ok\nMS on A"]);
    accepts(Rule::comment, &["#", "# anything: MS on A for 4s"]);
}
