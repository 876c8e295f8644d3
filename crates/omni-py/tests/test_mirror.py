"""Python mirrors the CLI (issue 19): one argument order, the CLI's flag names and defaults, the same
numbers and files as the `omnical` command for the same inputs."""

from __future__ import annotations

import inspect
import json
import math
import re
import subprocess
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import omnical
from conftest import omnical_command

# Python's spelling of a CLI flag, where it differs: a Python-only option maps to None.
PYTHON_ONLY = {"progress", "title", "diagnose", "every", "effects", "split_s", "recorded_odometry", "noise_free",
               "prefix", "sample_drop_probability", "sample_jitter_s", "duration_s"}


def cli(*args: str, check: bool = True) -> subprocess.CompletedProcess[str]:
    r = subprocess.run([*omnical_command(), *args], capture_output=True, text=True)
    if check:
        assert r.returncode == 0, r.stderr
    return r


def cli_flags(command: str) -> set[str]:
    """The long flags of `omnical COMMAND --help`, as Python names (`--min-gain` -> `min_gain`)."""
    return {f.replace("-", "_") for f in re.findall(r"^\s+(?:-\w, )?--([\w-]+)", cli(command, "--help").stdout, re.M)}


def cli_defaults(command: str) -> dict[str, str]:
    """`[default: X]` of each flag of `omnical COMMAND --help`."""
    text = cli(command, "--help").stdout
    found: dict[str, str] = {}
    for block in re.split(r"\n(?=\s+(?:-\w, )?--)", text):
        m = re.match(r"\s+(?:-\w, )?--([\w-]+)", block)
        d = re.search(r"\[default: ([^\]]+)\]", block)
        if m and d:
            found[m.group(1).replace("-", "_")] = d.group(1)
    return found


CALLS = {"evaluate": "eval", "diagnose": "diagnose", "report": "report", "explore": "explore",
         "train": "train", "export": "export"}


@pytest.mark.parametrize("name", sorted(CALLS))
def test_model_then_runs_then_the_cli_flags_as_keywords(name: str) -> None:
    params = list(inspect.signature(getattr(omnical, name)).parameters.values())
    assert [p.name for p in params[:2]] == ["model", "runs"]
    assert all(p.kind == p.POSITIONAL_OR_KEYWORD for p in params[:2])
    assert all(p.kind == p.KEYWORD_ONLY for p in params[2:]), name
    flags = cli_flags(CALLS[name])
    keywords = {p.name for p in params[2:]} - PYTHON_ONLY
    assert keywords <= flags, f"omnical.{name}: {sorted(keywords - flags)} are not flags of omnical {CALLS[name]}"
    assert "robot" in keywords or name == "train" and "robot" in {p.name for p in params}
    # A CLI flag that Python offers under another name is listed in PYTHON_ONLY: the shared ones must match.
    if name in ("diagnose", "report", "explore"):
        assert "validate" in keywords
    assert inspect.signature(omnical.integrate).parameters.keys() >= {"model", "run", "robot"}


def test_runs_first_is_a_type_error_showing_the_order(runs: list[omnical.Run]) -> None:
    m = omnical.Model.paper()
    for f in (omnical.evaluate, omnical.diagnose, omnical.train, omnical.report, omnical.explore, omnical.export):
        with pytest.raises(TypeError, match=rf"omnical.{f.__name__}\(model, runs, \.\.\.\): the model comes first, "
                                            rf"then the runs .* e\.g\. omnical\.{f.__name__}\(\"design\", runs"):
            if f is omnical.report:
                f(runs, m, out="x.html")  # type: ignore[arg-type]
            elif f is omnical.explore:
                f(runs, m, validate=runs)  # type: ignore[arg-type]
            else:
                f(runs, m)  # type: ignore[operator]
    with pytest.raises(TypeError, match=r"omnical.integrate\(model, runs, \.\.\.\): the model comes first"):
        omnical.integrate(runs[0], m)  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="unexpected keyword argument 'validation'"):
        omnical.diagnose(m, runs, validation=runs)  # type: ignore[call-arg]  # the CLI's --validate
    with pytest.raises(TypeError, match="takes 2 positional arguments but 3 were given"):
        omnical.explore(m, runs, runs)  # type: ignore[misc]


