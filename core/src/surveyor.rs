//! Who walks the survey: the one surveyor type of the crate (SPEC section 4).
//!
//! The planner reads how often a sample is taken and how the labels are noised (the scan
//! spacing, the step error, the check-in turn threshold); the session also reads what it
//! needs to follow the walk (a human's step length, a robot's speed). One type carries both,
//! so a plan, its session and the app's profile cannot disagree about the surveyor, and the
//! defaults below are written once.
//!
//! # Serialised form
//! `{"kind": "human", "step_length_m": 0.7, "speed_mps": 1.2, "scan_interval_s": 4,
//! "step_error": 0.05, "turn_threshold_deg": 30}` or `{"kind": "robot", "interval_m": 0.5,
//! "speed_mps": 0.5}`. Stores, bundles and experiment files written before the types were
//! merged hold the planner's older form, `{"model": "robot", "interval": 0.5}` or
//! `{"model": "human", "speed": 1.2, "scan_interval": 4, "step_error": 0.05,
//! "turn_threshold_deg": 30}`; it is still read (the step length and the robot speed it
//! never carried take the defaults, which the utility does not depend on) and never written.

use serde::{Deserialize, Deserializer, Serialize};

use crate::{Error, Result};

/// Step length of a human surveyor without calibration, metres.
pub const DEFAULT_STEP_LENGTH_M: f64 = 0.7;
/// A person's walking speed, m/s (SPEC section 4).
pub const DEFAULT_WALKING_SPEED_MPS: f64 = 1.2;
/// Time between completed Wi-Fi scans on a phone, s (SPEC section 4).
pub const DEFAULT_SCAN_INTERVAL_S: f64 = 4.0;
/// Relative step-length error `eps` of a step counter (SPEC section 4).
pub const DEFAULT_STEP_ERROR: f64 = 0.05;
/// A vertex where the walk turns by more than this is a check-in, degrees (SPEC section 4).
pub const DEFAULT_TURN_THRESHOLD_DEG: f64 = 30.0;
/// The paper's robot: metres between scans.
pub const DEFAULT_ROBOT_INTERVAL_M: f64 = 0.5;
/// The paper's robot: speed, m/s (time estimates only).
pub const DEFAULT_ROBOT_SPEED_MPS: f64 = 0.5;

/// Who walks, and how often a scan is taken.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
#[serde(remote = "Self")]
pub enum Surveyor {
    /// A person with a phone counting steps. Labels carry an error that grows with the
    /// distance walked since the last check-in.
    Human {
        /// Step length before the session re-estimates it at check-ins, metres (from
        /// calibration, else [`DEFAULT_STEP_LENGTH_M`]).
        step_length_m: f64,
        /// Walking speed, m/s (time estimates and the sample spacing).
        speed_mps: f64,
        /// Time between completed Wi-Fi scans, s.
        scan_interval_s: f64,
        /// Relative step-length error `eps` of SPEC section 4.
        step_error: f64,
        /// A vertex where the walk turns by more than this is a check-in, degrees.
        turn_threshold_deg: f64,
    },
    /// A robot labelled by SLAM (its own poses), without extra label noise.
    Robot {
        /// Metres between scans (speed times scan period).
        interval_m: f64,
        /// Speed, m/s (time estimates only).
        speed_mps: f64,
    },
}

impl Default for Surveyor {
    /// The paper's robot.
    fn default() -> Self {
        Surveyor::robot()
    }
}

impl Serialize for Surveyor {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        Surveyor::serialize(self, s)
    }
}

/// The planner's surveyor form before the types were merged (see the module docs).
#[derive(Deserialize)]
#[serde(tag = "model", rename_all = "snake_case", deny_unknown_fields)]
enum Legacy {
    Robot {
        interval: f64,
    },
    Human {
        speed: f64,
        scan_interval: f64,
        step_error: f64,
        turn_threshold_deg: f64,
    },
}

