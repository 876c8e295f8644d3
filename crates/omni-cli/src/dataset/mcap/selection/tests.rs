use super::*;
use crate::dataset::mcap::poses::PoseSeries;
use crate::dataset::mcap::twist::Commands;

fn channel(topic: &str, msg_type: MsgType, frame: Option<&str>, problem: Option<&str>) -> Channel {
    let content = match msg_type {
        MsgType::Odometry => Content::Poses(PoseSeries { frame: frame.map(String::from), ..Default::default() }),
        _ => Content::Commands(Commands::default()),
    };
    Channel {
        topic: topic.into(),
        schema: String::new(),
        msg_type,
        messages: 3,
        content,
        problem: problem.map(|p| (Some(2), p.to_string())),
        geodetic_origin: None,
    }
}

#[test]
fn optional_sources_are_left_out_with_a_note() {
    let path = Path::new("a.mcap");
    let odom = |t: &str| channel(t, MsgType::Odometry, Some(ODOM_FRAME), None);
    let bag = Bag { path, channels: vec![odom("/robot1/odom"), odom("/robot2/odom")] };
    let mut notes = Vec::new();
    assert_eq!(bag.recorded_odometry(&mut notes), None);
    assert_eq!(
        notes.iter().map(ToString::to_string).collect::<Vec<_>>(),
        ["a.mcap: recorded odometry could come from several topics (/robot1/odom, /robot2/odom), none of them \
          /odom: recorded odometry is left out"]
    );
    let bag = Bag { path, channels: vec![odom("/robot1/odom"), odom("/odom")] };
    assert_eq!(bag.recorded_odometry(&mut Vec::new()), Some(1));

    let bag =
        Bag { path, channels: vec![channel("/cmd_vel", MsgType::TwistStamped, None, Some("field linear.x is NaN"))] };
    let mut notes = Vec::new();
    assert_eq!(bag.commands(None, &mut notes), None);
    // The note's text leaves the file to its source, so the same note from other files is said once.
    assert_eq!(notes[0].text, "topic \"/cmd_vel\", message 2: field linear.x is NaN (the command is left out)");
    assert_eq!(
        notes.iter().map(ToString::to_string).collect::<Vec<_>>(),
        ["a.mcap: topic \"/cmd_vel\", message 2: field linear.x is NaN (the command is left out)"]
    );
}

#[test]
fn a_localization_is_never_taken_as_ground_truth_unless_named() {
    let path = Path::new("a.mcap");
    let bag = Bag { path, channels: vec![channel("/amcl_pose", MsgType::Odometry, Some("map"), None)] };
    let e = crate::api::settings::as_flags(&bag.truth(&McapOptions::default()).err().unwrap().to_string());
    assert!(
        e.contains(
            "; /amcl_pose looks like a localization, which may fuse the wheel odometry being calibrated, so it is \
             not taken as ground truth unless named with --gt-topic. Without motion capture: a lidar's scans"
        ),
        "{e}"
    );
    let named = McapOptions { truth_topic: Some("/amcl_pose".into()), ..Default::default() };
    assert!(matches!(bag.truth(&named), Ok(Truth::Poses(0))));
    let bag = Bag {
        path,
        channels: vec![
            channel("/amcl_pose", MsgType::Odometry, Some("map"), None),
            channel("/mocap/pose", MsgType::Odometry, Some("world"), None),
        ],
    };
    assert!(matches!(bag.truth(&McapOptions::default()), Ok(Truth::Poses(1))));
}
