//! The PSL vocabulary: shot sizes, profile angles, camera angles, screen thirds, camera moves.
//!
//! This module is the single source of truth for the words of the language and for the
//! conventions that belong to the language itself: the camera azimuth of each profile angle and
//! the screen x of each third. The grammar (`psl.pest`) spells the same words;
//! `tests::keywords_match_grammar` keeps the two in step.

use serde::{Deserialize, Serialize};
use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};

/// Shot size, tightest first.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Size {
    ECU,
    BCU,
    CU,
    MCU,
    MS,
    MLS,
    FS,
    LS,
    ELS,
}

/// The size codes in `Size::ALL` order.
pub const SIZE_NAMES: &[&str] = &["ECU", "BCU", "CU", "MCU", "MS", "MLS", "FS", "LS", "ELS"];
/// The profile words in `Profile::ALL` order.
pub const PROFILE_NAMES: &[&str] = &[
    "front",
    "34left",
    "left",
    "34backleft",
    "back",
    "34backright",
    "right",
    "34right",
];
/// The camera moves in `MoveKind::ALL` order.
pub const MOVE_NAMES: &[&str] = &["hold", "pan", "dolly", "crane", "track", "follow"];
/// The words that start a shot after the first: a new shot (`cut`, `dissolve`) or its
/// continuation (`then`).
pub const TRANSITION_NAMES: &[&str] = &["cut", "dissolve", "then"];

impl Size {
    pub const ALL: [Size; 9] = [
        Size::ECU,
        Size::BCU,
        Size::CU,
        Size::MCU,
        Size::MS,
        Size::MLS,
        Size::FS,
        Size::LS,
        Size::ELS,
    ];

    pub fn as_str(self) -> &'static str {
        SIZE_NAMES[self as usize]
    }

    pub fn parse(s: &str) -> Option<Size> {
        Size::ALL.into_iter().find(|z| z.as_str() == s)
    }
}

/// Profile angle: the side of the actor the camera is on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Profile {
    Front,
    #[serde(rename = "34left")]
    ThreeQuarterLeft,
    Left,
    #[serde(rename = "34backleft")]
    ThreeQuarterBackLeft,
    Back,
    #[serde(rename = "34backright")]
    ThreeQuarterBackRight,
    Right,
    #[serde(rename = "34right")]
    ThreeQuarterRight,
}

impl Profile {
    pub const ALL: [Profile; 8] = [
        Profile::Front,
        Profile::ThreeQuarterLeft,
        Profile::Left,
        Profile::ThreeQuarterBackLeft,
        Profile::Back,
        Profile::ThreeQuarterBackRight,
        Profile::Right,
        Profile::ThreeQuarterRight,
    ];

    pub fn as_str(self) -> &'static str {
        PROFILE_NAMES[self as usize]
    }

    pub fn parse(s: &str) -> Option<Profile> {
        Profile::ALL.into_iter().find(|p| p.as_str() == s)
    }

    /// Camera azimuth around the actor in radians, measured from the actor's facing
    /// direction, counter-clockwise seen from above, in (−π, π].
    pub fn azimuth_rad(self) -> f64 {
        match self {
            Profile::Front => 0.0,
            Profile::ThreeQuarterLeft => FRAC_PI_4,
            Profile::Left => FRAC_PI_2,
            Profile::ThreeQuarterBackLeft => 3.0 * FRAC_PI_4,
            Profile::Back => PI,
            Profile::ThreeQuarterBackRight => -3.0 * FRAC_PI_4,
            Profile::Right => -FRAC_PI_2,
            Profile::ThreeQuarterRight => -FRAC_PI_4,
        }
    }
}

/// Camera angle of a composition; eye level is the default.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CameraAngle {
    #[default]
    EyeLevel,
    High,
    Low,
}

impl CameraAngle {
    pub const ALL: [CameraAngle; 3] = [CameraAngle::EyeLevel, CameraAngle::High, CameraAngle::Low];

    pub fn as_str(self) -> &'static str {
        match self {
            CameraAngle::EyeLevel => "eye level",
            CameraAngle::High => "high angle",
            CameraAngle::Low => "low angle",
        }
    }
}

/// A third of the frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ScreenThird {
    Left,
    Center,
    Right,
}

impl ScreenThird {
    pub fn parse(s: &str) -> Option<ScreenThird> {
        match s {
            "left" => Some(ScreenThird::Left),
            "center" | "centre" => Some(ScreenThird::Center),
            "right" => Some(ScreenThird::Right),
            _ => None,
        }
    }

    pub fn as_str(self) -> &'static str {
        match self {
            ScreenThird::Left => "left",
            ScreenThird::Center => "center",
            ScreenThird::Right => "right",
        }
    }

    /// Screen x in [−1, 1], left to right: the thirds sit at −1/3, 0, +1/3.
    pub fn screen_x(self) -> f64 {
        match self {
            ScreenThird::Left => -1.0 / 3.0,
            ScreenThird::Center => 0.0,
            ScreenThird::Right => 1.0 / 3.0,
        }
    }
}

/// Camera move of a `then … to` transition.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum MoveKind {
    Hold,
    Pan,
    Dolly,
    Crane,
    Track,
    Follow,
}

impl MoveKind {
    pub const ALL: [MoveKind; 6] = [
        MoveKind::Hold,
        MoveKind::Pan,
        MoveKind::Dolly,
        MoveKind::Crane,
        MoveKind::Track,
        MoveKind::Follow,
    ];

    pub fn as_str(self) -> &'static str {
        MOVE_NAMES[self as usize]
    }

    pub fn parse(s: &str) -> Option<MoveKind> {
        MoveKind::ALL.into_iter().find(|m| m.as_str() == s)
    }
}