impl From<Legacy> for Surveyor {
    fn from(l: Legacy) -> Self {
        match l {
            Legacy::Robot { interval } => Surveyor::Robot {
                interval_m: interval,
                speed_mps: DEFAULT_ROBOT_SPEED_MPS,
            },
            Legacy::Human {
                speed,
                scan_interval,
                step_error,
                turn_threshold_deg,
            } => Surveyor::Human {
                step_length_m: DEFAULT_STEP_LENGTH_M,
                speed_mps: speed,
                scan_interval_s: scan_interval,
                step_error,
                turn_threshold_deg,
            },
        }
    }
}

impl<'de> Deserialize<'de> for Surveyor {
    /// Reads the current form, or the older one when the object has a `model` tag and no
    /// `kind`; a bad object gets the error of the form its tag names.
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        use serde::de::Error as _;
        let v = serde_json::Value::deserialize(d)?;
        let legacy = v.get("kind").is_none() && v.get("model").is_some();
        if legacy {
            serde_json::from_value::<Legacy>(v)
                .map(Surveyor::from)
                .map_err(D::Error::custom)
        } else {
            Surveyor::deserialize(v).map_err(D::Error::custom)
        }
    }
}

impl Surveyor {
    /// A human surveyor with the defaults of SPEC section 4 and an uncalibrated step.
    pub fn human() -> Self {
        Surveyor::Human {
            step_length_m: DEFAULT_STEP_LENGTH_M,
            speed_mps: DEFAULT_WALKING_SPEED_MPS,
            scan_interval_s: DEFAULT_SCAN_INTERVAL_S,
            step_error: DEFAULT_STEP_ERROR,
            turn_threshold_deg: DEFAULT_TURN_THRESHOLD_DEG,
        }
    }

    /// The paper's robot: a scan every 0.5 m at 0.5 m/s.
    pub fn robot() -> Self {
        Surveyor::Robot {
            interval_m: DEFAULT_ROBOT_INTERVAL_M,
            speed_mps: DEFAULT_ROBOT_SPEED_MPS,
        }
    }

    /// A robot scanning every `interval_m` metres at the default speed.
    pub fn robot_every(interval_m: f64) -> Self {
        Surveyor::Robot {
            interval_m,
            speed_mps: DEFAULT_ROBOT_SPEED_MPS,
        }
    }

    /// Whether this is a human surveyor.
    pub fn is_human(&self) -> bool {
        matches!(self, Surveyor::Human { .. })
    }

    /// Walking (or driving) speed, m/s.
    pub fn speed_mps(&self) -> f64 {
        match *self {
            Surveyor::Human { speed_mps, .. } | Surveyor::Robot { speed_mps, .. } => speed_mps,
        }
    }

    /// Distance between consecutive samples, metres: a robot's scan interval, a person's
    /// speed times scan interval.
    pub fn spacing(&self) -> f64 {
        match *self {
            Surveyor::Robot { interval_m, .. } => interval_m,
            Surveyor::Human {
                speed_mps,
                scan_interval_s,
                ..
            } => speed_mps * scan_interval_s,
        }
    }

    /// The check-in turn threshold of a human, degrees; `None` for a robot, which checks in
    /// only at the ends.
    pub fn turn_threshold_deg(&self) -> Option<f64> {
        match *self {
            Surveyor::Human {
                turn_threshold_deg, ..
            } => Some(turn_threshold_deg),
            Surveyor::Robot { .. } => None,
        }
    }

