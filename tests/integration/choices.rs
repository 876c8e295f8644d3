//! One source of truth at the edges: the library's choices (preset, objective, …) carry the names that
//! serde, the command line and Python use, and the command line's defaults are the library's.

use clap::{CommandFactory, Parser};
use omni_cli::cli::{Cli, Command};
use omni_ga::calibrate::{Preset, Unexcited};
use omni_ga::diagnose::DiagnoseOptions;
use omni_ga::excitation::{PlanRequest, RunSet};
use omni_ga::identify::IdentifyOptions;
use omni_kin::robot::BaseKind;
use omni_kin::simulate::SimConfig;
use omni_kin::{Choice, CostKind, CostName, KinematicsKind};

/// Every id parses back, serde writes the same id, and the command line lists the ids (kebab-case) with
/// their help lines, in the library's order.
fn check<T: Choice + std::fmt::Debug + serde::Serialize + std::str::FromStr>(cmd: &str, flag: &str)
where
    T::Err: std::fmt::Debug,
{
    for &v in T::ALL {
        assert_eq!(serde_json::to_string(&v).unwrap(), format!("{:?}", v.id()), "{v:?}");
        assert_eq!(v.id().parse::<T>().unwrap(), v);
        assert_eq!(v.flag_value().parse::<T>().unwrap(), v);
    }
    let cli = Cli::command();
    let arg = cli.find_subcommand(cmd).unwrap().get_arguments().find(|a| a.get_id() == flag).unwrap();
    let listed: Vec<(String, String)> = arg
        .get_possible_values()
        .iter()
        .map(|p| (p.get_name().to_string(), p.get_help().map(|h| h.to_string()).unwrap_or_default()))
        .collect();
    let want: Vec<(String, String)> = T::ALL.iter().map(|v| (v.flag_value(), v.describe().to_string())).collect();
    assert_eq!(listed, want, "{cmd} --{flag}");
}

#[test]
fn choices_have_one_name_everywhere() {
    check::<Preset>("train", "preset");
    check::<KinematicsKind>("train", "model");
    check::<KinematicsKind>("plan", "model");
    check::<CostName>("train", "objective");
    check::<Unexcited>("train", "unexcited");
    check::<RunSet>("plan", "set");
    check::<BaseKind>("init", "kind");
    assert_eq!(CostName::EndPose.flag_value(), "end-pose");
    assert_eq!(CostKind::PATH.name(), "path");
    // Messages list the default first; callers say what was chosen (`preset "fast": …`).
    assert_eq!("fast".parse::<Preset>().unwrap_err().to_string(), r#""fast": expected "default" or "paper""#);
    assert_eq!("x".parse::<RunSet>().unwrap_err().to_string(), r#""x": expected "greedy" or "flower""#);
    assert_eq!(
        "wheels".parse::<KinematicsKind>().unwrap_err().to_string(),
        r#""wheels": expected "ik", "geometry", "diff", "mecanum" or "skid""#
    );
    assert_eq!(
        "tank".parse::<BaseKind>().unwrap_err().to_string(),
        r#""tank": expected "omni", "mecanum", "diff" or "skid""#
    );
}

#[test]
fn command_line_defaults_are_the_library_defaults() {
    let cli = Cli::try_parse_from(["omnical", "train", "runs/"]).unwrap();
    let Command::Train(t) = cli.command else { panic!("train") };
    assert_eq!(t.preset, Preset::default());
    assert_eq!(t.model, None, "train fits the robot's own kind: diff for a differential drive, else ik");
    let id = IdentifyOptions::default();
    assert_eq!((t.fit.max_std_error, t.fit.min_excitation), (id.max_std_error, id.min_excitation));
    assert_eq!(t.fit.max_std_error, 0.05);
    assert_eq!(CostKind::Path { every: t.fit.every, heading_weight_m_per_rad: t.fit.heading_weight }, CostKind::PATH);

    let cli = Cli::try_parse_from(["omnical", "plan"]).unwrap();
    let Command::Plan(p) = cli.command else { panic!("plan") };
    let (got, want) = (p.request(), PlanRequest::default());
    assert_eq!(serde_json::to_value(&got).unwrap(), serde_json::to_value(&want).unwrap());

    let cli = Cli::try_parse_from(["omnical", "diagnose", "--model", "design", "runs/"]).unwrap();
    let Command::Diagnose(d) = cli.command else { panic!("diagnose") };
    assert_eq!(d.min_gain, DiagnoseOptions::default().min_gain);

    let cli = Cli::try_parse_from(["omnical", "simulate", "--out", "sim"]).unwrap();
    let Command::Simulate(s) = cli.command else { panic!("simulate") };
    let sim = SimConfig::default();
    assert_eq!((s.runs_per_command_or_default(), s.duration_s), (sim.runs_per_command, sim.duration_s));
    assert_eq!(s.robot, "apr02");

    let cli = Cli::try_parse_from(["omnical", "init", "rec.mcap"]).unwrap();
    let Command::Init(i) = cli.command else { panic!("init") };
    assert_eq!(i.max_file_mb << 20, omni_cli::dataset::DEFAULT_MAX_FILE_BYTES);
    assert_eq!((i.out.to_str(), i.kind), (Some("robot.toml"), None));
    let cli = Cli::try_parse_from(["omnical", "init", "rec.mcap", "--kind", "diff"]).unwrap();
    let Command::Init(i) = cli.command else { panic!("init") };
    assert_eq!(i.kind, Some(BaseKind::Diff));
}
