"""omnical.info: the CLI's `omnical info --json` document, built on the same library code."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import pytest

import omnical
from conftest import omnical_command


@pytest.fixture(scope="module")
def bags(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Two 1 s runs of the flower written by Python with an IMU at 50 Hz."""
    out = tmp_path_factory.mktemp("info") / "train"
    runs = omnical.simulate(runs_per_command=1, duration_s=1.0, out=out, imu=True, imu_rate=50.0)
    assert len(runs) == 36
    return out


def cli_info(*args: str) -> dict:
    r = subprocess.run([*omnical_command(), "info", *args, "--json"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    return json.loads(r.stdout)


def test_info_is_the_clis_json_document(bags: Path) -> None:
    bag = str(bags / "00-r0.mcap")
    ours = omnical.info(bag)
    assert ours == cli_info(bag)
    assert ours["command"] == "info" and ours["schema_version"] == 1
    [rec] = ours["recordings"]
    topics = {t["topic"]: t for t in rec["topics"]}
    assert topics["/imu"]["role"] == "imu" and topics["/imu"]["type"] == "sensor_msgs/msg/Imu"
    assert topics["/joint_states"]["role"] == "wheels"
    assert topics["/imu"]["rate_hz"] == pytest.approx(50.0, rel=1e-6)
    assert topics["/joint_states"]["rate_hz"] == pytest.approx(100.0, rel=1e-6)
    assert topics["/joint_states"]["joint_names"] == ["wheel_a", "wheel_b", "wheel_c"]
    read = rec["read"]
    assert read["ok"] is True
    [run] = read["runs"]
    # The run read back is the one simulated: same samples, same ground-truth path.
    sim = omnical.simulate(runs_per_command=1, duration_s=1.0)[0]
    assert run["wheel_samples"] == sim.n_samples
    assert run["truth_poses"] == len(sim.truth)
    assert run["wheel_rate_hz"] == pytest.approx(100.0, rel=1e-6)
    assert run["duration_s"] == pytest.approx(sim.t_s[-1] - sim.t_s[0], abs=1e-6)


def test_a_folder_gives_each_recording_and_the_data_options_change_the_read(bags: Path) -> None:
    doc = omnical.info(bags)
    assert len(doc["recordings"]) == 36
    assert doc == cli_info(str(bags))
    # load's keywords are info's: a ground-truth topic that is not there stops the read, and info says so.
    bad = omnical.info(bags / "03-r0.mcap", gt_topic="/nope")["recordings"][0]["read"]
    assert bad["ok"] is False and "/nope" in bad["error"]
    assert bad == cli_info(str(bags / "03-r0.mcap"), "--gt-topic", "/nope")["recordings"][0]["read"]


def test_bad_paths_are_named(tmp_path: Path, bags: Path) -> None:
    missing = tmp_path / "missing.mcap"
    with pytest.raises(FileNotFoundError, match="missing.mcap"):
        omnical.info(missing)
    csv = tmp_path / "run.csv"
    csv.write_text("t_s\n")
    # A CSV run is an input info describes (issue 48): one it cannot read has its error, naming the file, in
    # "read"; a file that is no input at all is refused.
    read = omnical.info(csv)["recordings"][0]["read"]
    assert read == {"ok": False, "error": f"{csv}: line 1: no wheel columns: expected <joint>_rad_s or <joint>_ticks columns"}
    notes = tmp_path / "notes.txt"
    notes.write_text("hello\n")
    with pytest.raises(omnical.DatasetError, match="notes.txt: unsupported input"):
        omnical.info(notes)
    with pytest.raises(ValueError, match="at least one path"):
        omnical.info()
    with pytest.raises(ValueError, match="gt_kind"):
        omnical.info(bags / "00-r0.mcap", gt_kind="sideways")