/// Every reserved word: none of these can name an actor. Must match `keyword` in `psl.pest`.
pub const KEYWORDS: &[&str] = &[
    "ECU",
    "BCU",
    "CU",
    "MCU",
    "MS",
    "MLS",
    "FS",
    "LS",
    "ELS",
    "34backleft",
    "34backright",
    "34left",
    "34right",
    "front",
    "back",
    "left",
    "right",
    "on",
    "and",
    "cut",
    "dissolve",
    "then",
    "as",
    "to",
    "for",
    "over",
    "at",
    "hold",
    "pan",
    "dolly",
    "crane",
    "track",
    "follow",
    "high",
    "low",
    "eye",
    "level",
    "angle",
    "screen",
    "center",
    "centre",
    "stage",
    "lens",
    "drone",
    "actor",
    "height",
    "facing",
    "walks",
    "turns",
    "path",
    "square",
    "helix",
    "orbit",
    "waypoints",
    "side",
    "radius",
    "altitude",
    "from",
    "around",
    "clockwise",
    "counterclockwise",
    "looking",
    "x",
    "coverage",
];

pub fn is_keyword(word: &str) -> bool {
    KEYWORDS.contains(&word)
}

#[cfg(test)]
mod tests {
    use super::*;
    use dronecine_math::wrap_angle_rad;

    #[test]
    fn profile_azimuths_follow_psl_section_3() {
        let deg: Vec<f64> = Profile::ALL
            .iter()
            .map(|p| p.azimuth_rad().to_degrees().round())
            .collect();
        assert_eq!(
            deg,
            [0.0, 45.0, 90.0, 135.0, 180.0, -135.0, -90.0, -45.0],
            "front, 34left, left, 34backleft, back, 34backright, right, 34right"
        );
        // 34left is toward the actor's own left: counter-clockwise from the facing direction.
        let facing = 0.0_f64; // actor looks along +x
        let a = facing + Profile::ThreeQuarterLeft.azimuth_rad();
        assert!(
            a.sin() > 0.0,
            "34left camera is on the +y side of an actor facing +x"
        );
    }

    #[test]
    fn profiles_are_45_degrees_apart() {
        for w in Profile::ALL.windows(2) {
            let d = wrap_angle_rad(w[1].azimuth_rad() - w[0].azimuth_rad());
            assert!((d - FRAC_PI_4).abs() < 1e-12, "{:?} → {:?}", w[0], w[1]);
        }
    }

    #[test]
    fn name_tables_follow_the_enums() {
        for (i, z) in Size::ALL.iter().enumerate() {
            assert_eq!(*z as usize, i);
            assert_eq!(Size::parse(SIZE_NAMES[i]), Some(*z));
        }
        for (i, p) in Profile::ALL.iter().enumerate() {
            assert_eq!(*p as usize, i);
            assert_eq!(Profile::parse(PROFILE_NAMES[i]), Some(*p));
        }
        for (i, m) in MoveKind::ALL.iter().enumerate() {
            assert_eq!(*m as usize, i);
            assert_eq!(MoveKind::parse(MOVE_NAMES[i]), Some(*m));
        }
    }

    #[test]
    fn thirds_sit_at_one_third() {
        assert_eq!(ScreenThird::Left.screen_x(), -1.0 / 3.0);
        assert_eq!(ScreenThird::Center.screen_x(), 0.0);
        assert_eq!(ScreenThird::Right.screen_x(), 1.0 / 3.0);
    }

    #[test]
    fn wrap_is_half_open_at_minus_pi() {
        assert_eq!(wrap_angle_rad(PI), PI);
        assert!((wrap_angle_rad(-PI) - PI).abs() < 1e-12);
        assert!((wrap_angle_rad(3.0 * PI / 2.0) + FRAC_PI_2).abs() < 1e-12);
        assert!((wrap_angle_rad(-7.0 * PI) - PI).abs() < 1e-9);
        assert_eq!(wrap_angle_rad(0.0), 0.0);
    }

    #[test]
    fn wrap_keeps_in_range_angles_bit_for_bit() {
        // A wrap through 2π and back would turn −1e-20 into 0 and −0.3 two ulps off.
        for a in [-1e-20, -0.3, -FRAC_PI_2, -PI + 1e-15, 1e-300, -0.0, 3.0, PI] {
            assert_eq!(wrap_angle_rad(a).to_bits(), a.to_bits(), "{a}");
        }
        assert!(wrap_angle_rad(f64::NAN).is_nan());
        assert!((wrap_angle_rad(PI + 1e-9) - (-PI + 1e-9)).abs() < 1e-12);
    }

    #[test]
    fn keywords_match_grammar() {
        let grammar = include_str!("psl.pest");
        let start = grammar.find("keyword = @{").expect("keyword rule");
        let end = start
            + grammar[start..]
                .find("~ boundary")
                .expect("end of keyword rule");
        let mut in_grammar: Vec<&str> = grammar[start..end].split('"').skip(1).step_by(2).collect();
        let mut here: Vec<&str> = KEYWORDS.to_vec();
        in_grammar.sort_unstable();
        here.sort_unstable();
        assert_eq!(in_grammar, here);
        for s in Size::ALL {
            assert!(is_keyword(s.as_str()));
        }
        for p in Profile::ALL {
            assert!(is_keyword(p.as_str()));
        }
        for w in MOVE_NAMES.iter().chain(TRANSITION_NAMES) {
            assert!(is_keyword(w), "{w}");
        }
        for a in CameraAngle::ALL {
            assert!(a.as_str().split(' ').all(is_keyword), "{a:?}");
        }
    }
}
