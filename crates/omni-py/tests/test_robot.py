"""robot=: the robot a design comes from (a robot.toml or "apr02"), as the CLI's --robot; no silent default."""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import numpy as np
import pytest

import omnical
from conftest import REPO


def no_design(what: str) -> str:
    """The message of a call that needs the robot's design and has none (the CLI's, with Python's names)."""
    return (
        f"{what} needs the robot's design (its wheel geometry), and none is given: no model= or robot=, no "
        "geometry in the data, no robot.toml beside the data or in the working directory. Describe the robot "
        'once in a robot.toml (docs/formats.md, "Robot description"; `omnical init RECORDING --urdf FILE` '
        "drafts one from a recording and the robot's URDF) and put it beside the data or pass "
        'robot="robot.toml"; for the paper\'s APR-02 robot pass robot="apr02"'
    )


def docs_robot(heading: str, tmp_path: Path) -> Path:
    """The complete robot.toml example of docs/formats.md whose first line is ``# robot.toml: {heading}``."""
    text = (REPO / "docs" / "formats.md").read_text(encoding="utf-8")
    m = re.search(r"```toml\n(# robot\.toml: " + re.escape(heading) + r"\n.*?)```", text, re.S)
    assert m, f"docs/formats.md has no robot.toml example {heading!r}"
    path = tmp_path / f"{heading.replace(' ', '_')}.toml"
    path.write_text(m.group(1), encoding="utf-8")
    return path


def omni_design(angles_deg: list[float], distance_m: float, radius_m: float) -> np.ndarray:
    """The design IK matrix of omni wheels on a circle, each pushing along the counter-clockwise tangent:
    the least-squares inverse of the forward matrix (wheel speed = (-sin a, cos a, R) . twist / r)."""
    a = np.radians(angles_deg)
    forward = np.column_stack([-np.sin(a), np.cos(a), np.full_like(a, distance_m)]) / radius_m
    return np.linalg.pinv(forward)


def test_a_call_without_a_design_says_how_to_give_one(runs: list[omnical.Run]) -> None:
    with pytest.raises(ValueError) as e:
        omnical.train("design", runs)
    assert str(e.value) == no_design("omnical.train")
    with pytest.raises(ValueError) as e:
        omnical.evaluate("design", runs)
    assert str(e.value) == no_design("omnical.evaluate")
    with pytest.raises(ValueError) as e:
        omnical.integrate("design", runs[0])
    assert str(e.value) == no_design("omnical.integrate")
    with pytest.raises(ValueError, match="give model= or robot=, not both"):
        omnical.evaluate(omnical.Model.paper(), runs, robot="apr02")


def test_data_without_a_robot_has_no_design(
    sim_dir: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)  # no robot.toml in the working directory either
    data = tmp_path / "bare"
    data.mkdir()
    for name in ("00-r0.csv", "09-r0.csv"):
        shutil.copy(sim_dir / "csv" / "train" / name, data / name)
    ds = omnical.load(data)
    assert ds.design is None and ds.robot is None
    with pytest.raises(ValueError) as e:
        omnical.evaluate("design", ds)
    assert str(e.value) == no_design("omnical.evaluate")
    apr02 = omnical.load(data, robot="apr02")
    assert apr02.robot == "apr02 (built in: the paper's APR-02)"
    assert apr02.design is not None
    np.testing.assert_array_equal(apr02.design.matrix, omnical.Model.design().matrix)
    assert omnical.evaluate("design", apr02).cost == omnical.evaluate("design", ds, robot="apr02").cost


def test_a_robot_toml_beside_the_data_is_picked_up(sim_dir: Path) -> None:
    ds = omnical.load(sim_dir / "csv" / "train")  # `omnical simulate` writes train/robot.toml
    assert ds.robot is not None and ds.robot.endswith("robot.toml (found beside the data)")
    assert ds.notes[0] == f"robot: {ds.robot}"
    assert ds.design is not None
    np.testing.assert_array_equal(ds.design.design_matrix, omnical.Model.design("apr02").design_matrix)


