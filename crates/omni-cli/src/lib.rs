//! # omni-cli
//!
//! The edges of omnical: datasets (CSV, OptiOdom, ROS 2 MCAP), model files, reports, and the `omnical`
//! command built on them.
#![deny(missing_docs)]

pub mod api;
pub mod argv;
pub mod atomic;
pub mod cli;
pub mod cmd;
pub mod controller;
pub mod dataset;
pub mod design;
pub mod entry;
pub mod export;
pub mod init;
pub mod interrupt;
pub mod lidar;
pub mod logging;
pub mod model_file;
pub mod out_path;
pub mod progress;
pub mod project_file;
pub mod report;
pub mod robot_config;
pub mod robot_file;
pub mod toml_error;
pub mod units;
