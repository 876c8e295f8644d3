//! References that give positions only (UWB, GNSS, a tracker without heading; issue 43 item 5): a `--gt`
//! CSV with `t,x,y` columns is read as such, each run's start heading is fitted with the model, and the
//! identifiability says what such a reference leaves undetermined (the body frame's orientation).
#![allow(clippy::unwrap_used, clippy::expect_used)] // test code: a failed unwrap is a failed test

mod support;

use omni_cli::dataset::ground_truth::{GroundTruthOptions, Kept};
use omni_cli::dataset::{self, LoadOptions};
use omni_kin::IkMatrix;
use std::fmt::Write as _;
use std::path::Path;
use support::{omnical, stderr, succeeded_on_two_threads};

/// Splits the simulated CSV runs of `sim/PART` into wheel logs (`d/PART/wheels`, with the robot.toml) and
/// ground-truth files of positions only (`d/PART/gt/RUN.csv`, columns `t,x,y`) and with a heading
/// (`d/PART/gtyaw`, `t,x,y,yaw`).
fn split(dir: &Path, part: &str) {
    let (wheels, gt, gtyaw) =
        (dir.join(format!("d/{part}/wheels")), dir.join(format!("d/{part}/gt")), dir.join(format!("d/{part}/gtyaw")));
    for d in [&wheels, &gt, &gtyaw] {
        std::fs::create_dir_all(d).unwrap();
    }
    let src = dir.join(format!("sim/{part}"));
    std::fs::copy(src.join("robot.toml"), wheels.join("robot.toml")).unwrap();
    for entry in std::fs::read_dir(&src).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|e| e != "csv") {
            continue;
        }
        let text = std::fs::read_to_string(&path).unwrap();
        let (comments, rows): (Vec<&str>, Vec<&str>) = text.lines().partition(|l| l.starts_with('#'));
        let header: Vec<&str> = rows[0].split(',').collect();
        let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
        let wheel_cols: Vec<usize> = (0..header.len()).filter(|&i| header[i].starts_with("wheel_")).collect();
        let (t, x, y, th) = (col("t_s"), col("x_m"), col("y_m"), col("theta_rad"));
        let mut w = comments.join("\n") + "\n";
        w += &std::iter::once("t_s").chain(wheel_cols.iter().map(|&i| header[i])).collect::<Vec<_>>().join(",");
        w.push('\n');
        let (mut g, mut gy) = (String::from("t,x,y\n"), String::from("t,x,y,yaw\n"));
        for row in &rows[1..] {
            let f: Vec<&str> = row.split(',').collect();
            if !f[wheel_cols[0]].is_empty() {
                let values: Vec<&str> = wheel_cols.iter().map(|&i| f[i]).collect();
                writeln!(w, "{},{}", f[t], values.join(",")).unwrap();
            }
            if !f[x].is_empty() {
                writeln!(g, "{},{},{}", f[t], f[x], f[y]).unwrap();
                writeln!(gy, "{},{},{},{}", f[t], f[x], f[y], f[th]).unwrap();
            }
        }
        let name = path.file_name().unwrap();
        std::fs::write(wheels.join(name), w).unwrap();
        std::fs::write(gt.join(name), g).unwrap();
        std::fs::write(gtyaw.join(name), gy).unwrap();
    }
}

fn matrix_of(path: &Path) -> IkMatrix {
    let f = omni_cli::model_file::read(path).unwrap();
    f.model.resolve(&f.params).unwrap().ik.clone()
}

/// The translational rows of `m` turned by the angle that best lays them on `truth`'s, and that angle (rad).
fn aligned_rows(m: &IkMatrix, truth: &IkMatrix) -> (Vec<[f64; 2]>, f64) {
    let n = m.n_wheels();
    let col = |k: &IkMatrix, j: usize| [k.entries()[j], k.entries()[n + j]];
    let (mut cross, mut dot) = (0.0, 0.0);
    for j in 0..n {
        let (a, b) = (col(m, j), col(truth, j));
        cross += a[0] * b[1] - a[1] * b[0];
        dot += a[0] * b[0] + a[1] * b[1];
    }
    let d = f64::atan2(cross, dot);
    let (s, c) = d.sin_cos();
    ((0..n).map(|j| col(m, j)).map(|a| [c * a[0] - s * a[1], s * a[0] + c * a[1]]).collect(), d)
}

