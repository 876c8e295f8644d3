"""omnical.imu: `omnical imu --json`'s document, built on the same library code (omni_cli::api::imu). On
runs Python simulated with an IMU, the gyro's bias and the wheel matrix's rotation row come back (as the
CLI's tests/imu.rs asserts), and a recording without the IMU's topic is refused naming the file and topic."""

from __future__ import annotations

import json
import re
import subprocess
from pathlib import Path

import numpy as np
import pytest

import omnical
from conftest import omnical_command

BIAS = 0.005  # rad/s, the simulated gyro's bias (tests/imu.rs's)


@pytest.fixture(scope="module")
def sim(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, list[omnical.Run]]:
    """The flower on the paper's robot, 1 run per command of 6 s, with an IMU at 100 Hz (bias BIAS)."""
    out = tmp_path_factory.mktemp("imu") / "train"
    runs = omnical.simulate(runs_per_command=1, duration_s=6.0, out=out, imu=True, imu_bias=BIAS)
    assert len(runs) == 36
    return out, runs


def cli_imu(*args: str) -> dict:
    r = subprocess.run([*omnical_command(), "imu", *args, "--json"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    return json.loads(r.stdout)


def test_imu_is_the_clis_json_document(sim: tuple[Path, list[omnical.Run]]) -> None:
    out, _ = sim
    ours = omnical.imu(out)
    assert ours == cli_imu(str(out))
    assert ours["command"] == "imu" and ours["schema_version"] == 1
    assert ours["topic"] == "/imu" and ours["window_s"] == 1.0 and ours["out"] is None
    assert ours["wheel_names"] == ["wheel_a", "wheel_b", "wheel_c"]
    # Another window is the CLI's --window.
    assert omnical.imu(out / "00-r0.mcap", window_s=0.5) == cli_imu(str(out / "00-r0.mcap"), "--window", "0.5")


def test_the_bias_and_the_rotation_row_come_back(sim: tuple[Path, list[omnical.Run]]) -> None:
    out, runs = sim
    fit = omnical.imu(out)["fit"]
    bias, se = fit["bias_rad_s"], fit["bias_std_rad_s"]
    assert 0.0 < se < 2e-4
    assert abs(bias - BIAS) < max(4.0 * se, 2e-4), f"bias {bias} ± {se}"
    row = np.array(fit["row"])
    assert fit["windows"] > 200 and fit["turned_rad"] > 30.0
    # Within 0.3 % of motion capture's row on the same runs (train on the simulated ground truth), as the
    # CLI's tests/imu.rs, and of the true robot's (simulate's default truth: Eq. 9 on APR-02).
    mocap = omnical.train("ik", runs, robot="apr02").matrix[2]
    np.testing.assert_allclose(row, mocap, rtol=3e-3)
    np.testing.assert_allclose(row, omnical.Model.paper().matrix[2], rtol=3e-3)
    # ... and not the design's, which is 7 % off (a test that could fail).
    design = omnical.imu(out)["design_row"]
    assert np.all(np.abs(row / np.array(design) - 1.0) > 0.03)


def test_out_writes_the_design_with_the_fitted_rotation_row(sim: tuple[Path, list[omnical.Run]],
                                                            tmp_path: Path) -> None:
    out, _ = sim
    path = tmp_path / "imu.toml"
    doc = omnical.imu(out / "05-r0.mcap", out=path)
    assert doc["out"] == str(path) and path.exists()
    model = omnical.load_model(path)
    np.testing.assert_allclose(model.matrix[2], doc["fit"]["row"], rtol=1e-12)
    np.testing.assert_allclose(model.matrix[:2], model.design_matrix[:2], rtol=1e-12)
    assert f"gyro_bias_rad_s = {doc['fit']['bias_rad_s']}" in path.read_text()


def test_bad_inputs_are_refused_naming_the_file_and_topic(sim: tuple[Path, list[omnical.Run]],
                                                          tmp_path: Path) -> None:
    out, _ = sim
    plain = tmp_path / "plain"
    omnical.simulate(runs_per_command=1, duration_s=2.0, out=plain)
    bag = plain / "00-r0.mcap"
    want = f'{bag}: no topic "/imu" in the recording; no topic holds sensor_msgs/msg/Imu: record the IMU'
    with pytest.raises(omnical.DatasetError, match=re.escape(want)):
        omnical.imu(bag)
    with pytest.raises(omnical.DatasetError, match=re.escape('no topic "/imu2" in the recording; the Imu topics '
                                                             'are /imu: name one (--topic)')):
        omnical.imu(out / "00-r0.mcap", topic="/imu2")
    with pytest.raises(ValueError, match=re.escape('topic "/imu": the gyro reference: window 0 s')):
        omnical.imu(out / "00-r0.mcap", window_s=0.0)
    with pytest.raises(FileNotFoundError, match="missing.mcap"):
        omnical.imu(tmp_path / "missing.mcap")
    with pytest.raises(ValueError, match="at least one recording"):
        omnical.imu()
    # The ground-truth keywords, split_s and ticks_per_rev are no keywords of imu: the IMU is the reference.
    for keyword in ("gt_scans", "gt_parent_frame", "gt_child_frame", "gt_columns", "gt_units", "split_s",
                    "ticks_per_rev"):
        with pytest.raises(TypeError, match=keyword):
            omnical.imu(out, **{keyword: "x"})


def test_an_upside_down_imu_reads_with_its_mount_and_is_refused_without(sim: tuple[Path, list[omnical.Run]],
                                                                         tmp_path: Path) -> None:
    out, _ = sim
    upright = omnical.imu(out)
    assert upright["mounts"] == [{"source": "transforms", "base_frame": "base_link", "frame_id": "imu_link",
                                  "roll_deg": 0.0, "pitch_deg": 0.0, "yaw_deg": 0.0, "recordings": 36}]
    down, bare = tmp_path / "down", tmp_path / "bare"
    # The same seed as `sim`: the same gyro samples, written in the IMU's frame upside down.
    omnical.simulate(runs_per_command=1, duration_s=6.0, out=down, imu=True, imu_bias=BIAS, imu_mount=(180, 0, 0))
    omnical.simulate(runs_per_command=1, duration_s=6.0, out=bare, imu=True, imu_bias=BIAS, imu_mount="180,0,0",
                     imu_tf="none")
    doc = omnical.imu(down)
    assert doc["mounts"][0]["source"] == "transforms" and doc["mounts"][0]["roll_deg"] == pytest.approx(180.0)
    np.testing.assert_allclose(doc["fit"]["row"], upright["fit"]["row"], rtol=1e-9)
    with pytest.raises(omnical.DatasetError, match=re.escape("the IMU's z axis seems to point down. Publish its "
                                                             "mount on /tf_static")):
        omnical.imu(bare)
    given = omnical.imu(bare, mount=(180, 0, 0))
    assert given["mounts"][0]["source"] == "given"
    np.testing.assert_allclose(given["fit"]["row"], upright["fit"]["row"], rtol=1e-9)
    assert given == cli_imu(str(bare), "--mount", "180,0,0")
    with pytest.raises(ValueError, match=re.escape('mount "up": expected (roll_deg, pitch_deg, yaw_deg)')):
        omnical.imu(bare, mount="up")
