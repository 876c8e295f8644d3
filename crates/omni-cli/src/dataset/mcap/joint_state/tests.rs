//! The JointState reader's unit tests.

use super::*;
use crate::dataset::mcap::common::Time;

fn wheels() -> Vec<String> {
    ["wheel_a", "wheel_b", "wheel_c"].map(String::from).to_vec()
}

fn msg(ns: i64, names: &[&str], position: &[f64], velocity: &[f64]) -> JointState {
    JointState {
        header: Header { stamp: Time::from_ns(ns).unwrap(), frame_id: RosString::default() },
        name: names.iter().map(|s| RosString(s.to_string())).collect(),
        position: position.to_vec(),
        velocity: velocity.to_vec(),
        effort: vec![],
    }
}

#[test]
fn maps_joints_by_name() {
    let mut s = JointSeries::default();
    s.push(msg(0, &["x", "wheel_c", "wheel_a", "wheel_b"], &[], &[9.0, 3.0, 1.0, 2.0]), &wheels(), 0).unwrap();
    s.push(msg(10, &["wheel_b", "wheel_a", "wheel_c"], &[], &[5.0, 4.0, 6.0]), &wheels(), 10).unwrap();
    let w = s.finish(&wheels(), &[0.0, 1e-8], &WheelData::default()).unwrap();
    assert_eq!(w.rad_s, [1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
    assert_eq!(w.differentiated, None);
    assert_eq!(w.position, None);
}

#[test]
fn differentiates_position_when_velocity_is_empty() {
    let mut s = JointSeries::default();
    let names = ["wheel_a", "wheel_b", "wheel_c"];
    s.push(msg(0, &names, &[0.0, 0.0, 0.0], &[]), &wheels(), 0).unwrap();
    s.push(msg(500_000_000, &names, &[1.0, -2.0, 0.5], &[]), &wheels(), 500_000_000).unwrap();
    s.push(msg(1_000_000_000, &names, &[2.0, -4.0, 0.5], &[]), &wheels(), 1_000_000_000).unwrap();
    let w = s.finish(&wheels(), &[0.0, 0.5, 1.0], &WheelData::default()).unwrap();
    assert_eq!(w.rad_s, [2.0, -4.0, 1.0, 2.0, -4.0, 1.0, 2.0, -4.0, 0.0]);
    assert_eq!(w.differentiated, Some(3));
}

#[test]
fn problems_name_the_field() {
    // A wheel joint in no message.
    let mut s = JointSeries::default();
    s.push(msg(0, &["wheel_a", "wheel_b"], &[], &[1.0, 2.0]), &wheels(), 0).unwrap();
    s.push(msg(1, &["wheel_a", "wheel_b"], &[], &[1.0, 2.0]), &wheels(), 0).unwrap();
    let e = s.finish(&wheels(), &[0.0, 1e-9], &WheelData::default()).unwrap_err();
    assert_eq!(e, (0, "wheel joint \"wheel_c\" is missing (names: wheel_a, wheel_b)".to_string()));
    let mut s = JointSeries::default();
    let e = s.push(msg(0, &["wheel_a", "wheel_b", "wheel_c"], &[], &[1.0, 2.0]), &wheels(), 0).unwrap_err();
    assert_eq!(e, "field velocity has 2 entries, expected 3 (one per name) or none");
    let names = ["wheel_a", "wheel_b", "wheel_c"];
    s.push(msg(5, &names, &[], &[1.0, f64::NAN, 2.0]), &wheels(), 5).unwrap();
    let e = s.push(msg(5, &names, &[], &[1.0, 1.0, 2.0]), &wheels(), 5).unwrap_err();
    assert_eq!(e, "header.stamp 0.000000005 is not after the previous message's 0.000000005 (stamps must increase)");
    s.push(msg(6, &names, &[], &[1.0, 1.0, 2.0]), &wheels(), 6).unwrap();
    let e = s.finish(&wheels(), &[0.0, 1e-9], &WheelData::default()).unwrap_err();
    assert_eq!(e, (0, "field velocity[1] (joint \"wheel_b\") is NaN".to_string()));
}

#[test]
fn other_publishers_repeats_and_unfilled_stamps_are_noted_not_refused() {
    let mut s = JointSeries::default();
    let names = ["wheel_a", "wheel_b", "wheel_c"];
    // header.stamp never filled: log time instead (the first message re-stamped).
    s.push(msg(0, &names, &[], &[1.0, 2.0, 3.0]), &wheels(), 100).unwrap();
    s.push(msg(0, &["shoulder", "elbow"], &[0.1, 0.2], &[]), &wheels(), 105).unwrap();
    s.push(msg(0, &names, &[], &[4.0, 5.0, 6.0]), &wheels(), 110).unwrap();
    s.push(msg(0, &names, &[], &[4.0, 5.0, 6.0]), &wheels(), 110).unwrap();
    let w = s.finish(&wheels(), &[0.0, 1e-8], &WheelData::default()).unwrap();
    assert_eq!(w.t_ns, [100, 110]);
    assert_eq!(w.rad_s, [1.0, 2.0, 3.0, 4.0, 5.0, 6.0]);
    assert_eq!(
        w.notes,
        [
            "1 messages name none of the wheel joints (another publisher on the topic): passed over",
            "1 messages repeat the one before exactly (stamp and values): dropped",
            "header.stamp is 0: the messages are stamped by their log time instead",
        ]
    );
    // A repeated stamp with other values is still an error.
    let mut s = JointSeries::default();
    s.push(msg(5, &names, &[], &[1.0, 2.0, 3.0]), &wheels(), 5).unwrap();
    assert!(s.push(msg(5, &names, &[], &[1.0, 2.0, 4.0]), &wheels(), 6).unwrap_err().contains("not after"));
}

#[test]
fn nan_velocity_beside_positions_uses_the_positions() {
    let mut s = JointSeries::default();
    let names = ["wheel_a", "wheel_b", "wheel_c"];
    let nan = f64::NAN;
    s.push(msg(0, &names, &[0.0, 0.0, 0.0], &[nan, nan, nan]), &wheels(), 0).unwrap();
    s.push(msg(500_000_000, &names, &[1.0, -2.0, 0.5], &[nan, nan, nan]), &wheels(), 1).unwrap();
    let w = s.finish(&wheels(), &[0.0, 0.5], &WheelData::default()).unwrap();
    assert_eq!(w.rad_s, [2.0, -4.0, 1.0, 2.0, -4.0, 1.0]);
    assert_eq!(w.differentiated, Some(2));
    assert_eq!(
        w.notes,
        ["2 messages have a NaN wheel velocity beside finite positions: their speeds come from the positions"]
    );
}

#[test]
fn wrapped_positions_are_unwrapped() {
    use std::f64::consts::{PI, TAU};
    // Wheel a turns +2 rad/s, wheel b −3 rad/s, reported modulo 2π in [−π, π]; wheel c counts turns.
    let wrap = |p: f64| (p + PI).rem_euclid(TAU) - PI;
    let mut s = JointSeries::default();
    let names = ["wheel_a", "wheel_b", "wheel_c"];
    let t: Vec<f64> = (0..40).map(|k| 0.1 * k as f64).collect();
    for (k, &ts) in t.iter().enumerate() {
        let p = [wrap(2.0 * ts), wrap(-3.0 * ts), 10.0 + ts];
        s.push(msg(100_000_000 * k as i64 + 1, &names, &p, &[]), &wheels(), 0).unwrap();
    }
    let w = s.finish(&wheels(), &t, &WheelData::default()).unwrap();
    for k in 1..t.len() {
        let v = &w.rad_s[3 * k..3 * k + 3];
        assert!((v[0] - 2.0).abs() < 1e-9 && (v[1] + 3.0).abs() < 1e-9 && (v[2] - 1.0).abs() < 1e-9, "{k}: {v:?}");
    }
    assert_eq!(
        w.notes,
        [
            "the position of joint \"wheel_a\" wraps around (an angle modulo 2π): unwrapped at 1 jumps before it is differentiated",
            "the position of joint \"wheel_b\" wraps around (an angle modulo 2π): unwrapped at 2 jumps before it is differentiated",
        ]
    );
}

#[test]
fn counts_and_rpm_behind_a_gear_become_wheel_radians() {
    use omni_kin::robot::{PositionUnit, VelocityUnit};
    use std::f64::consts::TAU;
    let names = ["wheel_a", "wheel_b", "wheel_c"];
    // A motor-side encoder of 1024 counts behind a 30:1 gear; velocities in motor rpm.
    let units = WheelData {
        position: PositionUnit::Counts,
        velocity: VelocityUnit::Rpm,
        counts_per_rev: Some(1024.0),
        gear_ratio: Some(30.0),
        source: None,
    };
    // Wheel speeds 1, −2, 0.5 rad/s: motor rpm = ω · 30 · 60 / 2π; counts = θ · 30 · 1024 / 2π.
    let omega = [1.0, -2.0, 0.5];
    let rpm: Vec<f64> = omega.iter().map(|w| w * 30.0 * 60.0 / TAU).collect();
    let mut s = JointSeries::default();
    let t = [0.0, 0.5];
    for (k, ts) in t.iter().enumerate() {
        let counts: Vec<f64> = omega.iter().map(|w| (w * ts * 30.0 * 1024.0 / TAU).round()).collect();
        s.push(msg(500_000_000 * k as i64 + 1, &names, &counts, &rpm), &wheels(), 0).unwrap();
    }
    let w = s.finish(&wheels(), &t, &units).unwrap();
    for (got, want) in w.rad_s.iter().zip(omega.iter().chain(&omega)) {
        assert!((got - want).abs() < 1e-12, "{got} vs {want}");
    }
    let p = w.position.unwrap();
    for (got, want) in p[3..].iter().zip(omega.map(|w| w * 0.5)) {
        assert!((got - want).abs() < TAU / (30.0 * 1024.0), "{got} vs {want}");
    }
    assert_eq!(
        w.notes,
        ["joint positions in counts and velocities in rpm (1024 counts per revolution) behind a 30:1 gear are \
             converted to the wheel's rad and rad/s ([wheel_data] in the robot description)"]
    );
}

/// 21 messages 0.05 s apart of wheels turning 1, −2 and 3 rad/s, positions their integral; `edit` changes
/// message `k`'s names, positions and velocities before it is pushed.
fn steady(edit: impl Fn(usize, &mut Vec<&str>, &mut Vec<f64>, &mut Vec<f64>)) -> (JointSeries, Vec<f64>) {
    let mut s = JointSeries::default();
    let t: Vec<f64> = (0..21).map(|k| 0.05 * k as f64).collect();
    for (k, &ts) in t.iter().enumerate() {
        let (mut names, mut p, mut v) =
            (vec!["wheel_a", "wheel_b", "wheel_c"], vec![ts, -2.0 * ts, 3.0 * ts], vec![1.0, -2.0, 3.0]);
        edit(k, &mut names, &mut p, &mut v);
        s.push(msg(50_000_000 * k as i64 + 1, &names, &p, &v), &wheels(), 0).unwrap();
    }
    (s, t)
}

#[test]
fn a_stale_copy_of_a_joint_is_passed_over_for_the_one_that_changes() {
    // The stale copy first (a driver's template, all zeros), the live joint after it.
    let stale_first = |_: usize, n: &mut Vec<&str>, p: &mut Vec<f64>, v: &mut Vec<f64>| {
        n.insert(0, "wheel_b");
        p.insert(0, 0.0);
        v.insert(0, 0.0);
    };
    let (s, t) = steady(stale_first);
    let w = s.finish(&wheels(), &t, &WheelData::default()).unwrap();
    assert!(w.rad_s.chunks(3).all(|r| r == [1.0, -2.0, 3.0]), "{:?}", &w.rad_s[..6]);
    assert_eq!(
        w.notes,
        ["joint \"wheel_b\" is named twice in 21 messages; its first entry never changes (velocity 0, position 0: a \
          stale copy), so the last entry, which changes, is read"]
    );
    // The stale copy last: the first entry is read.
    let stale_last = |_: usize, n: &mut Vec<&str>, p: &mut Vec<f64>, v: &mut Vec<f64>| {
        n.push("wheel_b");
        p.push(0.0);
        v.push(0.0);
    };
    let (s, t) = steady(stale_last);
    let w = s.finish(&wheels(), &t, &WheelData::default()).unwrap();
    assert!(w.rad_s.chunks(3).all(|r| r == [1.0, -2.0, 3.0]), "{:?}", &w.rad_s[..6]);
    assert!(w.notes[0].ends_with("so the first entry, which changes, is read"), "{:?}", w.notes);
    // Two copies that both change: refused.
    let both = |k: usize, n: &mut Vec<&str>, p: &mut Vec<f64>, v: &mut Vec<f64>| {
        n.push("wheel_b");
        p.push(k as f64);
        v.push(k as f64);
    };
    let (s, t) = steady(both);
    let (k, e) = s.finish(&wheels(), &t, &WheelData::default()).unwrap_err();
    assert_eq!(k, 0);
    assert_eq!(
        e,
        "joint \"wheel_b\" is named twice, with different values (velocity -2 and 0, position -0 and 0), and neither \
         entry stays the same from message to message: nothing tells which is the wheel; have the driver publish \
         each joint once"
    );
}

#[test]
fn a_joint_missing_now_and_then_is_interpolated_and_a_long_gap_refused() {
    let drop_b = |ks: &'static [usize]| {
        move |k: usize, n: &mut Vec<&str>, p: &mut Vec<f64>, v: &mut Vec<f64>| {
            if ks.contains(&k) {
                n.remove(1);
                p.remove(1);
                v.remove(1);
            }
        }
    };
    let (s, t) = steady(drop_b(&[4, 11, 12, 20]));
    let w = s.finish(&wheels(), &t, &WheelData::default()).unwrap();
    assert!(w.rad_s.chunks(3).all(|r| r == [1.0, -2.0, 3.0]), "{:?}", w.rad_s);
    let p = w.position.unwrap();
    assert!((p[3 * 12 + 1] + 2.0 * 0.6).abs() < 1e-12, "{}", p[3 * 12 + 1]);
    assert_eq!(
        w.notes,
        ["wheel joint \"wheel_b\" is missing from 4 of 21 messages (at most 2 in a row): its velocity and position \
          there are interpolated from the neighbouring messages"]
    );
    let (s, t) = steady(drop_b(&[5, 6, 7, 8]));
    let (k, e) = s.finish(&wheels(), &t, &WheelData::default()).unwrap_err();
    assert_eq!(k, 5);
    assert_eq!(
        e,
        "wheel joint \"wheel_b\" is missing from 4 messages in a row (samples 5 to 8, 0.250 s from the message before \
         to the one after): too long a gap to fill from its neighbours (at most 3 messages and 0.5 s); record the \
         joint in every message, or cut the recording before or after the gap"
    );
}

#[test]
fn position_and_velocity_that_disagree_are_refused_unless_the_source_is_declared() {
    use omni_kin::robot::WheelField;
    // Velocity in a unit 6.6 times the positions' (motor rpm beside wheel counts, both declared rad).
    let rpm = |_: usize, _: &mut Vec<&str>, _: &mut Vec<f64>, v: &mut Vec<f64>| v.iter_mut().for_each(|x| *x *= 6.6);
    let (s, t) = steady(rpm);
    let (k, e) = s.finish(&wheels(), &t, &WheelData::default()).unwrap_err();
    assert_eq!(k, 0);
    assert_eq!(
        e,
        "field velocity gives a wheel rate of 13.200 rad/s and field position 2.000 rad/s (medians over 0.5 s \
         windows: 6.60 times more by velocity; both read as rad and rad/s): the two fields disagree beyond noise (more than 1.2×), so one of \
         them is in another unit or on another shaft (motor rpm beside wheel encoder counts?). Say which to read in \
         robot.toml: [wheel_data] source = \"position\" or \"velocity\", with that field's unit and gear_ratio \
         (docs/formats.md)"
    );
    let by = |source| WheelData { source: Some(source), ..WheelData::default() };
    let (s, t) = steady(rpm);
    let w = s.finish(&wheels(), &t, &by(WheelField::Position)).unwrap();
    for r in w.rad_s.chunks(3) {
        assert!((r[0] - 1.0).abs() < 1e-9 && (r[1] + 2.0).abs() < 1e-9 && (r[2] - 3.0).abs() < 1e-9, "{r:?}");
    }
    assert!(w.notes[0].ends_with("the wheel speeds come from field position ([wheel_data] source = \"position\")"));
    let (s, t) = steady(rpm);
    let w = s.finish(&wheels(), &t, &by(WheelField::Velocity)).unwrap();
    assert_eq!(&w.rad_s[..3], &[1.0 * 6.6, -2.0 * 6.6, 3.0 * 6.6]);
    assert_eq!(w.differentiated, None);
    // Agreeing fields say nothing; positions a driver leaves at 0 are no second opinion.
    let (s, t) = steady(|_, _, _, _| {});
    assert!(s.finish(&wheels(), &t, &WheelData::default()).unwrap().notes.is_empty());
    let (s, t) = steady(|_, _, p, _| p.iter_mut().for_each(|x| *x = 0.0));
    assert!(s.finish(&wheels(), &t, &WheelData::default()).unwrap().notes.is_empty());
}
