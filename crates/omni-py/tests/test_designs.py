"""Each run carries its own design, and train refuses what `omnical train` refuses: binding behaviour on the
shared OptiOdom sets (skipped when they are not beside the repository)."""

from __future__ import annotations

import math
import pickle
import warnings
from pathlib import Path

import pytest

import omnical
from conftest import REPO


def shared(kind: str) -> Path:
    """The shared OptiOdom folder of a robot type."""
    for base in (REPO.parent / "shared", Path("/work/shared")):
        p = base / "data" / f"optiodom-{kind}-square"
        if p.exists():
            return p
    pytest.skip(f"optiodom-{kind}-square not found beside the repository")


def test_design_is_each_sets_own_and_pools_run_weighted() -> None:
    """omni4: the two sets declare Li 0.2, 0.2 (8 runs) and 0.205, 0.215 (12 runs); evaluate("design") on
    both is the run-weighted mean of each set's own (Eq. 6; path RMS from the mean MSE), as the CLI's eval,
    and survives pickling; diagnose's design costs on the training runs are the same numbers."""
    data = shared("omni4")
    a, b = data / "080920201715", data / "231220200521"
    ea, eb = omnical.evaluate("design", omnical.load(a)), omnical.evaluate("design", omnical.load(b))
    both = omnical.load(a, b)
    assert any("declare 2 different designs" in n for n in both.notes), both.notes
    e = omnical.evaluate("design", both)
    assert e.cost == pytest.approx((8 * ea.cost + 12 * eb.cost) / 20, abs=1e-12)
    assert e.path_cost == pytest.approx(math.sqrt((8 * ea.path_cost**2 + 12 * eb.path_cost**2) / 20), abs=1e-12)
    # Measured: 0.39375 and 0.98397, pooled 0.74788 (one design for all gave 0.87913).
    assert (round(ea.cost, 5), round(eb.cost, 5), round(e.cost, 5)) == (0.39375, 0.98397, 0.74788)
    again = pickle.loads(pickle.dumps(both))
    assert omnical.evaluate("design", again).cost == e.cost
    # The start (Dataset.design) is the design of the most runs: b's.
    assert omnical.evaluate(both.design, omnical.load(b)).cost == pytest.approx(eb.cost, abs=1e-12)
    d = omnical.diagnose("design", both, validate=omnical.load(b), candidates=["time_offset"])
    assert d.design_costs["train_end_pose"] == pytest.approx(e.cost, abs=1e-12)
    assert d.design_costs["train_path"] == pytest.approx(e.path_cost, abs=1e-12)


def test_mixed_robot_kinds_are_refused() -> None:
    with pytest.raises(omnical.DatasetError, match="runs of robots of different kinds in one command: .*omni3 set"):
        omnical.load(shared("omni3") / "221220201934", shared("diff") / "230620202042")


@pytest.mark.parametrize("kind,set_id,ms", [("omni3", "221220201934", 40), ("diff", "230620202042", 50)])
def test_paper_preset_on_other_sampling_is_refused_unless_forced(kind: str, set_id: str, ms: int) -> None:
    runs = omnical.load(shared(kind) / set_id)
    with pytest.raises(omnical.CalibrationError, match=f"sampled every {ms} ms .*use preset=\"default\"") as e:
        omnical.train("ik", runs, preset="paper")
    assert "force=True fits with the fixed step anyway" in str(e.value)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        fit = omnical.train("ik", runs, preset="paper", force=True)
    texts = [str(w.message) for w in caught]
    assert any("the fitted model is worse than its start on its own training runs" in t for t in texts), texts
    assert fit.objective_fitted > 5 * omnical.evaluate("design", runs).cost
