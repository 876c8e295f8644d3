//! The units a recording's wheel joints are published in (`[wheel_data]` in `robot.toml`): ros2_control
//! publishes rad and rad/s, but many drivers outside it publish encoder counts or motor rpm, often on the
//! motor's side of a gearbox. The factors here turn those values into the wheel's rad and rad/s.

use super::error::{err, positive};
use super::{RobotError, RobotProblem};
use serde::{Deserialize, Serialize};
use std::f64::consts::TAU;

/// The unit of a joint's `position` field.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PositionUnit {
    /// Radians (ROS, REP-103).
    #[default]
    Rad,
    /// Degrees.
    Deg,
    /// Revolutions (turns).
    Rev,
    /// Encoder counts (`counts_per_rev` per turn of the encoder's shaft).
    Counts,
}

/// The unit of a joint's `velocity` field.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum VelocityUnit {
    /// rad/s (ROS, REP-103).
    #[default]
    RadS,
    /// deg/s.
    DegS,
    /// Revolutions per second.
    RevS,
    /// Revolutions per minute.
    Rpm,
    /// Encoder counts per second.
    CountsS,
}

/// Which field of the joints gives the wheel speeds (`[wheel_data] source`), when a recording has both and
/// they disagree (a driver's `velocity` in motor rpm beside `position` in wheel encoder counts).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum WheelField {
    /// The speeds are differences of `position` over the stamps.
    Position,
    /// The speeds are `velocity`.
    Velocity,
}

impl WheelField {
    /// The name used in `robot.toml` and in messages (the JointState field's).
    pub fn name(self) -> &'static str {
        match self {
            Self::Position => "position",
            Self::Velocity => "velocity",
        }
    }
}

/// `[wheel_data]`: the units of the wheels' joint data and the encoder and gearbox between the measured
/// shaft and the wheel. Every wheel joint shares them. The default (empty table) is ROS's rad and rad/s on
/// the wheel's own shaft.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WheelData {
    /// Unit of `position`. Default `rad`.
    #[serde(default, skip_serializing_if = "is_default")]
    pub position: PositionUnit,
    /// Unit of `velocity`. Default `rad_s`.
    #[serde(default, skip_serializing_if = "is_default")]
    pub velocity: VelocityUnit,
    /// Encoder counts per turn of the shaft the encoder is on (with `counts` or `counts_s`). counts/rev.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub counts_per_rev: Option<f64>,
    /// Turns of the measured shaft per turn of the wheel (a motor-side encoder behind a 19.2:1 gearbox:
    /// 19.2). Default 1.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gear_ratio: Option<f64>,
    /// The field the wheel speeds come from when a recording has both `position` and `velocity`. Default:
    /// `velocity`, and a recording whose two fields give different rates is refused until this is set.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub source: Option<WheelField>,
}

impl PositionUnit {
    /// The name used in `robot.toml`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Rad => "rad",
            Self::Deg => "deg",
            Self::Rev => "rev",
            Self::Counts => "counts",
        }
    }
}

impl VelocityUnit {
    /// The name used in `robot.toml`.
    pub fn name(self) -> &'static str {
        match self {
            Self::RadS => "rad_s",
            Self::DegS => "deg_s",
            Self::RevS => "rev_s",
            Self::Rpm => "rpm",
            Self::CountsS => "counts_s",
        }
    }
}

fn is_default<T: Default + PartialEq>(v: &T) -> bool {
    *v == T::default()
}

impl WheelData {
    /// Whether this is the default (for serde: an empty table is not written).
    pub fn is_default(&self) -> bool {
        is_default(self)
    }

    /// Whether the data is ROS's rad and rad/s on the wheel's shaft (nothing to convert).
    pub fn is_identity(&self) -> bool {
        *self == Self { source: self.source, ..Self::default() }
            || (self.position_rad_per_unit() == 1.0 && self.velocity_rad_s_per_unit() == 1.0)
    }

    /// Turns of the measured shaft per wheel turn.
    fn gear(&self) -> f64 {
        self.gear_ratio.unwrap_or(1.0)
    }

    /// Counts per turn, or 1 when no unit needs it (validation refuses counts without it).
    fn counts(&self) -> f64 {
        self.counts_per_rev.unwrap_or(1.0)
    }

