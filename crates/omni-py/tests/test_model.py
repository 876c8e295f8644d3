"""Models and model files."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import omnical


def test_design_and_paper_matrices() -> None:
    d = omnical.Model.design()
    p = omnical.Model.paper()
    assert d.kinematics == "ik" and d.n_wheels == 3 and d.effects == []
    assert d.matrix.shape == (3, 3) and d.matrix.dtype == np.float64
    np.testing.assert_array_equal(p.design_matrix, d.matrix)
    assert not np.array_equal(p.matrix, d.matrix)
    assert d.param_names[:3] == ["m11", "m12", "m13"]
    assert d.param_values.shape == (9,)
    assert set(d.param_specs[0]) == {"name", "unit", "null", "lower", "upper"}
    g = omnical.Model.design(kinematics="geometry")
    assert g.kinematics == "geometry" and g.param_names[0] == "r_a"
    np.testing.assert_allclose(g.matrix, d.matrix, atol=1e-3)
    with pytest.raises(ValueError, match='kinematics "wheels": expected "ik", "geometry", "diff", "mecanum" or "skid"'):
        omnical.Model.design(kinematics="wheels")


def test_from_matrix_checks_shape() -> None:
    m = omnical.Model.from_matrix(np.eye(3))
    np.testing.assert_array_equal(m.matrix, np.eye(3))
    with pytest.raises(ValueError, match=r"matrix must have shape \(3, W\), got \(2, 3\)"):
        omnical.Model.from_matrix(np.ones((2, 3)))
    with pytest.raises(ValueError, match="design has 4 wheels but matrix has 3"):
        omnical.Model.from_matrix(np.eye(3), design=np.ones((3, 4)))
    with pytest.raises(ValueError, match="not finite"):
        omnical.Model.from_matrix(np.full((3, 3), np.nan))


def test_effects_and_params() -> None:
    m = omnical.Model.design().with_effect("time_offset", tau_s=0.02)
    assert m.effects == ["time_offset"]
    assert m.get("time_offset.tau_s") == 0.02
    assert m.params["time_offset.tau_s"] == 0.02
    m2 = m.with_params({"time_offset.tau_s": 0.05, "m11": -0.09})
    assert m2.get("time_offset.tau_s") == 0.05 and m2.get("m11") == -0.09
    assert m.get("time_offset.tau_s") == 0.02  # immutable
    with pytest.raises(ValueError, match='unknown effect "nope"; known: sensor_offset'):
        m.with_effect("nope")
    with pytest.raises(ValueError, match='effect time_offset: unknown parameter "tau"; known: tau_s'):
        omnical.Model.design().with_effect("time_offset", tau=1.0)
    with pytest.raises(ValueError, match='unknown parameter "x"'):
        m.get("x")
    with pytest.raises(ValueError, match='unknown parameter "x"'):
        m.with_params({"x": 1.0})
    assert "time_offset" in repr(m)


def test_catalogue() -> None:
    cat = omnical.effect_catalogue()
    assert [e["id"] for e in cat] == list(omnical.CATALOGUE)
    t = next(e for e in cat if e["id"] == "time_offset")
    assert t["stage"] == "clock" and t["params"][0]["name"] == "tau_s" and t["params"][0]["unit"] == "s"


def test_save_load_round_trip_is_exact(tmp_path: Path) -> None:
    m = omnical.Model.paper().with_effect("time_offset", tau_s=0.1 + 0.2)
    path = tmp_path / "m.toml"
    m.save(path)
    back = omnical.load_model(path)
    assert back.effects == ["time_offset"]
    np.testing.assert_array_equal(back.param_values, m.param_values)
    assert m.to_toml().startswith("# omnical model file")
    back_str = omnical.load_model(str(path))
    np.testing.assert_array_equal(back_str.matrix, m.matrix)


def test_model_file_errors(tmp_path: Path) -> None:
    with pytest.raises(FileNotFoundError, match="missing.toml"):
        omnical.load_model(tmp_path / "missing.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text("format = [")
    with pytest.raises(omnical.ModelFileError, match="bad.toml"):
        omnical.load_model(bad)
    wrong = tmp_path / "wrong.toml"
    wrong.write_text(omnical.Model.design().to_toml().replace('kinematics = "ik"', 'kinematics = "wheels"'))
    with pytest.raises(omnical.ModelFileError, match='kinematics = "wheels": expected "ik", "geometry", "diff", "mecanum" or "skid"'):
        omnical.load_model(wrong)
    with pytest.raises(OSError):
        omnical.Model.design().save(tmp_path / "no" / "such" / "dir" / "m.toml")


def test_a_model_marked_interrupted_is_loaded_with_a_warning(tmp_path: Path) -> None:
    """`train` stopped by Ctrl-C marks its model file `interrupted = true` (issue 48): Python says so as the CLI
    does; a finished model loads quietly."""
    import warnings

    done = tmp_path / "done.toml"
    omnical.Model.paper().save(done)
    marked = tmp_path / "m.toml"
    marked.write_text(done.read_text() + "\n[fit]\ninterrupted = true\n")
    with pytest.warns(UserWarning, match=r"m\.toml: the model is marked interrupted = true .* train again without stopping it"):
        m = omnical.load_model(marked)
    np.testing.assert_array_equal(m.matrix, omnical.Model.paper().matrix)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        omnical.load_model(done)


def test_a_skid_steer_base_has_its_own_model() -> None:
    """`kind = "skid"` (issue 47): the ICR model's five parameters at the design, the differential drive of
    the sides' mean positions, no sideways row."""
    robot = Path(__file__).resolve().parents[2] / "omni-cli" / "tests" / "data" / "skid_robot.toml"
    m = omnical.Model.design(robot, kinematics="skid")
    assert m.kinematics == "skid" and m.n_wheels == 4
    assert m.param_names == ["r_right", "r_left", "y_icr_left", "y_icr_right", "x_icr"]
    np.testing.assert_allclose(m.param_values, [0.165, 0.165, 0.2775, -0.2775, 0.0], atol=1e-12)
    np.testing.assert_array_equal(m.matrix[1], np.zeros(4))
    np.testing.assert_allclose(m.matrix[2], [-0.165 / 1.11, -0.165 / 1.11, 0.165 / 1.11, 0.165 / 1.11], rtol=1e-12)
