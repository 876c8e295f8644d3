//! What a run is, when it carries no command: its kind of path, derived from its ground truth.
//!
//! Real recordings carry no command ids, so runs cannot be grouped as repeats of one command. They can be
//! grouped by what their measured motion shows: the **shape** (straight, turning on the spot, translating
//! then turning as a square does, arcs that translate while they turn, or free driving that turns both
//! ways), the **turn** (net heading change left, right or none), and bands of the **speed** and the **path
//! length** (factors of two). Runs in one group are runs *of the same kind*, not repeats of one command;
//! the words say so ([`GroupBasis::Motion`]).
//!
//! The motion is read over windows of [`WINDOW_S`] so that ground-truth noise does not count as motion.

use super::compare::Turn;
use omni_kin::Run;
use omni_kin::pose::wrap_angle;
use serde::{Deserialize, Serialize};

/// Length of the windows the motion is read over. s.
const WINDOW_S: f64 = 0.25;
/// Speed above which a window translates. m/s.
const TRANSLATING_M_S: f64 = 0.02;
/// Turn rate above which a window turns. rad/s.
const TURNING_RAD_S: f64 = 0.1;
/// Net heading change below which a run does not turn. rad.
const NET_TURN_RAD: f64 = 0.5;

/// How the runs of a group were found to belong together.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum GroupBasis {
    /// The runs repeat one command (the simulator's or the plan's command ids).
    #[default]
    Command,
    /// The runs carry no command: grouped by the kind of path their ground truth shows.
    Motion,
}

/// The shape of a run's path.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Shape {
    /// Translates without turning.
    Straight,
    /// Turns without translating.
    Spin,
    /// Translates and turns in separate stretches (a square: sides, then turns on the spot).
    TranslateThenTurn,
    /// Translates while it turns, one way (arcs, circles).
    Arc,
    /// Turns both ways (figure-eights, free driving): no two such runs are alike.
    Free,
}

/// A run's kind of path, derived from its ground truth.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub struct MotionKind {
    /// The shape.
    pub shape: Shape,
    /// The net turn.
    pub turn: Turn,
    /// Mean speed while translating, as a power of two of 0.1 m/s (0: about 0.1 m/s; 1: about 0.2).
    pub speed_band: i32,
    /// Path length, as a power of two of 1 m.
    pub length_band: i32,
}

impl MotionKind {
    /// Whether runs of this kind may be grouped: free driving is never repeated.
    pub fn groups(&self) -> bool {
        self.shape != Shape::Free
    }