#[test]
fn a_position_only_reference_calibrates_the_rotation_row_and_the_translation_up_to_the_frames_orientation() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let sim = ["simulate", "--out", "sim", "--runs-per-command", "1", "--duration", "4", "--format", "csv"];
    succeeded_on_two_threads(&sim, dir);
    split(dir, "train");

    // Read as positions only: no heading, the stamps kept as recorded (no heading to estimate a clock with).
    let opts = LoadOptions {
        ground_truth: Some(GroundTruthOptions { path: dir.join("d/train/gt"), ..Default::default() }),
        ..Default::default()
    };
    let ds = dataset::load(&[dir.join("d/train/wheels")], &opts).unwrap();
    assert_eq!(ds.runs.len(), 36);
    assert!(ds.runs.iter().all(|r| r.truth_position_only() && r.truth().iter().all(|p| p.pose.theta_rad == 0.0)));
    assert!(ds.ground_truth_clocks.iter().all(|c| c.kept == Some(Kept::PositionOnly) && c.offset_s == 0.0));

    let train = ["--threads", "2", "train", "d/train/wheels", "--gt", "d/train/gt", "--out", "pos.toml"];
    let out = support::succeeded(&train, dir);
    let err = stderr(&out);
    assert!(err.contains("note: 36 of 36 runs have a reference of positions only (no heading)"), "{err}");
    assert!(err.contains("cannot see the orientation of the body frame"), "{err}");
    // No noise model: its heading terms need a measured heading.
    assert!(!support::stdout(&out).contains("odometry noise"), "{}", support::stdout(&out));
    assert!(omni_cli::model_file::read_noise(&dir.join("pos.toml")).unwrap().is_none());
    succeeded_on_two_threads(&["train", "d/train/wheels", "--gt", "d/train/gtyaw", "--out", "yaw.toml"], dir);

    let truth = IkMatrix::paper_calibrated();
    let design = IkMatrix::paper_design();
    let (pos, yaw) = (matrix_of(&dir.join("pos.toml")), matrix_of(&dir.join("yaw.toml")));
    // The rotation row (ω per wheel rad/s) is determined: within 0.6 % of the truth (Eq. 9) entry by entry
    // (with a heading: 0.3 %), where the design is 0.5–1.4 % off.
    for j in 0..3 {
        let (p, y, t) = (pos.entries()[6 + j], yaw.entries()[6 + j], truth.entries()[6 + j]);
        assert!((p / t - 1.0).abs() < 0.006, "ω row, wheel {j}: {p} vs {t}\n{pos:?}");
        assert!((y / t - 1.0).abs() < 0.003, "ω row, wheel {j}: {y} vs {t}");
    }
    // The translational rows up to one rotation (the frame's orientation, which positions cannot see):
    // within 0.8 % of the truth's scale, closer than the design's; the rotation itself stays small.
    let scale = truth.entries()[..6].iter().map(|v| v * v).sum::<f64>().sqrt();
    let off = |m: &IkMatrix| {
        let (rows, d) = aligned_rows(m, &truth);
        let e: f64 = (0..3)
            .map(|j| (rows[j][0] - truth.entries()[j]).powi(2) + (rows[j][1] - truth.entries()[3 + j]).powi(2))
            .sum();
        (e.sqrt() / scale, d)
    };
    let ((p_off, p_turn), (d_off, _)) = (off(&pos), off(&design));
    assert!(p_off < 0.008 && p_off < d_off, "positions only {p_off}, design {d_off}\n{pos:?}");
    assert!(p_turn.abs() < 0.02, "{p_turn} rad");
}

