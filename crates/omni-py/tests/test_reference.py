"""A sensor's own motion as the reference (``load(gt_kind="relative")``): the windows and the mount, as the CLI."""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest

import omnical

from conftest import REPO, omnical_command


@pytest.fixture(scope="module")
def diff_sim(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A diff drive whose ground truth is a sensor 0.2 m ahead at 5° yaw, its left wheel 2 % large."""
    root = tmp_path_factory.mktemp("reference")
    subprocess.run(
        [*omnical_command(), "simulate", "--robot", str(REPO / "crates/omni-cli/tests/data/diff_robot.toml"),
         "--out", str(root / "sim"), "--runs-per-command", "1", "--format", "csv",
         "--effect", "sensor_offset_yaw=0.2,0,0.0872665", "--effect", "wheel_radius:a=0.02"],
        check=True,
        capture_output=True,
    )
    return root / "sim" / "train"


def test_relative_windows_fit_the_mount_with_the_wheels(diff_sim: Path) -> None:
    ds = omnical.load(diff_sim, gt_kind="relative", gt_window_s=4.0)
    assert len(ds) == 36 and ds[0].name.endswith("#1")
    assert any("relative reference: 12 runs cut into 36 windows" in n for n in ds.notes)
    fit = omnical.train("diff", ds)
    p = fit.model.params
    assert abs(p["sensor_offset_yaw.dx_m"] - 0.2) < 0.01 and abs(p["sensor_offset_yaw.dy_m"]) < 0.01
    assert abs(p["sensor_offset_yaw.dyaw_rad"] - 0.0872665) < 0.5 / 57.3
    assert abs(p["r_left"] - 0.03366) < 5e-3 * 0.03366 and abs(p["r_right"] - 0.033) < 5e-3 * 0.033


def test_a_given_mount_moves_the_truth_and_bad_kinds_are_refused(diff_sim: Path) -> None:
    ds = omnical.load(diff_sim, gt_kind="relative", gt_mount=(0.2, 0.0, 5.0))
    fit = omnical.train("diff", ds)
    assert not any(k.startswith("sensor") for k in fit.model.params)
    assert abs(fit.model.params["r_left"] - 0.03366) < 5e-3 * 0.03366
    with pytest.raises(ValueError, match='gt_kind "lidar": expected "absolute", "relative" or "end_pose"'):
        omnical.load(diff_sim, gt_kind="lidar")


def test_a_lidar_is_the_reference_from_python(tmp_path: Path) -> None:
    """``load(gt_scans="/scan")``: the lidar's path as the ground truth, its mount fitted with the wheels."""
    subprocess.run(
        [*omnical_command(), "simulate", "--robot", str(REPO / "crates/omni-cli/tests/data/diff_robot.toml"),
         "--out", str(tmp_path / "sim"), "--runs-per-command", "1", "--duration", "6", "--lidar", "room",
         "--lidar-mount", "0.2,0,5", "--lidar-tf", "none", "--effect", "wheel_radius:a=0.02"],
        check=True,
        capture_output=True,
    )
    ds = omnical.load(tmp_path / "sim" / "train", gt_scans="/scan")
    assert any('lidar "/scan" matched scan to scan as the reference' in n for n in ds.notes)
    p = omnical.train("diff", ds).model.params
    assert abs(p["sensor_offset_yaw.dx_m"] - 0.2) < 0.01 and abs(p["sensor_offset_yaw.dyaw_rad"] - 0.0872665) < 0.5 / 57.3
    assert abs(p["r_left"] / p["r_right"] - 1.02) < 0.005
    with pytest.raises(omnical.OmnicalError, match='no topic "/laser" in the recording'):
        omnical.load(tmp_path / "sim" / "train", gt_scans="/laser")