def test_model_spellings_give_the_same_numbers(runs: list[omnical.Run], tmp_path: Path) -> None:
    paper = omnical.Model.paper()
    path = tmp_path / "paper.toml"
    paper.save(path)
    want = omnical.evaluate(paper, runs).path_cost
    assert omnical.evaluate("paper", runs).path_cost == want
    assert omnical.evaluate(str(path), runs).path_cost == want
    assert omnical.evaluate(path, runs).path_cost == want
    design = omnical.evaluate(omnical.Model.design(), runs).path_cost
    assert omnical.evaluate("design", runs, robot="apr02").path_cost == design != want
    with pytest.raises(ValueError, match="names a design, and the model file"):
        omnical.evaluate(path, runs, robot="apr02")


def test_simulate_defaults_are_the_cli_defaults() -> None:
    defaults = cli_defaults("simulate")
    sig = inspect.signature(omnical.simulate).parameters
    assert sig["seed"].default == int(defaults["seed"]) == 7
    # The CLI's default depends on --commands (5 on the benchmark, 1 with a plan): its help says both.
    assert "runs_per_command" not in defaults
    assert sig["runs_per_command"].default == 5
    assert "Default: 5 on the robot's benchmark" in cli("simulate", "--help").stdout
    assert sig["duration_s"].default == float(defaults["duration"]) == 10.0
    assert sig["prefix"].default == "train/"  # the CLI's training split


def test_simulate_makes_the_cli_runs(tmp_path: Path) -> None:
    # Only the size is given, on both sides: seed, truth, robot, noise and names are the defaults.
    cli("simulate", "--out", str(tmp_path), "--runs-per-command", "1", "--duration", "1", "--format", "csv")
    ours = omnical.simulate(runs_per_command=1, duration_s=1.0)
    for split, py in (("train", ours), ("validation", omnical.simulate(runs_per_command=1, duration_s=1.0, seed=8,
                                                                       prefix="validation/"))):
        theirs = omnical.load(tmp_path / split)
        assert [r.name.rsplit("/", 1)[-1] for r in theirs] == [r.name.rsplit("/", 1)[-1] for r in py]
        assert py[0].name.startswith(f"{split}/")
        for a, b in zip(py, theirs):
            np.testing.assert_allclose(b.t_s, a.t_s, rtol=0, atol=1e-9)
            np.testing.assert_allclose(b.wheel_rad_s, a.wheel_rad_s, rtol=1e-12, atol=1e-12)
            np.testing.assert_allclose(b.truth, a.truth, rtol=0, atol=1e-9)


@pytest.fixture(scope="module")
def csv_runs(tmp_path_factory: pytest.TempPathFactory) -> Path:
    root = tmp_path_factory.mktemp("csvsim")
    cli("simulate", "--out", str(root), "--runs-per-command", "1", "--duration", "2", "--format", "csv",
        "--effect", "time_offset=0.06")
    return root


def test_train_options_give_the_cli_fit(csv_runs: Path, tmp_path: Path) -> None:
    out = tmp_path / "fit.toml"
    cli("train", str(csv_runs / "train"), "--objective", "end-pose", "--every", "3", "--unexcited", "move",
        "--seed", "2", "--out", str(out))
    ds = omnical.load(csv_runs / "train")
    fit = omnical.train("ik", ds, objective="end_pose", every=3, unexcited="move", seed=2)
    assert fit.objective == "end_pose"
    np.testing.assert_array_equal(fit.matrix, omnical.load_model(out).matrix)  # the CLI's numbers, exactly
    path = omnical.train("ik", ds, seed=2)
    assert path.objective == "path"
    assert np.abs(path.matrix - fit.matrix).max() > 1e-6  # another objective, another fit
    # The same defaults as the CLI's flags.
    defaults = cli_defaults("train")
    sig = inspect.signature(omnical.train).parameters
    for name in ("every", "heading_weight", "max_std_error", "min_excitation", "seed", "preset"):
        default = sig[name].default
        assert default == (type(default)(defaults[name])), name
    with pytest.raises(ValueError, match=r"every= must be ≥ 1"):
        omnical.train("ik", ds, every=0)
    with pytest.raises(ValueError, match='objective "l2": expected "end_pose" or "path"'):
        omnical.train("ik", ds, objective="l2")
    with pytest.raises(ValueError, match='unexcited "free": expected "hold" or "move"'):
        omnical.train("ik", ds, unexcited="free")