#[test]
fn position_only_columns_can_be_named_and_a_clock_they_cannot_estimate_is_refused_when_the_stamps_miss() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let sim = ["simulate", "--out", "sim", "--runs-per-command", "1", "--duration", "3", "--format", "csv"];
    succeeded_on_two_threads(&sim, dir);
    split(dir, "validation");
    // `--gt-columns t,x,y` reads a file that has a heading as positions only.
    let args = ["--threads", "2", "eval", "--model", "paper", "d/validation/wheels", "--gt", "d/validation/gtyaw"];
    let listed = support::succeeded(&[&args[..], &["--gt-columns", "t,x,y"]].concat(), dir);
    assert!(stderr(&listed).contains("stamps kept as recorded, since a file of positions only"), "{}", stderr(&listed));
    // A bare word that is no column is refused, naming both forms.
    let bad = omnical(&[&args[..], &["--gt-columns", "stamp"]].concat(), dir);
    assert_eq!(bad.status.code(), Some(2));
    assert!(
        stderr(&bad).contains(
            "--gt-columns/--gt-units \"stamp\": expected KEY=VALUE (or, for --gt-columns, the list of columns present: \
             t,x,y for positions only)"
        ),
        "{}",
        stderr(&bad)
    );
    // Stamps that miss the wheel data cannot be mended without a heading: refused, naming --gt-time-offset.
    let gt = dir.join("d/validation/gt");
    let first = std::fs::read_dir(&gt).unwrap().next().unwrap().unwrap().path();
    let text = std::fs::read_to_string(&first).unwrap();
    let moved: String = std::iter::once("t,x,y".to_string())
        .chain(text.lines().skip(1).map(|l| {
            let (t, rest) = l.split_once(',').unwrap();
            format!("{},{rest}", t.parse::<f64>().unwrap() + 1000.0)
        }))
        .collect::<Vec<_>>()
        .join("\n");
    std::fs::write(&first, moved).unwrap();
    let e = omnical(&["eval", "--model", "paper", "d/validation/wheels", "--gt", "d/validation/gt"], dir);
    assert_eq!(e.status.code(), Some(2), "{}", stderr(&e));
    assert!(
        stderr(&e).contains("gives positions only, so its clock cannot be estimated from the wheels"),
        "{}",
        stderr(&e)
    );
    assert!(stderr(&e).contains("give the offset with --gt-time-offset SECONDS"), "{}", stderr(&e));
}

/// GNSS or UWB exported to TUM writes a fixed orientation (an identity quaternion) beside its positions:
/// a heading that never changes while the robot moves is read as none, not as a robot that never turns.
#[test]
fn a_tum_file_whose_heading_never_changes_is_read_as_positions_only() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let sim = ["simulate", "--out", "sim", "--runs-per-command", "1", "--duration", "3", "--format", "csv"];
    succeeded_on_two_threads(&sim, dir);
    split(dir, "validation");
    let tum = dir.join("d/validation/tum");
    std::fs::create_dir_all(&tum).unwrap();
    for entry in std::fs::read_dir(dir.join("d/validation/gt")).unwrap() {
        let path = entry.unwrap().path();
        let text = std::fs::read_to_string(&path).unwrap();
        let rows: Vec<String> =
            text.lines().skip(1).map(|l| format!("{} 0 0 0 1", l.replace(',', " ") + " 0")).collect();
        std::fs::write(tum.join(path.file_stem().unwrap()).with_extension("tum"), rows.join("\n")).unwrap();
    }
    let opts = LoadOptions {
        ground_truth: Some(GroundTruthOptions { path: tum.clone(), ..Default::default() }),
        ..Default::default()
    };
    let ds = dataset::load(&[dir.join("d/validation/wheels")], &opts).unwrap();
    assert_eq!(ds.runs.len(), 36);
    assert!(ds.runs.iter().all(omni_kin::Run::truth_position_only));
    assert!(
        ds.ground_truth_clocks.iter().all(|c| c.kept == Some(Kept::PositionOnly)),
        "{:?}",
        ds.ground_truth_clocks[0]
    );
    // The matrix that made the runs (Eq. 9) lies on these positions within millimetres (the path cost, each
    // run's start heading aligned); the design (Eq. 7) is several times further off.
    let path_cost = |model: &str| {
        let args =
            ["--threads", "2", "eval", "--model", model, "d/validation/wheels", "--gt", "d/validation/tum", "--json"];
        let v: serde_json::Value = serde_json::from_str(&support::stdout(&support::succeeded(&args, dir))).unwrap();
        v["path_cost"].as_f64().unwrap_or_else(|| panic!("{v}"))
    };
    let (paper, design) = (path_cost("paper"), path_cost("design"));
    assert!(paper < 0.006 && design > 3.0 * paper, "paper {paper}, design {design}");
}

