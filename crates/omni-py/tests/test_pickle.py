"""Run, Model, Calibration and Dataset pickle and unpickle exactly (Dask ships them between processes)."""

from __future__ import annotations

import pickle
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import omnical


class Slip(omnical.Effect):
    """A user effect (module level, so pickle finds its class): every wheel turns (1 - k) as fast."""

    id = "slip_py"
    stage = "wheel"
    params = (omnical.Param("k", "1", 0.0, -0.1, 0.1),)

    def wheel_rates(self, p, t_s, dt_s, wheel_rad_s):  # type: ignore[no-untyped-def]
        return wheel_rad_s * (1.0 - p[0])


def round_trip(obj: Any) -> Any:
    return pickle.loads(pickle.dumps(obj, protocol=pickle.HIGHEST_PROTOCOL))


def assert_same_run(a: omnical.Run, b: omnical.Run) -> None:
    assert (a.name, a.n_wheels, a.n_samples, a.command, a.repetition) == (b.name, b.n_wheels, b.n_samples, b.command, b.repetition)
    for field in ("t_s", "wheel_rad_s", "truth", "recorded_odometry"):
        x, y = getattr(a, field), getattr(b, field)
        assert x.shape == y.shape and x.tobytes() == y.tobytes(), field


def test_run_round_trip_is_exact(runs: list[omnical.Run]) -> None:
    r = runs[5]
    back = round_trip(r)
    assert isinstance(back, omnical.Run)
    assert_same_run(r, back)
    assert r.command is not None and back.command == r.command
    # Compact: the f64 columns and a short header, no per-element overhead.
    raw = 8 * (r.t_s.size + r.wheel_rad_s.size + r.truth.size + r.recorded_odometry.size)
    assert raw < len(pickle.dumps(r)) < raw + 300
    # A run built from arrays (no command, odd values) too, and the cost on it is the same number.
    a = omnical.Run(np.array([0.0, 0.01, 0.025]), np.array([[1.0, -2.0, 3e-300], [0.1, 0.2, 0.3], [5.0, 6.0, 7.0]]),
                    np.array([[0.0, 0, 0, 0], [0.02, 1e-3, -2e-3, 0.1]]), name="from arrays")
    b = round_trip(a)
    assert_same_run(a, b)
    assert omnical.evaluate(omnical.Model.paper(), b).cost == omnical.evaluate(omnical.Model.paper(), a).cost


def test_corrupt_run_bytes_are_refused() -> None:
    with pytest.raises(ValueError, match="pickled run: the data ends early"):
        omnical._omnical._run_from_bytes(b"omnrun2\0" + b"\x01")
    with pytest.raises(ValueError, match="not a run written by this version"):
        omnical._omnical._run_from_bytes(b"nonsense" * 4)


def test_model_round_trip_is_exact() -> None:
    m = omnical.Model.paper().with_effect("time_offset", tau_s=0.1 + 0.2).with_params({"m11": -0.08832864769631231})
    back = round_trip(m)
    assert isinstance(back, omnical.Model)
    assert back.to_toml() == m.to_toml()
    assert back.param_values.tobytes() == m.param_values.tobytes()
    assert back.design_matrix.tobytes() == m.design_matrix.tobytes()
    g = omnical.Model.design(kinematics="geometry")
    assert round_trip(g).param_values.tobytes() == g.param_values.tobytes()


def test_model_with_a_python_effect_round_trips(runs: list[omnical.Run]) -> None:
    m = omnical.Model.paper().with_effect(Slip(), k=0.0125)
    back = round_trip(m)
    assert back.effects == ["slip_py"] and back.get("slip_py.k") == 0.0125  # type: ignore[attr-defined]
    assert omnical.evaluate(back, runs[:4]).cost == omnical.evaluate(m, runs[:4]).cost  # type: ignore[arg-type]


def test_calibration_round_trip_is_exact(runs: list[omnical.Run]) -> None:
    c = omnical.train("design", runs, robot="apr02", seed=3)
    back = round_trip(c)
    assert isinstance(back, omnical.Calibration)
    assert back.matrix.tobytes() == c.matrix.tobytes()
    assert back.model.to_toml() == c.model.to_toml() and back.start.to_toml() == c.start.to_toml()
    assert back.costs == c.costs and back.costs["cost_fitted"] == c.cost_fitted
    assert back.identifiability == c.identifiability
    assert back.history == c.history and len(back.history) > 3
    for name in ("objective", "evaluations", "seconds", "at_bound", "outside_box", "interrupted", "stopped", "warnings", "held"):
        assert getattr(back, name) == getattr(c, name), name


def test_dataset_round_trip_is_exact(sim_dir: Path) -> None:
    ds = omnical.load(sim_dir / "csv" / "train")
    back = round_trip(ds)
    assert isinstance(back, omnical.Dataset)
    assert len(back) == len(ds) == 36 and back.notes == ds.notes and back.skipped == ds.skipped
    for a, b in zip(ds, back):
        assert_same_run(a, b)
    assert back.design.to_toml() == ds.design.to_toml()


def test_dataset_keeps_what_its_ground_truth_measures(sim_dir: Path) -> None:
    """A relative reference's dataset (windows; a fit adds the sensor's mount) and a given mount survive
    pickling (Dask workers train what they are sent): the unpickled data train to the same model."""
    for kwargs, effects in (({"gt_kind": "relative"}, ["sensor_offset_yaw"]),
                            ({"gt_kind": "relative", "gt_mount": (0.1, 0.0, 2.0)}, [])):
        ds = omnical.load(sim_dir / "mcap" / "train", **kwargs)
        back = round_trip(ds)
        robot = sim_dir / "mcap" / "train" / "robot.toml"
        fits = [omnical.train("ik", d, robot=robot, seed=0) for d in (ds, back)]
        assert fits[0].model.effects == fits[1].model.effects == effects
        assert fits[0].costs == fits[1].costs