def test_evaluate_gives_the_cli_relative_pose_error(csv_runs: Path) -> None:
    ds = omnical.load(csv_runs / "validation")
    for window in ("0.25m", "0.5s"):  # 2 s runs: 0.4 m long
        theirs = json.loads(cli("eval", str(csv_runs / "validation"), "--rpe-delta", window, "--json").stdout)
        ev = omnical.evaluate("design", ds, rpe_delta=window)
        ours = ev.rpe
        assert (ours["delta"], ours["delta_unit"]) == (theirs["rpe"]["delta"], theirs["rpe"]["delta_unit"])
        assert ours["pairs"] == theirs["rpe"]["pairs"] > 0
        for key in ("translation_m", "rotation_rad", "drift_pct"):
            for stat in ("mean", "median", "rmse", "max"):
                assert ours[key][stat] == pytest.approx(theirs["rpe"][key][stat], rel=1e-12, abs=1e-15), (key, stat)
        assert ev.runs[0].rpe["pairs"] == theirs["runs"][0]["rpe"]["pairs"]
        assert ev.runs[0].rpe["translation_m"]["rmse"] == pytest.approx(
            theirs["runs"][0]["rpe"]["translation_m"]["rmse"], rel=1e-12)
    assert inspect.signature(omnical.evaluate).parameters["rpe_delta"].default == cli_defaults("eval")["rpe_delta"]
    with pytest.raises(ValueError, match=r'rpe_delta="1km": expected a distance in metres or a time in seconds'):
        omnical.evaluate("design", ds, rpe_delta="1km")
    with pytest.raises(ValueError, match=r'rpe_delta="0s": the window must be longer than 0 \(got 0s\)'):
        omnical.evaluate("design", ds, rpe_delta="0s")


def test_unexcited_move_lets_unconstrained_directions_go(truth: omnical.Model) -> None:
    straight = [r for r in omnical.simulate(truth, runs_per_command=1, duration_s=2.0, seed=5)
                if r.command is not None and r.command[2] == 0.0][:4]
    hold = omnical.train("ik", straight, robot="apr02", seed=0)
    # Unheld, the directions the straight runs leave free wander far from the design (a reversed wheel):
    # refused as implausible (issue 43), and written with force=True.
    with pytest.raises(omnical.CalibrationError, match="the fitted model is implausibly far from its start"):
        omnical.train("ik", straight, robot="apr02", seed=0, unexcited="move")
    move = omnical.train("ik", straight, robot="apr02", seed=0, unexcited="move", force=True)
    assert hold.held and not move.held
    assert np.abs(hold.matrix - move.matrix).max() > 1e-4


ROBOT = """\
name = "three wheels"
kind = "omni"
[[wheels]]
joint = "wheel_a"
distance_m = 0.2
angle_deg = 90.0
radius_m = 0.05
[[wheels]]
joint = "wheel_b"
distance_m = 0.2
angle_deg = 210.0
radius_m = 0.05
[[wheels]]
joint = "wheel_c"
distance_m = 0.2
angle_deg = 330.0
radius_m = 0.05
{priors}"""


def test_train_uses_the_robot_priors(tmp_path: Path) -> None:
    plain = tmp_path / "plain" / "robot.toml"
    tight = tmp_path / "tight" / "robot.toml"
    for p, priors in ((plain, ""), (tight, "[priors]\nradius_std_m = 0.00005\n")):
        p.parent.mkdir()
        p.write_text(ROBOT.format(priors=priors))
    # The true robot's wheel a is 2 % larger than designed. The tight prior's GA box (±3 σ = ±0.15 mm)
    # keeps the paper's GA near the design radius, where the plain one (±10 %) moves towards the truth; the
    # default preset's polish is not bounded and reaches the truth either way, and names r_a as having left
    # the prior's box (as `omnical train` does).
    design = omnical.Model.design(plain, kinematics="geometry")
    truth = design.with_params({"r_a": 0.051})
    runs = omnical.simulate(truth, robot=plain, runs_per_command=1, duration_s=1.5, noise_free=True)[::3]
    free = omnical.train("geometry", runs, robot=plain, seed=0, preset="paper")
    bound = omnical.train("geometry", runs, robot=tight, seed=0, preset="paper")
    assert free.params["r_a"] - 0.05 > 4e-4
    assert abs(bound.params["r_a"] - 0.05) <= 3 * 0.00005 + 1e-12
    free = omnical.train("geometry", runs, robot=plain, seed=0)
    bound = omnical.train("geometry", runs, robot=tight, seed=0)
    assert abs(free.params["r_a"] - 0.051) < 1e-5 and abs(bound.params["r_a"] - 0.051) < 1e-5
    assert free.outside_box == [] and bound.outside_box == ["r_a"]
    # A Model as the start is the CLI's --start: no priors.
    start = omnical.train(omnical.Model.design(tight, kinematics="geometry"), runs, seed=0)
    assert start.outside_box == []


