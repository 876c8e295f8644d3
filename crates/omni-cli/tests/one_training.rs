//! One training sequence (issue 47 item 1): `omnical train` and the fleet's `train_quietly` build the model
//! file's summary in one place (`api::train::summarize`), so a differential drive with `[priors]` and a
//! lidar reference gets the same model file from both, byte for byte (the fleet's file used to lack the
//! priors and the mount warning).
#![allow(clippy::unwrap_used, clippy::expect_used)]

mod support;

use omni_cli::api::fit::FitOptions;
use omni_cli::api::load::DataOptions;
use omni_cli::api::train::{TrainRequest, train_quietly};
use omni_ga::calibrate::Preset;
use support::{succeeded, test_data};

#[test]
fn a_diff_robot_with_priors_and_a_lidar_gets_the_same_model_file_from_the_command_and_the_fleet() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let robot = test_data("diff_robot.toml");
    let args = ["simulate", "--robot", robot.to_str().unwrap(), "--effect", "wheel_radius:a=0.02", "--out", "sim"];
    let lidar = ["--runs-per-command", "1", "--lidar", "room", "--lidar-mount", "0.2,0.05,0", "--duration", "4", "-q"];
    succeeded(&[&args[..], &lidar].concat(), d);
    let text = std::fs::read_to_string(&robot).unwrap();
    let priors = "[priors]\nradius_std_m = 0.001\nseparation_std_m = 0.01\n";
    std::fs::write(d.join("sim/train/robot.toml"), format!("{text}{priors}")).unwrap();
    let train = d.join("sim/train");
    let (cli, fleet) = (d.join("cli.toml"), d.join("fleet.toml"));
    let cli_args = ["train", train.to_str().unwrap(), "--gt-scans", "/scan", "--out", cli.to_str().unwrap(), "-q"];
    succeeded(&cli_args, d);
    let request = TrainRequest {
        runs: vec![train.clone()],
        data: DataOptions { gt_scans: Some("/scan".into()), ..DataOptions::default() },
        model: None,
        start: None,
        preset: Preset::Default,
        seed: 0,
        effects: Vec::new(),
        out: Some(fleet.clone()),
        force: false,
        fit: FitOptions::default(),
    };
    train_quietly(&request).unwrap();
    let (a, b) = (std::fs::read_to_string(&cli).unwrap(), std::fs::read_to_string(&fleet).unwrap());
    assert!(a.contains("[[fit.priors]]") && a.contains("name = \"r_left\""), "{a}");
    assert_eq!(a, b, "the command's model file and the fleet's differ");
}
