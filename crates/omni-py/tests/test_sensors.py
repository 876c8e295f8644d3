"""omnical.simulate's sensors (issue 28): `out=` with `lidar=` and `imu=` writes the bags `omnical simulate
--lidar ROOM --imu` writes, and the CLI's consumers of them (`--gt-scans`, `omnical imu`) read them."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import omnical
from conftest import omnical_command

BIAS, NOISE = 0.01, 0.003  # rad/s


@pytest.fixture(scope="module")
def sim(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, list[omnical.Run]]:
    """Python's training split with a lidar in the built-in room and an IMU: 1 run per command of 3 s."""
    out = tmp_path_factory.mktemp("sensors") / "train"
    runs = omnical.simulate(runs_per_command=1, duration_s=3.0, seed=3, out=out, lidar="room",
                            lidar_mount=(0.2, 0.0, 5.0), imu=True, imu_bias=BIAS, imu_noise=NOISE)
    return out, runs


def cli(*args: str) -> subprocess.CompletedProcess[str]:
    r = subprocess.run([*omnical_command(), *args], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    return r


def messages(bag: Path, topic: str) -> list[Any]:
    """The decoded messages of `topic` in `bag`, as Foxglove's decoder reads them."""
    reader = pytest.importorskip("mcap.reader")
    decoder = pytest.importorskip("mcap_ros2.decoder")
    with bag.open("rb") as f:
        r = reader.make_reader(f, decoder_factories=[decoder.DecoderFactory()])
        return [m for _s, _c, _raw, m in r.iter_decoded_messages(topics=[topic])]


def stamp_s(msg: Any) -> float:
    return msg.header.stamp.sec + 1e-9 * msg.header.stamp.nanosec


def test_the_bags_are_the_clis(sim: tuple[Path, list[omnical.Run]], tmp_path: Path) -> None:
    out, runs = sim
    cli("simulate", "--out", str(tmp_path / "cli"), "--runs-per-command", "1", "--duration", "3", "--seed", "3",
        "--lidar", "room", "--lidar-mount", "0.2,0,5", "--imu", "--imu-bias", str(BIAS), "--imu-noise", str(NOISE),
        "-q")
    ours = sorted(p.name for p in out.iterdir())
    assert ours == sorted(p.name for p in (tmp_path / "cli" / "train").iterdir())
    assert len(ours) == 37 and "robot.toml" in ours  # 36 bags and the robot beside them
    for name in ours:
        assert (out / name).read_bytes() == (tmp_path / "cli" / "train" / name).read_bytes(), name
    assert [r.name for r in runs] == [f"train/{p[:-5]}" for p in ours if p.endswith(".mcap")]


def test_scans_and_imu_messages_follow_the_simulated_motion(sim: tuple[Path, list[omnical.Run]]) -> None:
    out, runs = sim
    run = runs[0]  # the flower's first command turns at -0.35 rad/s
    assert run.command is not None and run.command[2] == pytest.approx(-0.35)
    bag = out / (run.name.split("/")[1] + ".mcap")
    scans, imu, joints = messages(bag, "/scan"), messages(bag, "/imu"), messages(bag, "/joint_states")
    truth = run.truth  # (M, 4): t_s, x_m, y_m, theta_rad on the run's clock
    end_s = truth[-1, 0]  # the sensors run from t = 0 to the end of the last rest
    assert len(scans) == round(10.0 * end_s) + 1  # 10 Hz
    assert len(imu) == round(100.0 * end_s) + 1  # 100 Hz
    assert len(joints) == run.n_samples
    assert all(len(s.ranges) == 720 for s in scans)
    assert scans[0].header.frame_id == "laser" and imu[0].header.frame_id == "imu_link"
    # The gyro measures the true base's yaw rate plus bias and noise: its integral less the bias is the
    # ground truth's turn (the motion capture's own noise is a few mrad).
    t0 = stamp_s(joints[0]) - run.t_s[0]  # the bag's clock against the run's
    t = np.array([stamp_s(m) for m in imu]) - t0
    rate = np.array([m.angular_velocity.z for m in imu])
    inside = (t >= truth[0, 0]) & (t <= truth[-1, 0])
    turned = np.trapezoid(rate[inside] - BIAS, t[inside])
    heading = np.unwrap(truth[:, 3])
    assert heading[-1] - heading[0] < -0.9  # it turns
    assert turned == pytest.approx(heading[-1] - heading[0], abs=0.01)
    # Sample to sample, the true rate hardly changes: the differences are the noise (robust spread).
    d = np.diff(rate)
    spread = 1.4826 * np.median(np.abs(d - np.median(d))) / np.sqrt(2)
    assert spread == pytest.approx(NOISE, rel=0.25)


def test_the_clis_consumers_read_them(sim: tuple[Path, list[omnical.Run]]) -> None:
    out, _runs = sim
    # The lidar as the runs' reference (load's gt_scans): the true robot (Eq. 9) fits it better than the design.
    ds = omnical.load(out, gt_scans="/scan")
    assert len(ds) >= 36
    paper, design = omnical.evaluate("paper", ds).path_cost, omnical.evaluate("design", ds).path_cost
    assert paper < 0.5 * design, (paper, design)
    # The IMU as a rotation reference (`omnical imu`): the gyro's bias comes back.
    fit = json.loads(cli("imu", str(out), "--json").stdout)["fit"]
    assert fit["bias_rad_s"] == pytest.approx(BIAS, abs=max(4 * fit["bias_std_rad_s"], 5e-4))


def test_bad_sensor_settings_are_refused(tmp_path: Path) -> None:
    small = dict(runs_per_command=1, duration_s=1.0)
    with pytest.raises(FileNotFoundError, match="nowhere.toml: no such room file, and not a built-in room"):
        omnical.simulate(**small, out=tmp_path / "a", lidar=str(tmp_path / "nowhere.toml"))
    with pytest.raises(ValueError, match="give out=DIR"):
        omnical.simulate(**small, imu=True)
    with pytest.raises(ValueError, match="imu-rate 0: expected 1 to 10000 Hz"):
        omnical.simulate(**small, out=tmp_path / "b", imu=True, imu_rate=0.0)
    with pytest.raises(ValueError, match="lidar settings"):
        omnical.simulate(**small, out=tmp_path / "c", lidar="room", lidar_beams=0)
    with pytest.raises(ValueError, match='lidar_tf "up": expected'):
        omnical.simulate(**small, out=tmp_path / "d", lidar="room", lidar_tf="up")
    with pytest.raises(ValueError, match='lidar_mount "0.2,0,x": expected'):
        omnical.simulate(**small, out=tmp_path / "d", lidar="room", lidar_mount="0.2,0,x")
    with pytest.raises(ValueError, match="leaves the room"):
        omnical.simulate(runs_per_command=1, duration_s=30.0, out=tmp_path / "e", lidar="room")
    # Nothing was written by a refused call; a folder that holds files is refused unless force=True.
    assert not any(tmp_path.iterdir())
    (tmp_path / "f").mkdir()
    (tmp_path / "f" / "old.mcap").write_text("")
    with pytest.raises(FileExistsError, match="out="):
        omnical.simulate(**small, out=tmp_path / "f")
    omnical.simulate(**small, out=tmp_path / "f", force=True, lidar="room", lidar_tf="none")
    assert not (tmp_path / "f" / "old.mcap").exists()
    assert messages(tmp_path / "f" / "00-r0.mcap", "/tf_static") == []
    assert len(messages(tmp_path / "f" / "00-r0.mcap", "/scan")) > 5


def test_a_mount_as_the_clis_text_is_the_tuple(tmp_path: Path) -> None:
    small = dict(runs_per_command=1, duration_s=1.0, lidar="room", imu=True)
    omnical.simulate(**small, out=tmp_path / "text", lidar_mount="0.2,-0.1,5")
    omnical.simulate(**small, out=tmp_path / "tuple", lidar_mount=(0.2, -0.1, 5.0))
    omnical.simulate(**small, out=tmp_path / "other", lidar_mount=(0.2, -0.1, 6.0))
    bag = "04-r0.mcap"
    assert (tmp_path / "text" / bag).read_bytes() == (tmp_path / "tuple" / bag).read_bytes()
    assert (tmp_path / "text" / bag).read_bytes() != (tmp_path / "other" / bag).read_bytes()