def _read(d: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(d.iterdir())}


def test_export_writes_the_cli_files(csv_runs: Path, tmp_path: Path) -> None:
    fit = tmp_path / "fit.toml"
    cli("train", str(csv_runs / "train"), "--seed", "0", "--out", str(fit))
    cli("export", "--model", str(fit), str(csv_runs / "validation"), "--tum", str(tmp_path / "cli_tum"),
        "--mcap", str(tmp_path / "cli_mcap"))
    ds = omnical.load(csv_runs / "validation", recorded_odometry=True)
    written = omnical.export(str(fit), ds, tum=tmp_path / "py_tum", mcap=tmp_path / "py_mcap")
    assert len(written) == 4 * len(ds)
    cli_tum, py_tum = _read(tmp_path / "cli_tum"), _read(tmp_path / "py_tum")
    assert len(py_tum) == 3 * len(ds) and py_tum == cli_tum  # byte for byte
    assert _read(tmp_path / "py_mcap") == _read(tmp_path / "cli_mcap")
    first = sorted(py_tum)[0]
    assert py_tum[first].startswith(b"# run ")
    # A folder that holds files already (another export's runs) is refused unless force=True, as --force.
    with pytest.raises(FileExistsError, match=r"tum= .*py_tum: the folder already holds files \(.*\); give force=True"):
        omnical.export(str(fit), [ds[0]], tum=tmp_path / "py_tum")
    assert _read(tmp_path / "py_tum") == cli_tum
    one = omnical.export(str(fit), [ds[0]], tum=tmp_path / "py_tum", force=True)
    assert sorted(_read(tmp_path / "py_tum")) == sorted(Path(f).name for f in one) and len(one) == 3
    with pytest.raises(ValueError, match="nothing to export: give tum=DIR and/or mcap=DIR"):
        omnical.export(str(fit), ds)


def test_export_of_ros_recordings_keeps_their_time_base_as_the_cli(sim_dir: Path, tmp_path: Path) -> None:
    # MCAP recordings: both front ends stamp the exports in the recording's time (here the simulator's
    # epoch, 2023-11-14), byte for byte; the Python export once wrote 1970 stamps.
    bags = sim_dir / "mcap" / "validation"
    cli("export", "--model", "design", str(bags), "--robot", "apr02",
        "--tum", str(tmp_path / "cli_tum"), "--mcap", str(tmp_path / "cli_mcap"))
    ds = omnical.load(bags, robot="apr02", recorded_odometry=True)
    omnical.export("design", ds, tum=tmp_path / "py_tum", mcap=tmp_path / "py_mcap")
    assert _read(tmp_path / "py_tum") == _read(tmp_path / "cli_tum")
    assert _read(tmp_path / "py_mcap") == _read(tmp_path / "cli_mcap")
    first = next(line for line in sorted((tmp_path / "py_tum").glob("*.gt.tum"))[0].read_text().splitlines()
                 if not line.startswith("#"))
    assert 1.7e9 <= float(first.split()[0]) < 1.71e9


def test_export_mcap_has_the_model_odometry(runs: list[omnical.Run], tmp_path: Path) -> None:
    mcap_reader = pytest.importorskip("mcap.reader")
    tum, bag = (Path(p) for p in omnical.export("paper", runs[:1], tum=tmp_path / "tum", mcap=tmp_path / "bags")[2:])
    with bag.open("rb") as f:
        counts: dict[str, int] = {}
        for _schema, channel, _message in mcap_reader.make_reader(f).iter_messages():
            counts[channel.topic] = counts.get(channel.topic, 0) + 1
    # The poses of the calibrated TUM file: every wheel-sample step plus the ground-truth stamps.
    poses = [line for line in tum.read_text().splitlines() if not line.startswith("#")]
    assert counts["/omnical/odometry"] == len(poses) > runs[0].n_samples // 2


def _tum(truth: np.ndarray[Any, Any], shift_s: float) -> str:
    lines = ["# t x y z qx qy qz qw"]
    for t, x, y, th in truth:
        lines.append(f"{t + shift_s:.9f} {x:.9f} {y:.9f} 0 0 0 {math.sin(th / 2):.12f} {math.cos(th / 2):.12f}")
    return "\n".join(lines) + "\n"


