"""simulate, evaluate, integrate, train, diagnose: shapes, keywords, callbacks, errors."""

from __future__ import annotations

import os
import signal
from pathlib import Path

import numpy as np
import pytest

import omnical


def test_simulate_is_deterministic_and_named(truth: omnical.Model) -> None:
    a = omnical.simulate(truth, runs_per_command=1, duration_s=1.0, seed=3, prefix="x/")
    b = omnical.simulate(truth, runs_per_command=1, duration_s=1.0, seed=3, prefix="x/")
    c = omnical.simulate(truth, runs_per_command=1, duration_s=1.0, seed=4, prefix="x/")
    assert len(a) == 36 and a[0].name == "x/00-r0" and a[0].command is not None
    np.testing.assert_array_equal(a[5].wheel_rad_s, b[5].wheel_rad_s)
    assert not np.array_equal(a[5].wheel_rad_s, c[5].wheel_rad_s)
    quiet = omnical.simulate(runs_per_command=1, duration_s=1.0, noise_free=True)
    assert omnical.evaluate(omnical.Model.paper(), quiet).cost < omnical.evaluate("design", quiet, robot="apr02").cost
    with pytest.raises(ValueError, match="simulator duration_s: must be > 0"):
        omnical.simulate(runs_per_command=1, duration_s=-1.0)
    with pytest.raises(ValueError, match="at least one command and one repetition"):
        omnical.simulate(runs_per_command=0)


def test_evaluate_returns_residual_arrays(runs: list[omnical.Run]) -> None:
    ev = omnical.evaluate(omnical.Model.design(), runs)
    assert ev.end_errors.shape == (36, 3) and len(ev.runs) == 36 and ev.names[0] == runs[0].name
    r = ev.runs[0]
    k = runs[0].truth.shape[0] - 1
    assert r.t_s.shape == (k,) and r.predicted.shape == (k, 3) and r.error.shape == (k, 3)
    assert r.truth_index == list(range(1, k + 1))
    np.testing.assert_array_equal(r.end_error, ev.end_errors[0])
    np.testing.assert_allclose(ev.cost, np.mean(np.linalg.norm(ev.end_errors, axis=1)), rtol=1e-12)
    assert ev.path_cost > 0 and r.path_rms > 0
    assert omnical.evaluate("design", runs, robot="apr02").cost == ev.cost  # the robot's design model
    assert omnical.evaluate("design", runs[0], robot="apr02").names == [runs[0].name]


def test_evaluate_rejects_wrong_inputs(runs: list[omnical.Run]) -> None:
    four = omnical.Model.from_matrix(np.ones((3, 4)))
    with pytest.raises(ValueError, match="has 3 wheels but the model has 4"):
        omnical.evaluate(four, runs)
    with pytest.raises(TypeError, match="runs must be a Dataset, a Run or an iterable of Run, got int"):
        omnical.evaluate("design", 3)
    with pytest.raises(TypeError, match='model must be an omnical.Model, "design", "paper" or a model file path, got int'):
        omnical.evaluate(3, runs)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="omnical.evaluate"):
        omnical.evaluate("design", runs)  # simulated runs name no robot


def test_integrate(runs: list[omnical.Run]) -> None:
    path = omnical.integrate(omnical.Model.design(), runs[0])
    assert path.ndim == 2 and path.shape[1] == 4
    np.testing.assert_allclose(path[0], runs[0].truth[0])
    assert path[-1, 0] == runs[0].truth[-1, 0]


def test_train_returns_a_model_and_costs(runs: list[omnical.Run]) -> None:
    seen: list[dict] = []
    fit = omnical.train("design", runs, robot="apr02", seed=0, progress=seen.append)
    assert isinstance(fit.model, omnical.Model)
    assert fit.matrix.shape == (3, 3) and fit.matrix.dtype == np.float64
    assert fit.costs["cost_fitted"] < 0.5 * fit.costs["cost_start"]
    assert fit.cost_fitted == fit.costs["cost_fitted"] and fit.objective == "path"
    assert fit.effects == [] and set(fit.params) == {f"m{r}{c}" for r in (1, 2, 3) for c in (1, 2, 3)}
    assert seen and seen[0]["optimizer"] == "ga" and seen[0]["iteration"] == 1
    assert [h["iteration"] for h in fit.history][: len(seen)] == [s["iteration"] for s in seen]
    assert not fit.interrupted and not fit.stopped and fit.evaluations > 0
    again = omnical.train("design", runs, robot="apr02", seed=0)
    np.testing.assert_array_equal(again.matrix, fit.matrix)  # deterministic for a seed
    # The flower runs constrain every entry: standard errors for all nine, no warnings, nothing held.
    ident = fit.identifiability
    assert fit.warnings == [] and fit.held == [] and ident["weak"] == []
    assert [p["name"] for p in ident["params"]] == list(fit.params)
    assert all(0 < p["std_error"] < 0.01 * p["scale"] for p in ident["params"])
    assert ident["covariance_kind"] == "per_run" and ident["condition_number"] > 1


def test_train_warns_about_unexcited_directions(truth: omnical.Model) -> None:
    straight = [r for r in omnical.simulate(truth, runs_per_command=1, duration_s=3.0, seed=5)
                if r.command is not None and r.command[2] == 0.0]
    fit = omnical.train("design", straight, robot="apr02", seed=0)
    assert len(fit.held) == 3 and len(fit.warnings) == 3
    assert all("rotating on the spot" in w for w in fit.warnings)
    assert sum(p["std_error"] is None for p in fit.identifiability["params"]) >= 3


