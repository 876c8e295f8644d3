//! # omni-kin
//!
//! The kinematics core of omnical: robot geometry and the inverse kinematic (IK) matrix (the paper's
//! Eq. 3 and Eq. 7), validated runs, fixed-step and exact-arc odometry (Eq. 1), costs (Eq. 6 and a path
//! cost), models with physical effects, and a seeded simulator of the paper's flower benchmark.
//!
//! No file or terminal I/O happens here: everything takes and returns plain data.
//!
//! Units follow ROS REP-103: metres, seconds, radians, rad/s; x forward, y left, yaw counter-clockwise.
#![deny(missing_docs)]

pub mod ape;
pub mod choice;
pub mod clock;
pub mod cost;
pub mod effect;
pub mod error;
pub mod evaluate;
pub mod fast;
pub mod geometry;
pub mod gyro;
pub mod hand_eye;
pub mod ik;
pub mod kinematics;
pub mod lidar;
pub mod model;
pub mod noise;
pub mod odometry;
pub mod plan;
pub mod pose;
pub mod position_only;
pub mod reference;
pub mod relative;
pub mod robot;
pub mod run;
pub mod run_models;
pub mod simulate;
pub mod stats;
pub mod travel;

pub use ape::{AbsoluteErrors, ApeSummary};
pub use choice::Choice;
pub use cost::{CostKind, CostName};
pub use effect::{Effect, EffectKind, ParamSpec, Stage};
pub use error::KinError;
pub use geometry::{RobotGeometry, Wheel};
pub use ik::IkMatrix;
pub use kinematics::{BaseKinematics, BaseRecord, KinematicsKind, UnexcitedBase};
pub use model::{FittedModel, Integration, Kinematics, Model, Scheme, StepMode};
pub use odometry::{Selection, Trajectory};
pub use pose::{Pose2, PoseError, StampedPose, Twist2};
pub use relative::{RelativeErrors, RpeDelta, RpeSummary};
pub use robot::{BaseKind, RobotDescription};
pub use run::{Command, Run, RunData};
pub use run_models::{RunModels, ToRunModels};
pub use stats::Stats;