def test_load_reads_ground_truth_files_with_the_cli_clock_alignment(tmp_path: Path) -> None:
    cli("simulate", "--out", str(tmp_path / "sim"), "--runs-per-command", "1", "--duration", "4")
    bag = sorted((tmp_path / "sim" / "train").glob("*.mcap"))[2]
    original = omnical.load(bag)[0]
    tum = tmp_path / "mocap.tum"
    tum.write_text(_tum(original.truth, 3.217))  # the mocap PC's clock: 3.217 s ahead of the loaded times
    # The bag's stamps count from the simulator's epoch, 1.7e9 s; loaded times from the whole second of its
    # first stamp (-0.5 s): the true offset (wheel clock = mocap clock + offset) is 1.7e9 - 1 - 3.217 s.
    true_offset = 1_700_000_000 - 1 - 3.217
    ds = omnical.load(bag, gt=tum)
    (clock,) = ds.ground_truth_clocks
    assert clock["estimated"] and clock["recording"] == "02-r0"
    assert abs(clock["offset_s"] - true_offset) < 0.05 and 0 < clock["std_error_s"] < 0.05
    (cli_clock,) = json.loads(cli("train", str(bag), "--gt", str(tum), "--json").stdout)["ground_truth_clock"]
    assert cli_clock == clock  # the CLI's estimate, to the bit
    forced = omnical.load(bag, gt=tum, gt_time_offset=true_offset)
    assert forced.ground_truth_clocks[0]["estimated"] is False
    np.testing.assert_allclose(forced[0].truth, original.truth, atol=1e-6)
    # CSV with named columns and units.
    csv = tmp_path / "mocap.csv"
    rows = ["stamp_ns,pos_x_mm,pos_y_mm,heading_deg"]
    rows += [f"{round((t + 1.0) * 1e9)},{x * 1e3:.9f},{y * 1e3:.9f},{math.degrees(th):.12f}"
             for t, x, y, th in original.truth]
    csv.write_text("\n".join(rows) + "\n")
    from_csv = omnical.load(bag, gt=csv, gt_time_offset=true_offset + 3.217 - 1.0,
                            gt_columns={"t": "stamp_ns", "x": "pos_x_mm", "y": "pos_y_mm", "yaw": "heading_deg"},
                            gt_units={"time": "ns", "length": "mm", "angle": "deg"})
    np.testing.assert_allclose(from_csv[0].truth, original.truth, atol=1e-6)
    assert not from_csv[0].truth_position_only
    # The same file as a reference of positions only (UWB, GNSS): headings 0 and never compared.
    positions = omnical.load(bag, gt=csv, gt_time_offset=true_offset + 3.217 - 1.0,
                             gt_columns={"t": "stamp_ns", "x": "pos_x_mm", "y": "pos_y_mm", "yaw": "none"},
                             gt_units={"time": "ns", "length": "mm"})
    assert positions[0].truth_position_only and not positions[0].truth[:, 3].any()
    np.testing.assert_allclose(positions[0].truth[:, :3], original.truth[:, :3], atol=1e-6)
    with pytest.raises(ValueError, match="q"):
        omnical.load(bag, gt=csv, gt_columns={"q": "stamp_ns"})


def test_force_never_replaces_an_input(csv_runs: Path, tmp_path: Path) -> None:
    # Issue 44: export(force=True) into the folder of the data it exports, or a folder inside it, deleted the
    # data. Both are refused before any work, whatever force, naming both paths; so is simulate(out=) over
    # its robot file.
    import shutil
    data = tmp_path / "data"
    shutil.copytree(csv_runs / "validation", data)
    before = _read(data)
    ds = omnical.load(data)
    for force in (False, True):
        with pytest.raises(ValueError, match=r"tum= .*data: this folder holds the data .*/data, which "
                                             r"this command reads; give tum= a folder apart from its inputs"):
            omnical.export("design", ds, tum=data, force=force)
        with pytest.raises(ValueError, match=r"mcap= .*inside: this folder is inside the data"):
            omnical.export("design", ds, mcap=data / "inside", force=force)
    assert _read(data) == before
    robot = tmp_path / "setup" / "robot.toml"
    robot.parent.mkdir()
    robot.write_text((csv_runs / "train" / "robot.toml").read_text())
    with pytest.raises(ValueError, match=r"out= .*setup: this folder holds robot= .*robot.toml"):
        omnical.simulate(robot=robot, runs_per_command=1, duration_s=1.0, out=robot.parent, force=True)
    assert robot.exists()