/// The built-in robot's simulated MCAP runs (1 per flower command, 3 s) in `dir/sim`, and a copy of its
/// validation set in `dir/folder` (with the robot.toml) whose every recording `rewrite(from, to)` made.
fn simulated_validation_rewritten(dir: &Path, folder: &str, rewrite: impl Fn(&Path, &Path)) -> std::path::PathBuf {
    let sim = ["simulate", "--out", "sim", "--runs-per-command", "1", "--duration", "3"];
    succeeded_on_two_threads(&sim, dir);
    let to = dir.join(folder);
    std::fs::create_dir_all(&to).unwrap();
    std::fs::copy(dir.join("sim/validation/robot.toml"), to.join("robot.toml")).unwrap();
    for entry in std::fs::read_dir(dir.join("sim/validation")).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "mcap") {
            rewrite(&path, &to.join(path.file_name().unwrap()));
        }
    }
    to
}

/// `omnical eval --model MODEL dir/FOLDER`'s path cost (on two threads).
fn path_cost(dir: &Path, folder: &str, model: &str) -> f64 {
    let args = ["--threads", "2", "eval", "--model", model, folder, "--json"];
    let v: serde_json::Value = serde_json::from_str(&support::stdout(&support::succeeded(&args, dir))).unwrap();
    v["path_cost"].as_f64().unwrap_or_else(|| panic!("{v}"))
}

/// `src` with its ground-truth topic's PoseStamped messages turned into PointStamped ones (the same header
/// and position, no orientation: a PoseStamped's CDR cut after its position is a PointStamped's), as a
/// tracker or a total station publishes positions; every other channel as it was. `clicked`: the truth
/// stays, and its first position is also published as a PointStamped on `/clicked_point` (as RViz does).
fn with_point_stamped(src: &Path, to: &Path, clicked: bool) {
    use std::collections::BTreeMap;
    let bytes = std::fs::read(src).unwrap();
    let mut out = mcap::WriteOptions::new().profile("ros2").create(std::io::Cursor::new(Vec::new())).unwrap();
    let mut ids = BTreeMap::new();
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        let m = m.unwrap();
        let schema = m.channel.schema.as_ref().unwrap();
        let is_truth = m.channel.topic == omni_cli::dataset::mcap::TRUTH_TOPIC;
        let truth = is_truth && !clicked;
        let topic = m.channel.topic.clone();
        if is_truth && clicked && !ids.contains_key("/clicked_point") {
            let s = out.add_schema("geometry_msgs/msg/PointStamped", &schema.encoding, b"").unwrap();
            let id = out.add_channel(s, "/clicked_point", &m.channel.message_encoding, &BTreeMap::new()).unwrap();
            ids.insert("/clicked_point".to_string(), id);
            let len = u32::from_le_bytes(m.data[12..16].try_into().unwrap()) as usize;
            let position = 4 + (12 + len).next_multiple_of(8);
            let header = mcap::records::MessageHeader {
                channel_id: id,
                sequence: 0,
                log_time: m.log_time,
                publish_time: m.publish_time,
            };
            out.write_to_known_channel(&header, &m.data[..position + 24]).unwrap();
        }
        let id = *ids.entry(topic).or_insert_with(|| {
            let (name, text): (&str, &[u8]) = if truth {
                ("geometry_msgs/msg/PointStamped", b"std_msgs/Header header\ngeometry_msgs/Point point\n")
            } else {
                (&schema.name, &schema.data)
            };
            let s = out.add_schema(name, &schema.encoding, text).unwrap();
            out.add_channel(s, &m.channel.topic, &m.channel.message_encoding, &BTreeMap::new()).unwrap()
        });
        // Encapsulation (4 bytes), stamp (8), frame_id (4 + its length), padding to 8 from byte 4, then x, y, z.
        let data: &[u8] = if truth {
            let len = u32::from_le_bytes(m.data[12..16].try_into().unwrap()) as usize;
            let position = 4 + (12 + len).next_multiple_of(8);
            &m.data[..position + 24]
        } else {
            &m.data
        };
        let header = mcap::records::MessageHeader {
            channel_id: id,
            sequence: m.sequence,
            log_time: m.log_time,
            publish_time: m.publish_time,
        };
        out.write_to_known_channel(&header, data).unwrap();
    }
    out.finish().unwrap();
    std::fs::write(to, out.into_inner().into_inner()).unwrap();
}

