//! The vehicle's parameters: read by name ([`read_params`]), checked against what flying on
//! motion capture needs ([`check_parameters`]), and the limits the command mapping takes
//! from them ([`VehicleLimits`]).
//!
//! What flying on motion capture needs (ArduCopter with EKF3):
//! - `VISO_TYPE` = 1: the visual-odometry input is MAVLink (VISION_POSITION_ESTIMATE).
//! - `GPS1_TYPE` = 0 (`GPS_TYPE` on older firmware): no GPS.
//! - `EK3_SRC1_POSXY`, `EK3_SRC1_VELXY`, `EK3_SRC1_POSZ`, `EK3_SRC1_VELZ` = 6: the EKF's
//!   position and velocity come from the external navigation.
//! - `GUID_OPTIONS` bit 3 (value 8) clear: SET_ATTITUDE_TARGET's thrust is a climb rate.

use std::collections::HashMap;
use std::fmt;
use std::time::{Duration, Instant};

use dronecine_backend::BackendError;

use crate::link::Link;
use crate::messages;

/// How long a parameter request waits before it is sent again.
pub const PARAM_RETRY: Duration = Duration::from_millis(250);

/// The value a parameter must have.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Needed {
    Equals(f32),
    /// The bit (0 = least significant) must be clear.
    BitClear(u32),
}

impl Needed {
    fn holds(self, value: f32) -> bool {
        match self {
            Needed::Equals(v) => value == v,
            Needed::BitClear(bit) => (value as u32) & (1 << bit) == 0,
        }
    }
}

impl fmt::Display for Needed {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Needed::Equals(v) => write!(f, "{v}"),
            Needed::BitClear(bit) => write!(f, "bit {bit} (value {}) clear", 1u32 << bit),
        }
    }
}

/// The parameters flying on motion capture needs (module docs). A name with a `|` is read
/// as the first the vehicle has: `GPS1_TYPE|GPS_TYPE`.
pub const REQUIRED: [(&str, Needed); 7] = [
    ("VISO_TYPE", Needed::Equals(1.0)),
    ("GPS1_TYPE|GPS_TYPE", Needed::Equals(0.0)),
    ("EK3_SRC1_POSXY", Needed::Equals(6.0)),
    ("EK3_SRC1_VELXY", Needed::Equals(6.0)),
    ("EK3_SRC1_POSZ", Needed::Equals(6.0)),
    ("EK3_SRC1_VELZ", Needed::Equals(6.0)),
    ("GUID_OPTIONS", Needed::BitClear(3)),
];

/// One parameter that is not as needed.
#[derive(Clone, Debug, PartialEq)]
pub struct WrongParam {
    /// The name the vehicle has (or every name tried, when it answered to none).
    pub name: String,
    /// `None` when the vehicle did not answer.
    pub value: Option<f32>,
    pub needed: Needed,
}

impl fmt::Display for WrongParam {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.value {
            Some(v) => write!(f, "{} is {v}, needs {}", self.name, self.needed),
            None => write!(f, "{} not answered, needs {}", self.name, self.needed),
        }
    }
}

/// The result of the parameter check: each parameter read, and those that are wrong.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ParamCheck {
    /// Every parameter checked, by the name the vehicle answered to, with its value.
    pub read: Vec<(String, f32)>,
    pub wrong: Vec<WrongParam>,
}

impl ParamCheck {
    pub fn passed(&self) -> bool {
        self.wrong.is_empty()
    }

    /// One sentence naming each wrong parameter, its value and the value it needs.
    pub fn refusal(&self) -> String {
        let list: Vec<String> = self.wrong.iter().map(|w| w.to_string()).collect();
        format!(
            "the vehicle's parameters are not set for flying on motion capture: {} (set them, \
             then reboot the autopilot)",
            list.join("; ")
        )
    }
}

/// The limits the command mapping reads from the vehicle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VehicleLimits {
    /// `WP_SPD_UP` (m/s; `WPNAV_SPEED_UP` in cm/s before 4.7): the climb rate of thrust 1.
    pub climb_max_mps: f64,
    /// `WP_SPD_DN` (m/s; `WPNAV_SPEED_DN` in cm/s): the descent rate of thrust 0.
    pub descent_max_mps: f64,
    /// `ATC_ANGLE_MAX` (degrees; `ANGLE_MAX` in centidegrees): the largest lean angle.
    pub tilt_max_rad: f64,
    /// `ATC_RATE_Y_MAX` (deg/s); `None` when 0 (no limit of its own).
    pub yaw_rate_max_radps: Option<f64>,
    /// `GUID_TIMEOUT` (s): how long the vehicle flies on without a set-point before it
    /// levels and holds its altitude.
    pub guided_timeout_s: f64,
    /// `1 / ATC_ANG_YAW_P` (s): how far ahead of the vehicle's yaw a yaw-rate command puts
    /// the yaw target, so that the autopilot's angle controller turns it at that rate.
    pub yaw_lead_s: f64,
}

