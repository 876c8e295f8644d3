"""explore (issue 18): a world-frame drift outside the catalogue is found by the world family, and the
learned correction trains like any other effect."""

from __future__ import annotations

import omnical


def test_explore_finds_a_world_drift_and_the_learned_effect_trains() -> None:
    truth = omnical.Model.design().with_effect("learned:world", drift_x=0.0039, drift_y=-0.0021)
    train = omnical.simulate(truth, runs_per_command=1, duration_s=4.0, seed=11)
    held_out = omnical.simulate(truth, runs_per_command=1, duration_s=4.0, seed=12, prefix="validation/")
    e = omnical.explore(omnical.Model.design(), train, validate=held_out)
    assert e.best == "world", e.conclusion
    assert e.unexplained is False
    world = e.families[0]
    assert world["family"] == "world" and world["passes"] and world["held_out_gain"] > 0.3
    assert world["status"] == "fitted" and world["status_reason"] is None
    # Every family is fitted or says why not, never all terms at 0 as a silent "fitted".
    for f in e.families:
        assert f["status"] in ("fitted", "not_excited", "singular", "not_converged"), f
        assert f["status"] != "fitted" or any(t["value"] != 0.0 for t in f["terms"]), f
        assert f["status_text"], f
    terms = {t["name"]: t for t in world["terms"]}
    assert abs(terms["drift_x"]["value"] - 0.0039) < 4e-4 and terms["drift_x"]["unit"] == "m/s"
    assert abs(terms["drift_y"]["value"] + 0.0021) < 4e-4
    assert e.to_dict()["schema_version"] == 1
    assert e.model is not None and "learned:world.drift_x" in e.model.param_names
    fit = omnical.train("design", train, robot="apr02", effects=["learned:world"], seed=0)
    true_cost = omnical.evaluate(truth, held_out).path_cost
    assert omnical.evaluate(fit.model, held_out).path_cost <= 1.1 * true_cost