/// A ground truth published as `geometry_msgs/msg/PointStamped` (positions, no heading) is read as a
/// position-only reference, with the same positions as the PoseStamped it came from: the matrix that made
/// the runs lies on them within millimetres, the design several times further off.
#[test]
fn a_point_stamped_ground_truth_is_read_as_positions_only() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let points = simulated_validation_rewritten(dir, "points", |from, to| with_point_stamped(from, to, false));
    let ds = dataset::load(std::slice::from_ref(&points), &LoadOptions::default()).unwrap();
    let poses = dataset::load(&[dir.join("sim/validation")], &LoadOptions::default()).unwrap();
    assert_eq!(ds.runs.len(), 36);
    assert!(ds.runs.iter().all(omni_kin::Run::truth_position_only));
    for (a, b) in ds.runs.iter().zip(&poses.runs) {
        let (pa, pb) = (a.truth(), b.truth());
        assert_eq!(pa.len(), pb.len(), "{}", a.name());
        assert!(pa.iter().zip(pb).all(|(p, q)| p.t_s == q.t_s && p.pose.x_m == q.pose.x_m && p.pose.y_m == q.pose.y_m));
    }
    // Beside a full pose, a PointStamped (RViz's /clicked_point) is no candidate: the pose is the truth.
    let clicked = dir.join("clicked");
    std::fs::create_dir_all(&clicked).unwrap();
    std::fs::copy(dir.join("sim/validation/robot.toml"), clicked.join("robot.toml")).unwrap();
    with_point_stamped(&dir.join("sim/validation/00-r0.mcap"), &clicked.join("00-r0.mcap"), true);
    let ds = dataset::load(std::slice::from_ref(&clicked), &LoadOptions::default()).unwrap();
    assert!(!ds.runs[0].truth_position_only() && ds.runs[0].truth().len() == poses.runs[0].truth().len());
    let (paper, design) = (path_cost(dir, "points", "paper"), path_cost(dir, "points", "design"));
    assert!(paper < 0.006 && design > 3.0 * paper, "paper {paper}, design {design}");
}