def test_apr02_is_the_papers_eq7() -> None:
    eq7 = omnical.Model.design("apr02").design_matrix
    np.testing.assert_array_equal(eq7, omnical.Model.design().design_matrix)
    # Eq. 7 is printed to 4 digits; the geometry gives it to rounding.
    np.testing.assert_allclose(eq7, omni_design([60, 180, 300], 0.195, 0.148), atol=6e-5)
    geometry = omnical.Model.design("apr02", kinematics="geometry")
    assert geometry.param_names[:3] == ["r_a", "r_b", "r_c"] and geometry.get("r_a") == 0.148


def test_omni4_from_the_docs_gives_its_design_matrix(tmp_path: Path) -> None:
    path = docs_robot("four-wheel omni", tmp_path)
    m = omnical.Model.design(path)
    assert m.n_wheels == 4 and m.kinematics == "ik"
    np.testing.assert_allclose(m.design_matrix, omni_design([45, 135, 225, 315], 0.21, 0.0508), rtol=1e-12)
    joints = ["front_left_wheel_joint", "rear_left_wheel_joint", "rear_right_wheel_joint", "front_right_wheel_joint"]
    assert m.wheel_names == joints
    assert f"wheel_names = {joints!r}".replace("'", '"') in m.to_toml()
    back = tmp_path / "m.toml"
    m.save(back)
    assert omnical.load_model(back).wheel_names == joints
    # Simulated on its own design, the design explains the runs to the simulator's noise.
    runs = omnical.simulate(robot=path, runs_per_command=1, duration_s=1.0, seed=2)
    assert len(runs) == 36 and runs[0].n_wheels == 4
    assert omnical.evaluate("design", runs, robot=path).path_cost < 0.01


def test_diff_from_the_docs_gives_its_design_matrix_and_fits_its_radii(tmp_path: Path) -> None:
    path = docs_robot("differential drive", tmp_path)
    r, s = 0.033, 0.287
    m = omnical.Model.design(path)
    np.testing.assert_allclose(m.design_matrix, [[r / 2, r / 2], [0, 0], [-r / s, r / s]], rtol=1e-12)
    assert m.wheel_names == ["wheel_left_joint", "wheel_right_joint"]
    diff = omnical.Model.design(path, kinematics="diff")
    assert diff.params == {"r_right": r, "r_left": r, "b": s}
    # A left wheel 3 % larger than designed: simulated (no sideways runs on a diff base) and recovered.
    truth = diff.with_params({"r_left": 1.03 * r})
    runs = omnical.simulate(truth, robot=path, runs_per_command=1, duration_s=2.0, seed=4)
    commands = [run.command for run in runs if run.command is not None]
    assert len(commands) == len(runs) == 12 and all(abs(np.sin(alpha)) < 1e-12 for _, alpha, _ in commands)
    fit = omnical.train(diff, runs, seed=0)
    assert fit.params["r_left"] == pytest.approx(1.03 * r, rel=2e-3)
    assert fit.params["r_right"] == pytest.approx(r, rel=2e-3)
    # The ik fit around the robot's design keeps the vy row at zero (a motion the base cannot make).
    ik = omnical.train("design", runs, robot=path, seed=0)
    assert set(ik.params) == {"m11", "m12", "m31", "m32"}
    np.testing.assert_array_equal(ik.matrix[1], [0.0, 0.0])


def test_a_bad_robot_file_names_the_file_line_and_field(tmp_path: Path, runs: list[omnical.Run]) -> None:
    good = docs_robot("differential drive", tmp_path).read_text(encoding="utf-8")
    bad = tmp_path / "bad.toml"
    bad.write_text(good.replace("left_radius_m = 0.033", "left_radius_m = -0.033"), encoding="utf-8")
    line = 1 + good.split("left_radius_m")[0].count("\n")
    with pytest.raises(ValueError) as e:
        omnical.Model.design(bad)
    assert str(e.value) == f"{bad}: line {line}: diff.left_radius_m: -0.033 must be > 0"
    with pytest.raises(ValueError, match=re.escape(f"{bad}: line {line}: diff.left_radius_m")):
        omnical.train("design", runs, robot=bad)
    with pytest.raises(FileNotFoundError, match=re.escape(str(tmp_path / "none.toml"))):
        omnical.load(tmp_path, robot=tmp_path / "none.toml")
    with pytest.raises(ValueError, match="truth has 3 wheels and robot .* has 2"):
        omnical.simulate(omnical.Model.paper(), robot=bad.with_name("differential_drive.toml"))
