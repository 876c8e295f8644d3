//! How well the design values are known (`[priors]`), and how far a parametric fit's search box reaches.

use super::error::{RobotError, positive};
use serde::{Deserialize, Serialize};

/// One-sigma uncertainties of the design values, as measured or as the drawings promise. Checked: finite
/// and positive. A parametric fit (`geometry`, `diff`, `mecanum`) searches the design ± [`PRIOR_BOX_SIGMAS`]
/// σ of each parameter they cover ([`Priors::std_of`]) instead of ±10 %, and reports its fitted values in σ.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Priors {
    /// Wheel radius. m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub radius_std_m: Option<f64>,
    /// Wheel position (each axis, or the distance). m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub position_std_m: Option<f64>,
    /// Wheel angle and drive direction. deg.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub angle_std_deg: Option<f64>,
    /// Wheel separation (`diff`). m.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub separation_std_m: Option<f64>,
}

/// How many standard deviations of a prior the GA's search box spans on each side of the design value.
pub const PRIOR_BOX_SIGMAS: f64 = 3.0;

impl Priors {
    /// The one-sigma uncertainty of a base parameter, by its name, in the parameter's unit (rad for
    /// angles): `radius_std_m` for the radii `r_*` (geometry, mecanum, diff), `position_std_m` for the
    /// distances `R_*` and the half-extents `lx`, `ly`, `angle_std_deg` for the angles `delta_*`,
    /// `separation_std_m` for `b`. `None` for what the priors do not cover (an `ik` matrix entry, a prior
    /// not given).
    pub fn std_of(&self, param: &str) -> Option<f64> {
        if param.starts_with("r_") {
            self.radius_std_m
        } else if param.starts_with("R_") || param == "lx" || param == "ly" {
            self.position_std_m
        } else if param.starts_with("delta_") {
            self.angle_std_deg.map(f64::to_radians)
        } else if param == "b" {
            self.separation_std_m
        } else {
            None
        }
    }

    pub(super) fn validate(&self) -> Result<(), RobotError> {
        let all = [
            ("radius_std_m", self.radius_std_m),
            ("position_std_m", self.position_std_m),
            ("angle_std_deg", self.angle_std_deg),
            ("separation_std_m", self.separation_std_m),
        ];
        for (f, v) in all {
            if let Some(v) = v {
                positive(format!("priors.{f}"), v)?;
            }
        }
        Ok(())
    }
}
