//! What several of omni-ga's integration tests share: the paper's design and an effect outside the
//! catalogue.

use omni_kin::effect::{Effect, ParamSpec, Stage};
use omni_kin::{FittedModel, IkMatrix, Model, Twist2};

/// The heading drifts in proportion to the distance travelled, `ω += k |v|` (rad/m): outside the
/// catalogue, expressed by the `body` family's `omega_speed`.
#[derive(Debug)]
pub struct HeadingDrift;

impl Effect for HeadingDrift {
    fn id(&self) -> &str {
        "heading_drift"
    }
    fn describe(&self) -> String {
        "test: heading drift growing with speed".into()
    }
    fn stage(&self) -> Stage {
        Stage::Twist
    }
    fn params(&self) -> Vec<ParamSpec> {
        vec![ParamSpec::new("k", "rad/m", 0.0, -1.0, 1.0)]
    }
    fn twist(&self, p: &[f64], t: Twist2, _w: &[f64]) -> Twist2 {
        Twist2 { omega_rad_s: t.omega_rad_s + p[0] * t.vx_m_s.hypot(t.vy_m_s), ..t }
    }
}

/// The paper's design matrix (Eq. 7), as a model.
pub fn design() -> FittedModel {
    FittedModel::nominal(Model::ik(IkMatrix::paper_design()))
}