/// `src` with its ground-truth topic's PoseStamped messages turned into `sensor_msgs/msg/NavSatFix` ones on
/// `/gnss/fix` (frame `base_link`, as many drivers publish it): the position as WGS 84 latitude and
/// longitude east and north of (47° N, 8° E, 400 m), no heading; before each fix, one message without a fix
/// (status −1, latitude NaN), which carries no position.
fn with_nav_sat_fix(src: &Path, to: &Path) {
    use std::collections::BTreeMap;
    let bytes = std::fs::read(src).unwrap();
    let mut out = mcap::WriteOptions::new().profile("ros2").create(std::io::Cursor::new(Vec::new())).unwrap();
    let mut ids = BTreeMap::new();
    for m in mcap::MessageStream::new(&bytes).unwrap() {
        let m = m.unwrap();
        let schema = m.channel.schema.as_ref().unwrap();
        let truth = m.channel.topic == omni_cli::dataset::mcap::TRUTH_TOPIC;
        let topic = if truth { "/gnss/fix".to_string() } else { m.channel.topic.clone() };
        let id = *ids.entry(topic.clone()).or_insert_with(|| {
            let name = if truth { "sensor_msgs/msg/NavSatFix" } else { schema.name.as_str() };
            let s = out.add_schema(name, &schema.encoding, if truth { b"" } else { &schema.data }).unwrap();
            out.add_channel(s, &topic, &m.channel.message_encoding, &BTreeMap::new()).unwrap()
        });
        let header = mcap::records::MessageHeader {
            channel_id: id,
            sequence: m.sequence,
            log_time: m.log_time,
            publish_time: m.publish_time,
        };
        if !truth {
            out.write_to_known_channel(&header, &m.data).unwrap();
            continue;
        }
        // Encapsulation (4 bytes), stamp (8), frame_id (4 + its length), then the position at 8-byte alignment.
        let len = u32::from_le_bytes(m.data[12..16].try_into().unwrap()) as usize;
        let position = 4 + (12 + len).next_multiple_of(8);
        let f = |k: usize| f64::from_le_bytes(m.data[position + 8 * k..position + 8 * k + 8].try_into().unwrap());
        let (lat0, lon0, alt0) = (47f64.to_radians(), 8f64.to_radians(), 400.0);
        let (lat, lon, alt) = map_3d::enu2geodetic(f(0), f(1), 0.0, lat0, lon0, alt0, map_3d::Ellipsoid::WGS84);
        let base_link = b"base_link\0";
        for (status, fix) in [(-1i8, [f64::NAN, 0.0, 0.0]), (0, [lat.to_degrees(), lon.to_degrees(), alt])] {
            let mut v = m.data[..12].to_vec();
            v.extend_from_slice(&(base_link.len() as u32).to_le_bytes());
            v.extend_from_slice(base_link);
            v.push(status as u8);
            while (v.len() - 4) % 2 != 0 {
                v.push(0);
            }
            v.extend_from_slice(&1u16.to_le_bytes());
            while (v.len() - 4) % 8 != 0 {
                v.push(0);
            }
            for x in fix.iter().chain(&[0.0; 9]) {
                v.extend_from_slice(&x.to_le_bytes());
            }
            v.push(0);
            out.write_to_known_channel(&header, &v).unwrap();
        }
    }
    out.finish().unwrap();
    std::fs::write(to, out.into_inner().into_inner()).unwrap();
}

/// A GNSS ground truth (`sensor_msgs/msg/NavSatFix`, frame base_link) is read as positions only, in metres
/// east and north of each recording's first fix: the PoseStamped positions it was made from, moved by the
/// first, within 0.1 mm; messages without a fix are left out. The matrix that made the runs lies on them
/// within millimetres, the design several times further off.
#[test]
fn a_nav_sat_fix_ground_truth_is_read_as_positions_east_and_north_of_the_first_fix() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    let gnss = simulated_validation_rewritten(dir, "gnss", with_nav_sat_fix);
    let ds = dataset::load(std::slice::from_ref(&gnss), &LoadOptions::default()).unwrap();
    let poses = dataset::load(&[dir.join("sim/validation")], &LoadOptions::default()).unwrap();
    assert_eq!(ds.runs.len(), 36);
    assert!(ds.runs.iter().all(omni_kin::Run::truth_position_only));
    let mut worst_m = 0.0f64;
    for (a, b) in ds.runs.iter().zip(&poses.runs) {
        let (pa, pb) = (a.truth(), b.truth());
        assert_eq!(pa.len(), pb.len(), "{}", a.name());
        let (x0, y0) = (pb[0].pose.x_m - pa[0].pose.x_m, pb[0].pose.y_m - pa[0].pose.y_m);
        for (p, q) in pa.iter().zip(pb) {
            assert_eq!(p.t_s, q.t_s);
            worst_m = worst_m.max((p.pose.x_m + x0 - q.pose.x_m).hypot(p.pose.y_m + y0 - q.pose.y_m));
        }
    }
    assert!(worst_m < 1e-4, "GNSS positions {worst_m} m from the poses they were made from");
    let (paper, design) = (path_cost(dir, "gnss", "paper"), path_cost(dir, "gnss", "design"));
    assert!(paper < 0.006 && design > 3.0 * paper, "paper {paper}, design {design}");
}