    /// Wheel rad per unit of `position`.
    pub fn position_rad_per_unit(&self) -> f64 {
        let shaft_rad = match self.position {
            PositionUnit::Rad => 1.0,
            PositionUnit::Deg => TAU / 360.0,
            PositionUnit::Rev => TAU,
            PositionUnit::Counts => TAU / self.counts(),
        };
        shaft_rad / self.gear()
    }

    /// Wheel rad/s per unit of `velocity`.
    pub fn velocity_rad_s_per_unit(&self) -> f64 {
        let shaft_rad_s = match self.velocity {
            VelocityUnit::RadS => 1.0,
            VelocityUnit::DegS => TAU / 360.0,
            VelocityUnit::RevS => TAU,
            VelocityUnit::Rpm => TAU / 60.0,
            VelocityUnit::CountsS => TAU / self.counts(),
        };
        shaft_rad_s / self.gear()
    }

    /// Checks: `counts_per_rev` given exactly when a unit is counts, and > 0; `gear_ratio` > 0.
    pub(super) fn validate(&self) -> Result<(), RobotError> {
        let counts = self.position == PositionUnit::Counts || self.velocity == VelocityUnit::CountsS;
        match self.counts_per_rev {
            Some(c) => {
                positive("wheel_data.counts_per_rev".into(), c)?;
                if !counts {
                    return Err(err(
                        "wheel_data.counts_per_rev",
                        RobotProblem::Layout("counts_per_rev is for position = \"counts\" or velocity = \"counts_s\""),
                    ));
                }
            }
            None if counts => {
                return Err(err(
                    "wheel_data.counts_per_rev",
                    RobotProblem::Layout("position = \"counts\" or velocity = \"counts_s\" needs counts_per_rev"),
                ));
            }
            None => {}
        }
        if let Some(g) = self.gear_ratio {
            positive("wheel_data.gear_ratio".into(), g)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn factors_turn_counts_rpm_and_gears_into_wheel_radians() {
        let enc = WheelData {
            position: PositionUnit::Counts,
            velocity: VelocityUnit::Rpm,
            counts_per_rev: Some(4096.0),
            gear_ratio: Some(19.2),
            source: None,
        };
        // 4096 counts · 19.2 = one wheel turn; 60 · 19.2 motor rpm = one wheel turn per second.
        assert!((enc.position_rad_per_unit() * 4096.0 * 19.2 - TAU).abs() < 1e-12);
        assert!((enc.velocity_rad_s_per_unit() * 60.0 * 19.2 - TAU).abs() < 1e-12);
        let deg = WheelData { position: PositionUnit::Deg, velocity: VelocityUnit::DegS, ..Default::default() };
        assert!((deg.position_rad_per_unit() * 180.0 - std::f64::consts::PI).abs() < 1e-15);
        assert!((deg.velocity_rad_s_per_unit() * 360.0 - TAU).abs() < 1e-15);
        let rev = WheelData { position: PositionUnit::Rev, velocity: VelocityUnit::RevS, ..Default::default() };
        assert_eq!((rev.position_rad_per_unit(), rev.velocity_rad_s_per_unit()), (TAU, TAU));
        assert!(WheelData::default().is_identity());
        assert!(!enc.is_identity());
    }

    #[test]
    fn counts_need_counts_per_rev_and_values_must_be_positive() {
        let problem = |d: WheelData| d.validate().unwrap_err().to_string();
        let counts = WheelData { position: PositionUnit::Counts, ..Default::default() };
        assert_eq!(
            problem(counts.clone()),
            "wheel_data.counts_per_rev: position = \"counts\" or velocity = \"counts_s\" needs counts_per_rev"
        );
        assert_eq!(
            problem(WheelData { counts_per_rev: Some(0.0), ..counts.clone() }),
            "wheel_data.counts_per_rev: 0 must be > 0"
        );
        assert_eq!(
            problem(WheelData { counts_per_rev: Some(1024.0), ..Default::default() }),
            "wheel_data.counts_per_rev: counts_per_rev is for position = \"counts\" or velocity = \"counts_s\""
        );
        assert_eq!(
            problem(WheelData { gear_ratio: Some(-3.0), ..Default::default() }),
            "wheel_data.gear_ratio: -3 must be > 0"
        );
        assert!(WheelData { counts_per_rev: Some(1024.0), gear_ratio: Some(30.0), ..counts }.validate().is_ok());
    }
}
