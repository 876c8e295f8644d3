"""User effects written in Python: simulate, train, evaluate and diagnose use them like built-ins."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import omnical


class BrakeDrag(omnical.Effect):
    """Wheel a loses a constant speed while it turns (a dragging brake pad)."""

    id = "brake_drag"
    stage = "wheel"
    params = [omnical.Param("d_rad_s", "rad/s", 0.0, 0.0, 1.0)]

    def __init__(self) -> None:
        self.calls = 0

    def wheel_rates(self, p, t_s, dt_s, wheel_rad_s):  # type: ignore[no-untyped-def]
        self.calls += 1
        assert t_s.shape == dt_s.shape == (wheel_rad_s.shape[0],) and wheel_rad_s.shape[1] == 3
        w = wheel_rad_s.copy()
        a = w[:, 0]
        w[:, 0] = np.where(np.abs(a) > p[0], a - p[0] * np.sign(a), a)
        return w


class Lag(omnical.Effect):
    """A clock lag, in Python."""

    id = "py_lag"
    stage = "clock"
    params = [omnical.Param("tau_s", "s", 0.0, -0.2, 0.2)]

    def clock_lag_s(self, p):  # type: ignore[no-untyped-def]
        return float(p[0])


def test_wheel_effect_is_simulated_and_recovered() -> None:
    drag = BrakeDrag()
    truth = omnical.Model.paper().with_effect(drag, d_rad_s=0.3)
    assert truth.effects == ["brake_drag"] and truth.get("brake_drag.d_rad_s") == 0.3
    runs = omnical.simulate(truth, runs_per_command=1, duration_s=2.0, seed=1)
    assert drag.calls >= 36
    fit = omnical.train(omnical.Model.paper(), runs, effects=[drag], seed=0)
    assert abs(fit.params["brake_drag.d_rad_s"] - 0.3) < 0.05


def test_clock_effect_matches_the_builtin(runs: list[omnical.Run]) -> None:
    py = omnical.Model.paper().with_effect(Lag(), tau_s=0.06)
    rs = omnical.Model.paper().with_effect("time_offset", tau_s=0.06)
    assert omnical.evaluate(py, runs).cost == pytest.approx(omnical.evaluate(rs, runs).cost, rel=1e-12)


def test_diagnose_ranks_a_python_effect(runs: list[omnical.Run], validation: list[omnical.Run]) -> None:
    fit = omnical.train("design", runs, robot="apr02", seed=0)
    d = omnical.diagnose(fit.model, runs, validate=validation, candidates=[Lag(), "sensor_offset"])
    assert d.verdict == "py_lag"
    assert d.ranking[0]["physics"] == "A clock lag, in Python."
    assert abs(d.ranking[0]["params"][0]["value"] - 0.06) < 0.01


def test_model_file_with_a_python_effect(tmp_path: Path) -> None:
    m = omnical.Model.paper().with_effect(Lag(), tau_s=0.05).with_effect("time_offset", tau_s=0.01)
    path = tmp_path / "m.toml"
    m.save(path)
    with pytest.raises(omnical.ModelFileError, match='unknown effect "py_lag"'):
        omnical.load_model(path)
    back = omnical.load_model(path, effects=[Lag()])
    assert back.effects == ["py_lag", "time_offset"]
    np.testing.assert_array_equal(back.param_values, m.param_values)


class Raises(omnical.Effect):
    id = "raises"
    stage = "wheel"
    params = [omnical.Param("k", "1", 0.0, -1.0, 1.0)]

    def wheel_rates(self, p, t_s, dt_s, wheel_rad_s):  # type: ignore[no-untyped-def]
        raise ZeroDivisionError("bad physics")


class WrongShape(Raises):
    id = "wrong_shape"

    def wheel_rates(self, p, t_s, dt_s, wheel_rad_s):  # type: ignore[no-untyped-def]
        return wheel_rad_s[:, :2]


def test_exceptions_in_effects_surface(runs: list[omnical.Run]) -> None:
    with pytest.raises(ZeroDivisionError, match="bad physics"):
        omnical.train("design", runs, robot="apr02", effects=[Raises()])
    with pytest.raises(ZeroDivisionError, match="bad physics"):
        omnical.evaluate(omnical.Model.design().with_effect(Raises()), runs)
    with pytest.raises(ValueError, match=r"effect wrong_shape: wheel_rates must return shape \(\d+, 3\), got \(\d+, 2\)"):
        omnical.simulate(omnical.Model.paper().with_effect(WrongShape()), runs_per_command=1, duration_s=1.0)


def test_bad_effect_definitions() -> None:
    class NoStage:
        id = "x"
        stage = "teleport"
        params = ()

    with pytest.raises(ValueError, match='effect stage "teleport" is not supported'):
        omnical.Model.design().with_effect(NoStage())
    with pytest.raises(ValueError, match="needs a string attribute `id`"):
        omnical.Model.design().with_effect(object())

    class BadParams(omnical.Effect):
        id = "bad_params"
        params = [("k", "1", 0.0)]  # type: ignore[list-item]

    with pytest.raises(ValueError, match=r"params\[0\] must be \(name, unit, null, lower, upper\)"):
        omnical.Model.design().with_effect(BadParams())


def test_world_drift_from_python() -> None:
    # A tilted floor: (+3.9, −2.1) mm/s in the world frame while the robot moves.
    assert "world_drift" in omnical.CATALOGUE
    truth = omnical.Model.paper().with_effect("world_drift", drift_x_m_s=0.0039, drift_y_m_s=-0.0021)
    runs = omnical.simulate(truth, runs_per_command=1, duration_s=2.5, seed=31)
    validation = omnical.simulate(truth, runs_per_command=1, duration_s=2.5, seed=32, prefix="validation/")
    d = omnical.diagnose(omnical.Model.paper(), runs, validate=validation, candidates=["world_drift", "time_offset"])
    assert d.verdict == "world_drift", d.verdict_text
    dx, dy = d.ranking[0]["params"]
    assert dx["name"] == "drift_x_m_s" and dx["unit"] == "m/s" and abs(dx["value"] - 0.0039) < 3e-4
    assert dy["name"] == "drift_y_m_s" and abs(dy["value"] + 0.0021) < 3e-4
    assert truth.effects == ["world_drift"]