/// ArduCopter's default `ATC_ANG_YAW_P` (1/s), for a vehicle that does not answer for it.
pub const DEFAULT_YAW_ANGLE_P: f64 = 4.5;

/// The limits' parameter names, in [`VehicleLimits`]' order: ArduCopter 4.7's name first,
/// then the older one (whose unit differs: [`OLD_UNIT_SCALE`]).
pub const LIMIT_PARAMS: [&str; 5] = [
    "WP_SPD_UP|WPNAV_SPEED_UP",
    "WP_SPD_DN|WPNAV_SPEED_DN",
    "ATC_ANGLE_MAX|ANGLE_MAX",
    "ATC_RATE_Y_MAX",
    "GUID_TIMEOUT",
];

/// The newer names of [`LIMIT_PARAMS`] and what their value is multiplied by to give the
/// older names' units (cm/s, centidegrees), which [`VehicleLimits::from_values`] takes.
pub const OLD_UNIT_SCALE: [(&str, f64); 3] = [
    ("WP_SPD_UP", 100.0),
    ("WP_SPD_DN", 100.0),
    ("ATC_ANGLE_MAX", 100.0),
];

impl VehicleLimits {
    /// Reads the limits from the vehicle (either generation of names); an error names the
    /// parameters it did not answer or that make no sense.
    pub fn read(link: &Link, timeout: Duration) -> Result<Self, BackendError> {
        let values = read_params(link, &LIMIT_PARAMS, timeout)?;
        let missing: Vec<&str> = (LIMIT_PARAMS.iter().zip(&values))
            .filter(|(_, v)| v.is_none())
            .map(|(n, _)| *n)
            .collect();
        if !missing.is_empty() {
            return Err(BackendError::Refused(format!(
                "the vehicle at {} did not answer for {} within {:.1} s: its limits are read \
                 from these parameters",
                link.url(),
                missing.join(", ").replace('|', " or "),
                timeout.as_secs_f64()
            )));
        }
        let scale = {
            let state = link.state();
            OLD_UNIT_SCALE.map(|(name, k)| {
                if state.params.contains_key(name) {
                    k
                } else {
                    1.0
                }
            })
        };
        let v = |i: usize| f64::from(values[i].unwrap_or(f32::NAN));
        let yaw_p = read_params(link, &["ATC_ANG_YAW_P"], timeout)?[0]
            .map(f64::from)
            .filter(|p| p.is_finite() && *p > 0.0)
            .unwrap_or(DEFAULT_YAW_ANGLE_P);
        let limits = Self::from_values(
            v(0) * scale[0],
            v(1) * scale[1],
            v(2) * scale[2],
            v(3),
            v(4),
        )?;
        Ok(VehicleLimits {
            yaw_lead_s: 1.0 / yaw_p,
            ..limits
        })
    }

    /// The limits from the parameters' values in their own units.
    pub fn from_values(
        speed_up_cmps: f64,
        speed_dn_cmps: f64,
        angle_max_cdeg: f64,
        rate_y_max_degps: f64,
        guid_timeout_s: f64,
    ) -> Result<Self, BackendError> {
        for (name, v) in [
            ("WPNAV_SPEED_UP", speed_up_cmps),
            ("WPNAV_SPEED_DN", speed_dn_cmps),
            ("ANGLE_MAX", angle_max_cdeg),
        ] {
            if !(v > 0.0) || !v.is_finite() {
                return Err(BackendError::Refused(format!(
                    "the vehicle's {name} is {v}: it must be above 0"
                )));
            }
        }
        Ok(VehicleLimits {
            climb_max_mps: speed_up_cmps / 100.0,
            descent_max_mps: speed_dn_cmps.abs() / 100.0,
            tilt_max_rad: (angle_max_cdeg / 100.0).to_radians(),
            yaw_rate_max_radps: (rate_y_max_degps > 0.0).then(|| rate_y_max_degps.to_radians()),
            guided_timeout_s: guid_timeout_s,
            yaw_lead_s: 1.0 / DEFAULT_YAW_ANGLE_P,
        })
    }
}

/// Reads parameters by name: a PARAM_REQUEST_READ for each, sent again every
/// [`PARAM_RETRY`] until the vehicle answers or `timeout` passes. A name with `|` is read
/// as its alternatives (`None` for a parameter the vehicle never answered).
pub fn read_params(
    link: &Link,
    names: &[&str],
    timeout: Duration,
) -> Result<Vec<Option<f32>>, BackendError> {
    let Some(target) = link.vehicle() else {
        return Err(BackendError::Link(format!(
            "no vehicle heard at {} to read parameters from",
            link.url()
        )));
    };
    let wanted: Vec<&str> = names.iter().flat_map(|n| n.split('|')).collect();
    {
        let mut state = link.state();
        for n in &wanted {
            state.params.remove(*n);
        }
    }
    let mut last_sent: Option<Instant> = None;
    let all_answered = |p: &HashMap<String, f32>| {
        names
            .iter()
            .all(|n| n.split('|').any(|a| p.contains_key(a)))
    };
    link.wait_for(
        timeout,
        || {
            if last_sent.is_some_and(|t| t.elapsed() < PARAM_RETRY) {
                return Ok(());
            }
            last_sent = Some(Instant::now());
            let missing: Vec<String> = {
                let state = link.state();
                (wanted.iter())
                    .filter(|n| !state.params.contains_key(**n))
                    .map(|n| n.to_string())
                    .collect()
            };
            for n in missing {
                link.send(&messages::param_request(target, &n))?;
            }
            Ok(())
        },
        |s| all_answered(&s.params),
    )?;
    let state = link.state();
    Ok(names
        .iter()
        .map(|n| n.split('|').find_map(|a| state.params.get(a).copied()))
        .collect())
}