    /// The shape in words: `straight`, `turning on the spot`, `sides then turns`, `arcs`, `free`.
    pub fn shape_label(&self) -> &'static str {
        match self.shape {
            Shape::Straight => "straight",
            Shape::Spin => "turning on the spot",
            Shape::TranslateThenTurn => "sides then turns",
            Shape::Arc => "arcs",
            Shape::Free => "free",
        }
    }

    /// `square-like, turning right, ~0.2 m/s, ~4 m`.
    pub fn label(&self) -> String {
        let shape = self.shape_label();
        let turn = match self.turn {
            Turn::Straight => "no net turn",
            Turn::Left => "net turn left",
            Turn::Right => "net turn right",
        };
        let speed = 0.1 * 2f64.powi(self.speed_band);
        let length = 2f64.powi(self.length_band);
        format!("{shape}, {turn}, ~{speed:.2} m/s, ~{length:.2} m")
    }

    /// The kind of `run` from its ground truth (`None` when it has fewer than two windows of motion).
    pub fn of(run: &Run) -> Option<Self> {
        let truth = run.truth();
        let (mut translating_only, mut turning_only, mut both) = (0.0, 0.0, 0.0);
        let (mut left, mut right, mut length, mut moving_time) = (0.0, 0.0, 0.0, 0.0);
        let mut i = 0;
        while i + 1 < truth.len() {
            let t0 = truth[i].t_s;
            let j = (i + 1..truth.len()).find(|&j| truth[j].t_s - t0 >= WINDOW_S).unwrap_or(truth.len() - 1);
            let dt = truth[j].t_s - t0;
            if dt <= 0.0 {
                break;
            }
            let (a, b) = (truth[i].pose, truth[j].pose);
            let ds = ((b.x_m - a.x_m).powi(2) + (b.y_m - a.y_m).powi(2)).sqrt();
            let dtheta = wrap_angle(b.theta_rad - a.theta_rad);
            let (translates, turns) = (ds / dt > TRANSLATING_M_S, dtheta.abs() / dt > TURNING_RAD_S);
            match (translates, turns) {
                (true, true) => both += dt,
                (true, false) => translating_only += dt,
                (false, true) => turning_only += dt,
                (false, false) => {}
            }
            if translates {
                length += ds;
                moving_time += dt;
            }
            if turns {
                if dtheta > 0.0 { left += dtheta } else { right -= dtheta }
            }
            i = j;
        }
        let moving = translating_only + turning_only + both;
        if moving <= 2.0 * WINDOW_S {
            return None;
        }
        let rotation = left + right;
        let shape = if rotation > 1.0 && left.min(right) > 0.25 * rotation {
            Shape::Free
        } else if both >= 0.5 * moving {
            Shape::Arc
        } else if turning_only < 0.1 * moving {
            Shape::Straight
        } else if translating_only < 0.1 * moving {
            Shape::Spin
        } else {
            Shape::TranslateThenTurn
        };
        let net = truth[truth.len() - 1].pose.theta_rad - truth[0].pose.theta_rad;
        let net = if (net - (left - right)).abs() > std::f64::consts::PI { left - right } else { net };
        let turn = if net.abs() < NET_TURN_RAD { Turn::Straight } else { Turn::of(net) };
        let band = |x: f64| if x > 0.0 { x.log2().round() as i32 } else { i32::MIN };
        let speed = if moving_time > 0.0 { length / moving_time } else { 0.0 };
        Some(Self { shape, turn, speed_band: band(speed / 0.1), length_band: band(length) })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use omni_kin::pose::{Pose2, StampedPose};
    use omni_kin::run::RunData;

    /// A run whose ground truth follows `pose(t)` for `duration_s` at 100 Hz (two wheels at rest: the
    /// kind reads only the ground truth).
    fn run_along(duration_s: f64, pose: impl Fn(f64) -> (f64, f64, f64)) -> Run {
        let n = (duration_s * 100.0) as usize + 1;
        let t: Vec<f64> = (0..n).map(|k| k as f64 * 0.01).collect();
        let truth = t
            .iter()
            .map(|&t_s| {
                let (x_m, y_m, theta_rad) = pose(t_s);
                StampedPose { t_s, pose: Pose2 { x_m, y_m, theta_rad } }
            })
            .collect();
        let data = RunData {
            name: "r".into(),
            wheel_rad_s: vec![0.0; 2 * n],
            n_wheels: 2,
            wheel_t_s: t,
            truth,
            ..Default::default()
        };
        Run::new(data).expect("a valid run")
    }

    #[test]
    fn circles_squares_lines_and_figure_eights_are_told_apart() {
        // A circle of radius 0.5 m at 0.2 m/s, turning left: arcs, ~0.2 m/s, one lap ≈ 3.1 m.
        let w = 0.4;
        let circle =
            run_along(2.0 * std::f64::consts::PI / w, |t| (0.5 * (w * t).sin(), 0.5 - 0.5 * (w * t).cos(), w * t));
        let k = MotionKind::of(&circle).expect("moves");
        assert_eq!((k.shape, k.turn, k.speed_band, k.length_band), (Shape::Arc, Turn::Left, 1, 2));
        assert!(k.groups());
        // A straight line at 0.4 m/s for 5 s.
        let line = MotionKind::of(&run_along(5.0, |t| (0.4 * t, 0.0, 0.0))).expect("moves");
        assert_eq!((line.shape, line.turn, line.speed_band, line.length_band), (Shape::Straight, Turn::Straight, 2, 1));
        // A square of 1 m sides at 0.25 m/s, turning right on the spot at 0.5 rad/s at each corner.
        let side = 4.0;
        let corner = std::f64::consts::FRAC_PI_2 / 0.5;
        let square = run_along(4.0 * (side + corner), |t| {
            let leg = (t / (side + corner)).floor().min(3.0);
            let s = t - leg * (side + corner);
            let heading = -leg * std::f64::consts::FRAC_PI_2;
            let (mut x, mut y) = (0.0, 0.0);
            for l in 0..leg as i32 {
                let h = -(l as f64) * std::f64::consts::FRAC_PI_2;
                (x, y) = (x + h.cos(), y + h.sin());
            }
            let along = (0.25 * s).min(1.0);
            let turned = ((s - side).max(0.0) * 0.5).min(std::f64::consts::FRAC_PI_2);
            (x + along * heading.cos(), y + along * heading.sin(), heading - turned)
        });
        let sq = MotionKind::of(&square).expect("moves");
        assert_eq!((sq.shape, sq.turn), (Shape::TranslateThenTurn, Turn::Right));
        // A figure-eight turns both ways: free, never grouped.
        let eight = MotionKind::of(&run_along(20.0, |t| {
            let a = 2.0 * std::f64::consts::PI * t / 20.0;
            (a.sin(), 0.5 * (2.0 * a).sin(), (2.0 * a).cos().atan2(a.cos()))
        }))
        .expect("moves");
        assert_eq!(eight.shape, Shape::Free);
        assert!(!eight.groups());
        // Standing still: no kind.
        assert_eq!(MotionKind::of(&run_along(3.0, |_| (0.0, 0.0, 0.0))), None);
    }
}