    /// Checks every parameter; the message names the bad one.
    pub fn validate(&self) -> Result<()> {
        let bad = |name: &str, v: f64, want: &str| {
            Err(Error::InvalidRequest(format!(
                "surveyor: {name} must be {want}, got {v}"
            )))
        };
        let speed_ok = |v: f64| v.is_finite() && v > 0.0 && v <= 10.0;
        match *self {
            Surveyor::Robot {
                interval_m,
                speed_mps,
            } => {
                if !interval_m.is_finite() || interval_m < 0.01 {
                    return bad("interval", interval_m, "at least 0.01 m");
                }
                if !speed_ok(speed_mps) {
                    return bad("speed", speed_mps, "a positive number of m/s up to 10");
                }
            }
            Surveyor::Human {
                step_length_m,
                speed_mps,
                scan_interval_s,
                step_error,
                turn_threshold_deg,
            } => {
                if !speed_ok(step_length_m) {
                    return bad(
                        "step length",
                        step_length_m,
                        "a positive number of m up to 10",
                    );
                }
                if !speed_ok(speed_mps) {
                    return bad("speed", speed_mps, "a positive number of m/s up to 10");
                }
                if !scan_interval_s.is_finite() || scan_interval_s <= 0.0 {
                    return bad(
                        "scan interval",
                        scan_interval_s,
                        "a positive number of seconds",
                    );
                }
                if speed_mps * scan_interval_s < 0.01 {
                    return bad(
                        "speed x scan interval",
                        speed_mps * scan_interval_s,
                        "at least 0.01 m",
                    );
                }
                if !step_error.is_finite() || !(0.0..=1.0).contains(&step_error) {
                    return bad("step error", step_error, "between 0 and 1");
                }
                if !turn_threshold_deg.is_finite() || !(0.0..=180.0).contains(&turn_threshold_deg) {
                    return bad(
                        "turn threshold",
                        turn_threshold_deg,
                        "between 0 and 180 degrees",
                    );
                }
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_current_form_round_trips() {
        for s in [
            Surveyor::human(),
            Surveyor::robot(),
            Surveyor::robot_every(1.5),
        ] {
            let text = serde_json::to_string(&s).unwrap();
            assert!(text.contains("\"kind\""), "{text}");
            assert_eq!(serde_json::from_str::<Surveyor>(&text).unwrap(), s);
        }
    }

    #[test]
    fn the_older_planner_form_is_read_with_the_defaults_it_never_carried() {
        let robot: Surveyor = serde_json::from_str(r#"{"model":"robot","interval":0.8}"#).unwrap();
        assert_eq!(robot, Surveyor::robot_every(0.8));
        let human: Surveyor = serde_json::from_str(
            r#"{"model":"human","speed":1.0,"scan_interval":3,"step_error":0.1,"turn_threshold_deg":45}"#,
        )
        .unwrap();
        assert_eq!(
            human,
            Surveyor::Human {
                step_length_m: DEFAULT_STEP_LENGTH_M,
                speed_mps: 1.0,
                scan_interval_s: 3.0,
                step_error: 0.1,
                turn_threshold_deg: 45.0,
            }
        );
        assert_eq!(human.spacing(), 3.0);
    }

    #[test]
    fn a_bad_object_gets_the_error_of_its_own_form() {
        let e = serde_json::from_str::<Surveyor>(r#"{"model":"robot","intervall":0.8}"#)
            .unwrap_err()
            .to_string();
        assert!(e.contains("intervall"), "{e}");
        let e = serde_json::from_str::<Surveyor>(r#"{"kind":"robot","interval_m":0.5}"#)
            .unwrap_err()
            .to_string();
        assert!(e.contains("speed_mps"), "{e}");
        let e = serde_json::from_str::<Surveyor>(r#"{"kind":"cat"}"#)
            .unwrap_err()
            .to_string();
        assert!(e.contains("cat"), "{e}");
    }

    #[test]
    fn validation_names_the_bad_parameter() {
        let mut s = Surveyor::human();
        if let Surveyor::Human {
            scan_interval_s, ..
        } = &mut s
        {
            *scan_interval_s = f64::NAN;
        }
        let e = s.validate().unwrap_err().to_string();
        assert!(e.contains("scan interval"), "{e}");
        let e = Surveyor::robot_every(0.0)
            .validate()
            .unwrap_err()
            .to_string();
        assert!(e.contains("interval"), "{e}");
        let e = Surveyor::Robot {
            interval_m: 0.5,
            speed_mps: -1.0,
        }
        .validate()
        .unwrap_err()
        .to_string();
        assert!(e.contains("speed"), "{e}");
        assert!(Surveyor::human().validate().is_ok());
        assert!(Surveyor::robot().validate().is_ok());
    }
}
