"""The `omnical` console command installed with the wheel, and the exception hierarchy."""

from __future__ import annotations

import pickle
import subprocess
from pathlib import Path

import omnical
from conftest import omnical_command


def test_console_command_runs_the_cli(sim_dir: Path, tmp_path: Path) -> None:
    help_ = subprocess.run([*omnical_command(), "--help"], capture_output=True, text=True)
    assert help_.returncode == 0 and "simulate" in help_.stdout
    out = tmp_path / "fit.toml"
    train = subprocess.run(
        [*omnical_command(), "train", str(sim_dir / "csv" / "train"), "--out", str(out)],
        capture_output=True,
        text=True,
    )
    assert train.returncode == 0, train.stderr
    assert "fitted IK matrix" in train.stdout
    assert omnical.load_model(out).kinematics == "ik"  # the CLI's model file reads in Python


def test_console_command_errors_exit_2(tmp_path: Path) -> None:
    r = subprocess.run([*omnical_command(), "eval", str(tmp_path / "missing.csv")], capture_output=True, text=True)
    assert r.returncode == 2 and r.stderr.startswith("error: ") and "missing.csv" in r.stderr
    usage = subprocess.run([*omnical_command(), "frobnicate"], capture_output=True, text=True)
    assert usage.returncode == 2 and "unrecognized subcommand" in usage.stderr


def test_exception_hierarchy() -> None:
    for e in (omnical.DatasetError, omnical.ModelFileError, omnical.CalibrationError):
        assert issubclass(e, omnical.OmnicalError)
    assert issubclass(omnical.OmnicalError, Exception)
    assert omnical.OmnicalError.__module__ == "omnical"


def test_public_api_is_exported() -> None:
    for name in omnical.__all__:
        assert hasattr(omnical, name), name
    assert omnical.__version__ == "0.1.0"


def test_a_python_fit_saves_the_clis_model_file_byte_for_byte(tmp_path: Path) -> None:
    """One training (issue 47): Python's ``train`` builds the model file's summary where ``omnical train``
    does, so a differential drive with ``[priors]`` gets the same file from both, byte for byte."""
    robot = Path(__file__).resolve().parents[2] / "omni-cli" / "tests" / "data" / "diff_robot.toml"
    subprocess.run(
        [*omnical_command(), "simulate", "--robot", str(robot), "--effect", "wheel_radius:a=0.02",
         "--runs-per-command", "1", "--duration", "4", "--out", str(tmp_path / "sim"), "-q"],
        check=True,
        capture_output=True,
    )
    train = tmp_path / "sim" / "train"
    with open(train / "robot.toml", "a") as f:
        f.write("\n[priors]\nradius_std_m = 0.001\nseparation_std_m = 0.01\n")
    cli = tmp_path / "cli.toml"
    subprocess.run([*omnical_command(), "train", str(train), "--out", str(cli), "-q"], check=True, capture_output=True)
    fit = omnical.train("diff", omnical.load(train), seed=0)
    fit.save(tmp_path / "python.toml")
    text = cli.read_text()
    assert "[[fit.priors]]" in text and "noise" in text, text
    assert (tmp_path / "python.toml").read_text() == text
    # A pickled calibration (a fleet worker's) writes the same file.
    pickle.loads(pickle.dumps(fit)).save(tmp_path / "unpickled.toml")
    assert (tmp_path / "unpickled.toml").read_text() == text
