"""A world-frame Python effect (`twist_at` with the heading) matches the learned correction it names:
examples/floor_slope.py fits both on runs with a world drift and judges them on held-out runs."""

from __future__ import annotations

import importlib.util
import math
from pathlib import Path

import pytest

import omnical

EXAMPLE = Path(__file__).resolve().parents[3] / "examples" / "floor_slope.py"


def load_example():  # type: ignore[no-untyped-def]
    spec = importlib.util.spec_from_file_location("floor_slope", EXAMPLE)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_twist_at_gets_the_heading() -> None:
    fs = load_example()
    seen: list[tuple[float, float]] = []

    class Spy(fs.FloorSlope):  # type: ignore[misc, name-defined]
        def twist_at(self, p, twist, wheel_rad_s, heading_rad, since_start_s):  # type: ignore[no-untyped-def]
            seen.append((heading_rad, since_start_s))
            return super().twist_at(p, twist, wheel_rad_s, heading_rad, since_start_s)

    py = omnical.Model.design().with_effect(Spy(), downhill_x=0.004, downhill_y=-0.002)
    rs = omnical.Model.design().with_effect("learned:world", drift_x=0.004, drift_y=-0.002)
    runs = omnical.simulate(rs, runs_per_command=1, duration_s=2.0, seed=3)
    assert omnical.evaluate(py, runs).path_cost == pytest.approx(omnical.evaluate(rs, runs).path_cost, rel=1e-9)
    assert max(abs(h) for h, _ in seen) > 0.5 and max(t for _, t in seen) > 1.5


def test_floor_slope_matches_the_learned_world_correction() -> None:
    r = load_example().compare()
    assert r["design_cost"] > 1.5 * r["true_cost"]
    assert r["learned_cost"] <= 1.1 * r["true_cost"] and r["slope_cost"] <= 1.1 * r["true_cost"], r
    assert r["slope_cost"] == pytest.approx(r["learned_cost"], rel=0.02)
    for got in (r["learned"], r["slope"]):
        assert math.isclose(got[0], 0.0039, abs_tol=4e-4) and math.isclose(got[1], -0.0021, abs_tol=4e-4), r
