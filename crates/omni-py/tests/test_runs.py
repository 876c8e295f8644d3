"""Runs from arrays and from files: shapes, dtypes, validation messages, file errors."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import omnical


def arrays(n: int = 50, wheels: int = 3) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    t = np.arange(n) * 0.01
    w = np.tile([1.0, -0.5, -0.5][:wheels] + [0.0] * max(0, wheels - 3), (n, 1))
    truth = np.array([[0.0, 0.0, 0.0, 0.0], [t[-1], 0.1, 0.0, 0.0]])
    return t, w, truth


def test_run_from_arrays_round_trips_columns() -> None:
    t, w, truth = arrays()
    r = omnical.Run(t, w, truth, name="mine", command=(0.2, 0.5, 0.0), repetition=2)
    assert (r.name, r.n_wheels, r.n_samples, r.repetition) == ("mine", 3, 50, 2)
    assert r.command == (0.2, 0.5, 0.0)
    np.testing.assert_array_equal(r.t_s, t)
    np.testing.assert_array_equal(r.wheel_rad_s, w)
    np.testing.assert_array_equal(r.truth, truth)
    assert r.t_s.dtype == np.float64 and r.wheel_rad_s.shape == (50, 3) and r.truth.shape == (2, 4)
    assert r.recorded_odometry.shape == (0, 4)
    assert "mine" in repr(r)


def test_run_accepts_lists_ints_and_fortran_order() -> None:
    t, w, truth = arrays(4)
    r = omnical.Run(list(t), np.asfortranarray(w), truth.tolist())
    np.testing.assert_array_equal(r.wheel_rad_s, w)
    r2 = omnical.Run(np.arange(4), np.ones((4, 3), dtype=np.int32), [[0, 0, 0, 0], [3, 0, 0, 0]])
    assert r2.wheel_rad_s.dtype == np.float64


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (lambda t, w, g: (t, w[:, 0], g), r"wheel_rad_s must have shape \(N, W\), got \(50,\)"),
        (lambda t, w, g: (t, w[:-1], g), r"one row per stamp in t_s: shape \(N, W\) with N = 50, got \(49, 3\)"),
        (lambda t, w, g: (t, w, g[:, :3]), r"truth must have shape \(M, 4\): t_s, x_m, y_m, theta_rad, got \(2, 3\)"),
        (lambda t, w, g: (t.reshape(5, 10), w, g), r"t_s must have shape \(N,\), got \(5, 10\)"),
        (lambda t, w, g: (t, w, g[:1]), "run r: ground-truth poses has 1 entries, at least 2 are needed"),
    ],
)
def test_bad_shapes_raise_value_error(change, message) -> None:  # type: ignore[no-untyped-def]
    t, w, g = arrays()
    with pytest.raises(ValueError, match=message):
        omnical.Run(*change(t, w, g), name="r")


def test_nan_and_bad_stamps_raise_value_error_with_rust_message() -> None:
    t, w, g = arrays()
    w[7, 1] = np.nan
    with pytest.raises(ValueError) as e:
        omnical.Run(t, w, g, name="r1")
    assert str(e.value) == "run r1: wheel sample 7 has non-finite wheel_rad_s[1] NaN"
    t, w, g = arrays()
    t[3] = t[2]
    with pytest.raises(ValueError, match="stamps must strictly increase"):
        omnical.Run(t, w, g, name="r1")
    t, w, g = arrays()
    g[1, 2] = np.inf
    with pytest.raises(ValueError, match="ground-truth pose 1 has non-finite y_m inf"):
        omnical.Run(t, w, g, name="r1")
    with pytest.raises(ValueError, match="must be an array of numbers"):
        omnical.Run(t, [["a", "b", "c"]] * 50, g)


def test_load_csv_and_mcap(sim_dir: Path) -> None:
    csv = omnical.load(sim_dir / "csv" / "train")
    mcap = omnical.load(sim_dir / "mcap" / "train")
    assert isinstance(csv, omnical.Dataset)
    assert len(csv) == len(mcap) == 36
    assert csv[0].name.endswith("00-r0.csv") or "00-r0" in csv[0].name
    assert csv[-1].n_wheels == 3 and len(csv.runs) == 36
    assert [r.n_samples for r in csv][:3] == [r.n_samples for r in csv.runs][:3]
    np.testing.assert_allclose(csv[0].wheel_rad_s, mcap[0].wheel_rad_s, atol=1e-9)
    assert csv.skipped == [] and isinstance(csv.notes, list)
    assert csv.design.kinematics == "ik"
    with pytest.raises(IndexError):
        csv[36]
    two = omnical.load(sim_dir / "csv" / "train", sim_dir / "csv" / "validation")
    assert len(two) == 72


def test_load_optiodom_declares_its_geometry(optiodom: Path) -> None:
    ds = omnical.load(optiodom)
    assert len(ds) > 0
    assert ds.design.kinematics == "geometry"
    assert omnical.evaluate("design", ds).cost > 0


def test_missing_file_is_file_not_found(tmp_path: Path) -> None:
    missing = tmp_path / "nope.csv"
    with pytest.raises(FileNotFoundError) as e:
        omnical.load(missing)
    assert str(e.value).startswith(str(missing) + ": ")
    assert isinstance(e.value, OSError)


def test_bad_file_is_dataset_error(tmp_path: Path) -> None:
    bad = tmp_path / "bad.csv"
    bad.write_text("t_s,nonsense\n1,2\n")
    with pytest.raises(omnical.DatasetError) as e:
        omnical.load(bad)
    assert str(bad) in str(e.value)
    assert isinstance(e.value, omnical.OmnicalError)
    with pytest.raises(omnical.DatasetError, match="unsupported input"):
        omnical.load(tmp_path / "bad.txt") if (tmp_path / "bad.txt").write_text("x") else None
    with pytest.raises(ValueError, match="at least one path"):
        omnical.load()


def test_skip_invalid_lists_the_skipped(tmp_path: Path, sim_dir: Path) -> None:
    import shutil

    shutil.copy(sim_dir / "csv" / "train" / "00-r0.csv", tmp_path / "good.csv")
    (tmp_path / "zbad.csv").write_text("t_s,nonsense\n1,2\n")
    ds = omnical.load(tmp_path, skip_invalid=True)
    assert len(ds) == 1 and len(ds.skipped) == 1
    assert ds.skipped[0][0].endswith("zbad.csv")