/// Checks the parameters of [`REQUIRED`] against the values `lookup` gives for each name.
pub fn check_values(lookup: impl Fn(&str) -> Option<f32>) -> ParamCheck {
    let mut check = ParamCheck::default();
    for (names, needed) in REQUIRED {
        let found = names.split('|').find_map(|n| lookup(n).map(|v| (n, v)));
        match found {
            Some((name, value)) => {
                check.read.push((name.to_string(), value));
                if !needed.holds(value) {
                    check.wrong.push(WrongParam {
                        name: name.to_string(),
                        value: Some(value),
                        needed,
                    });
                }
            }
            None => check.wrong.push(WrongParam {
                name: names.replace('|', " (or ") + if names.contains('|') { ")" } else { "" },
                value: None,
                needed,
            }),
        }
    }
    check
}

/// Reads the parameters of [`REQUIRED`] from the vehicle and checks them.
pub fn check_parameters(link: &Link, timeout: Duration) -> Result<ParamCheck, BackendError> {
    let names: Vec<&str> = REQUIRED.iter().map(|(n, _)| *n).collect();
    read_params(link, &names, timeout)?;
    let state = link.state();
    Ok(check_values(|n| state.params.get(n).copied()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_wrong_parameter_is_named_with_its_value_and_the_value_needed() {
        let table: HashMap<&str, f32> = [
            ("VISO_TYPE", 0.0),
            ("GPS_TYPE", 1.0),
            ("EK3_SRC1_POSXY", 6.0),
            ("EK3_SRC1_VELXY", 6.0),
            ("EK3_SRC1_POSZ", 1.0),
            ("GUID_OPTIONS", 9.0),
        ]
        .into_iter()
        .collect();
        let check = check_values(|n| table.get(n).copied());
        assert!(!check.passed());
        let wrong: Vec<String> = check.wrong.iter().map(|w| w.to_string()).collect();
        assert_eq!(
            wrong,
            [
                "VISO_TYPE is 0, needs 1",
                "GPS_TYPE is 1, needs 0",
                "EK3_SRC1_POSZ is 1, needs 6",
                "EK3_SRC1_VELZ not answered, needs 6",
                "GUID_OPTIONS is 9, needs bit 3 (value 8) clear",
            ]
        );
        assert!(check.refusal().contains("GPS_TYPE is 1, needs 0"));
    }

    #[test]
    fn a_right_table_passes_and_the_newer_gps_name_wins() {
        let table: HashMap<&str, f32> = [
            ("VISO_TYPE", 1.0),
            ("GPS1_TYPE", 0.0),
            ("GPS_TYPE", 1.0),
            ("EK3_SRC1_POSXY", 6.0),
            ("EK3_SRC1_VELXY", 6.0),
            ("EK3_SRC1_POSZ", 6.0),
            ("EK3_SRC1_VELZ", 6.0),
            ("GUID_OPTIONS", 7.0),
        ]
        .into_iter()
        .collect();
        let check = check_values(|n| table.get(n).copied());
        assert!(check.passed(), "{:?}", check.wrong);
        assert!(check.read.contains(&("GPS1_TYPE".to_string(), 0.0)));
        let none = check_values(|_| None);
        assert_eq!(none.wrong[1].name, "GPS1_TYPE (or GPS_TYPE)");
    }

    #[test]
    fn limits_in_si_units() {
        let l = VehicleLimits::from_values(250.0, 150.0, 3000.0, 0.0, 3.0).unwrap();
        assert_eq!((l.climb_max_mps, l.descent_max_mps), (2.5, 1.5));
        assert!((l.tilt_max_rad - 30f64.to_radians()).abs() < 1e-12);
        assert_eq!(l.yaw_rate_max_radps, None);
        let l = VehicleLimits::from_values(250.0, 150.0, 3000.0, 90.0, 3.0).unwrap();
        assert!((l.yaw_rate_max_radps.unwrap() - 90f64.to_radians()).abs() < 1e-12);
        let e = VehicleLimits::from_values(0.0, 150.0, 3000.0, 0.0, 3.0).unwrap_err();
        assert!(e.to_string().contains("WPNAV_SPEED_UP is 0"), "{e}");
    }
}