def test_train_with_an_effect_recovers_it(runs: list[omnical.Run]) -> None:
    fit = omnical.train("design", runs, robot="apr02", effects=["time_offset"], seed=0)
    assert fit.effects == ["time_offset"]
    assert abs(fit.params["time_offset.tau_s"] - 0.06) < 0.01
    assert fit.start.effects == ["time_offset"]


def test_progress_false_stops_and_keeps_the_best(runs: list[omnical.Run]) -> None:
    fit = omnical.train("design", runs, robot="apr02", seed=0, progress=lambda it: it["iteration"] < 2)
    assert fit.stopped and not fit.interrupted
    assert max(h["iteration"] for h in fit.history) == 2
    assert fit.cost_fitted <= fit.cost_start


def test_ctrl_c_stops_training_and_keeps_the_best(runs: list[omnical.Run]) -> None:
    # Python leaves SIGINT ignored when it starts as a background job of a non-interactive shell (as a CI
    # step may be): install Python's own Ctrl-C handler, as an interactive session has, and restore it after.
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        _press_ctrl_c_during_training(runs)
    finally:
        signal.signal(signal.SIGINT, previous)


def _press_ctrl_c_during_training(runs: list[omnical.Run]) -> None:
    def press_ctrl_c(it: dict) -> None:
        if it["iteration"] == 2:
            os.kill(os.getpid(), signal.SIGINT)

    with pytest.warns(UserWarning, match="interrupted"):
        fit = omnical.train("design", runs, robot="apr02", seed=0, progress=press_ctrl_c)
    assert fit.interrupted
    assert all(h["optimizer"] == "ga" for h in fit.history)  # no polish after Ctrl-C
    assert fit.matrix.shape == (3, 3) and fit.cost_fitted <= fit.cost_start


def test_progress_exception_propagates(runs: list[omnical.Run]) -> None:
    def boom(it: dict) -> None:
        raise RuntimeError("from the callback")

    with pytest.raises(RuntimeError, match="from the callback"):
        omnical.train("design", runs, robot="apr02", progress=boom)


def test_train_bad_arguments(runs: list[omnical.Run]) -> None:
    with pytest.raises(ValueError, match='preset "fast": expected "default" or "paper"'):
        omnical.train("design", runs, robot="apr02", preset="fast")
    with pytest.raises(ValueError, match="no training runs"):
        omnical.train("design", [], robot="apr02")
    with pytest.raises(ValueError, match='unknown effect "nope"'):
        omnical.train("design", runs, robot="apr02", effects=["nope"])
    with pytest.raises(TypeError):
        omnical.train("design", runs, 0)  # type: ignore[misc]  # seed is keyword-only


def test_diagnose_ranks_the_hidden_effect(runs: list[omnical.Run], validation: list[omnical.Run]) -> None:
    fit = omnical.train("design", runs, robot="apr02", seed=0)
    d = omnical.diagnose(fit.model, runs, validate=validation, candidates=["time_offset", "sensor_offset"])
    assert d.verdict == "time_offset" and d.verdict_text.startswith("add time_offset")
    top = d.ranking[0]
    assert top["effect"] == "time_offset" and top["held_out_gain"] > 0.2
    assert top["params"][0]["name"] == "tau_s" and abs(top["params"][0]["value"] - 0.06) < 0.01
    assert {"train_path", "held_out_path", "train_end_pose", "held_out_end_pose"} <= set(d.costs)
    assert d.held_out == "validation set" and [r["label"] for r in d.ladder] == ["design", "model"]
    assert isinstance(d.findings, list) and d.noise_floor is not None
    assert d.final_model is not None and d.final_model.effects == []
    assert d.to_dict()["verdict"] == "time_offset"
    # No command is repeated here: the noise-floor ratio decides whether something is still missing.
    ev = d.unexplained_evidence
    assert d.unexplained is False and d.to_dict()["unexplained"] is False
    assert ev["decided_by"] == "noise_floor_ratio" and ev["groups_total"] == 0 and ev["share_biased"] is None
    assert 0.0 < ev["ratio"] < 3.0 and ev["remaining_held_out_m"] > 0.0
    assert "the group test could not be made" in d.verdict_text
    auto = omnical.diagnose(fit.model, runs, validate=validation, candidates=["time_offset"], auto=True)
    assert auto.final_model.effects == ["time_offset"] and auto.ladder[-1]["label"] == "+ time_offset"
    with pytest.raises(ValueError, match='unknown effect "nope"'):
        omnical.diagnose(fit.model, runs, candidates=["nope"])


def test_report_writes_every_figure(
    runs: list[omnical.Run], validation: list[omnical.Run], tmp_path: Path
) -> None:
    fit = omnical.train("design", runs, robot="apr02", seed=0)
    out = tmp_path / "r.html"
    ids = omnical.report(fit.model, runs, validate=validation, out=out, png=tmp_path / "png")
    assert ids == ["ladder", "overlay-worst", "overlay-typical", "flower", "heat-map", "growth", "ranking"]
    html = out.read_text(encoding="utf-8")
    assert html.count("<figure ") == 7 and "<script" not in html and "add time_offset" in html
    assert sorted(p.name for p in (tmp_path / "png").iterdir()) == sorted(f"{i}.png" for i in ids)
    quick = omnical.report(fit.model, runs, out=tmp_path / "q.html", diagnose=False)
    assert "ranking" not in quick and "ladder" in quick
    with pytest.raises(FileNotFoundError, match="fit.toml"):
        omnical.report(str(tmp_path / "fit.toml"), runs, out=tmp_path / "x.html")  # a model file that is not there
