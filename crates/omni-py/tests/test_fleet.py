"""omnical.fleet on a local Dask cluster of 2 worker processes: every robot-session calibrated, the
degrading robots of a simulated fleet found (and no others), model files byte-identical to `omnical
train`, a bad session's error in its row, a killed worker losing and duplicating nothing, Ctrl-C writing
what finished, and the `omnical fleet` command."""

from __future__ import annotations

import csv
import json
import os
import shutil
import signal
import subprocess
from pathlib import Path
from typing import Any, Iterator

import pytest

distributed = pytest.importorskip("distributed")

from conftest import omnical_command  # noqa: E402

from omnical import fleet  # noqa: E402

N_ROBOTS, N_SESSIONS = 6, 3


@pytest.fixture(scope="module")
def sim_fleet(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, dict[str, Any]]:
    """6 robots × 3 sessions (36 short runs each): spread radii, r01's wheel b wears 1 % per session,
    r02's clock lags 30 ms more each session."""
    root = tmp_path_factory.mktemp("fleet")
    truth = fleet.simulate_fleet(root, N_ROBOTS, N_SESSIONS, seed=0)
    return root, truth


@pytest.fixture(scope="module")
def client() -> Iterator[Any]:
    cluster = distributed.LocalCluster(
        n_workers=2, processes=True, threads_per_worker=1, dashboard_address=None, env={"RAYON_NUM_THREADS": "1"}
    )
    c = distributed.Client(cluster)
    yield c
    c.close()
    cluster.close()


@pytest.fixture(scope="module")
def fleet_run(sim_fleet: tuple[Path, dict[str, Any]], client: Any, tmp_path_factory: pytest.TempPathFactory) -> fleet.FleetResult:
    root, _ = sim_fleet
    return fleet.calibrate_fleet(root, tmp_path_factory.mktemp("out"), client=client, seed=0)


def csv_rows(path: Path) -> list[dict[str, str]]:
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def test_simulated_fleet_layout(sim_fleet: tuple[Path, dict[str, Any]]) -> None:
    root, truth = sim_fleet
    assert sorted(truth["degrading"]) == ["r01", "r02"]
    assert "wear" in truth["degrading"]["r01"][0] and "time_offset" in truth["degrading"]["r02"][0]
    assert truth["robots"]["r02"]["s02"]["time_offset_s"] == pytest.approx(0.06)
    b = [truth["robots"]["r01"][f"s{s:02d}"]["wheel_radius"]["b"] for s in range(3)]
    assert b[0] - b[2] == pytest.approx(0.02)
    assert (root / "robot.toml").is_file() and len(list((root / "r03" / "s01").glob("*.csv"))) == 36
    sessions = fleet.find_sessions(root)
    assert len(sessions) == 18 and sessions[4].robot == "r01" and sessions[4].session == "s01"
    assert sessions[4].robot_toml == str(root / "robot.toml")


def test_fleet_finds_the_degrading_robots_and_no_others(fleet_run: fleet.FleetResult, sim_fleet: tuple[Path, dict[str, Any]]) -> None:
    _, truth = sim_fleet
    r = fleet_run
    assert len(r.rows) == 18 and not r.errors, r.errors
    assert r.flagged == sorted(truth["degrading"]), r.analysis["reasons"]
    wear = [t for t in r.analysis["trends"] if t["flagged"] and t["robot"] == "r01"]
    assert [t["quantity"] for t in wear] == ["radius_b_pct"]
    # The wheel loses 1 % of its radius per session; the trend recovers it within its standard error.
    assert wear[0]["slope"] == pytest.approx(-1.0, abs=max(3 * wear[0]["slope_se"], 0.05))
    # r02: the diagnosis names the growing clock lag.
    assert {e["effect"] for e in r.analysis["effects"]["r02"]} == {"time_offset"}
    taus = {row["session"]: row.get("time_offset.tau_s") for row in r.rows if row["robot"] == "r02"}
    assert taus["s02"] == pytest.approx(0.06, abs=0.005)
    # The steady robots' fitted wheel radii match their true ones within 0.5 % (36 runs of 2 s a session;
    # the first-order standard errors, 0.07–0.18 %, ignore the entries' correlations).
    for row in r.rows:
        if row["robot"] in ("r00", "r03", "r04", "r05"):
            for w in "abc":
                true = 100 * truth["robots"][row["robot"]][row["session"]]["wheel_radius"][w]
                assert row[f"radius_{w}_pct"] == pytest.approx(true, abs=0.5), (row["robot"], row["session"], w)


def test_fleet_outputs(fleet_run: fleet.FleetResult) -> None:
    out = fleet_run.out
    table = csv_rows(out / "fleet.csv")
    assert [(t["robot"], t["session"], t["session_index"]) for t in table][:4] == [
        ("r00", "s00", "0"), ("r00", "s01", "1"), ("r00", "s02", "2"), ("r01", "s00", "0")
    ]
    assert len(table) == 18 and all(t["status"] == "ok" for t in table)
    assert float(table[0]["cost_fitted"]) < float(table[0]["cost_design"])
    assert table[0]["m11_se"] and table[0]["radius_b_pct_se"]
    for t in table:
        assert (out / t["model_file"]).is_file()
    page = (out / "fleet.html").read_text()
    assert page.startswith("<!DOCTYPE html>") and "<script" not in page and "http://" not in page.replace("http://www.w3.org/2000/svg", "")
    assert "robot r01, wheel b: effective radius" in page and "wear" in page and "time_offset" in page


def test_model_files_are_byte_identical_to_omnical_train(fleet_run: fleet.FleetResult, sim_fleet: tuple[Path, dict[str, Any]], tmp_path: Path) -> None:
    root, _ = sim_fleet
    for robot, session in (("r01", "s02"), ("r04", "s00")):
        out = tmp_path / f"{robot}-{session}.toml"
        subprocess.run(
            [*omnical_command(), "train", str(root / robot / session), "--robot", str(root / "robot.toml"), "--seed", "0", "--out", str(out)],
            check=True,
            capture_output=True,
        )
        assert (fleet_run.out / robot / session / "model.toml").read_bytes() == out.read_bytes()


def test_a_bad_session_gets_its_error_and_the_others_finish(sim_fleet: tuple[Path, dict[str, Any]], client: Any, tmp_path: Path,
                                                            capsys: pytest.CaptureFixture[str]) -> None:
    root, _ = sim_fleet
    small = tmp_path / "fleet"
    shutil.copytree(root / "r00", small / "r00")
    shutil.copy(root / "robot.toml", small / "robot.toml")
    bad = small / "r09" / "s00"
    shutil.copytree(root / "r03" / "s00", bad)
    (bad / "00-r0.csv").write_text("t_s,wheel_a_rad_s\n0.0,nan\n")
    # A robot folder whose recordings lie in it directly, with no session folder: said, and given a row.
    shutil.copytree(root / "r04" / "s00", small / "r10")
    r = fleet.calibrate_fleet(small, tmp_path / "out", client=client, diagnose="none")
    assert len(r.rows) == 5 and [e["robot"] for e in r.errors] == ["r09", "r10"]
    assert "00-r0.csv" in r.errors[0]["error"]
    assert r.errors[1]["error"] == f"{small / 'r10'} holds no session folder: its recordings go in FLEET_DIR/r10/<session>/"
    assert f"omnical fleet: warning: robot r10 skipped: {r.errors[1]['error']}" in capsys.readouterr().err
    assert r.analysis["errors"][0]["session"] == "s00"
    table = csv_rows(tmp_path / "out" / "fleet.csv")
    assert [(t["robot"], t["status"]) for t in table] == [("r00", "ok")] * 3 + [("r09", "error"), ("r10", "error")]
    assert not (tmp_path / "out" / "r09" / "s00" / "model.toml").exists()


def test_a_killed_worker_loses_and_duplicates_nothing(fleet_run: fleet.FleetResult, sim_fleet: tuple[Path, dict[str, Any]], client: Any, tmp_path: Path) -> None:
    root, _ = sim_fleet
    pids = client.run(os.getpid)
    killed: list[int] = []

    def kill_a_busy_worker(row: dict[str, Any]) -> None:
        if killed:
            return
        busy = [w for w, keys in client.processing().items() if keys]
        if busy:
            killed.append(pids[busy[0]])
            os.kill(pids[busy[0]], signal.SIGKILL)

    r = fleet.calibrate_fleet(root, tmp_path / "out", client=client, diagnose="none", on_row=kill_a_busy_worker)
    assert killed, "no worker was busy when the first row came back"
    client.wait_for_workers(2, timeout=30)
    assert killed[0] not in client.run(os.getpid).values()  # the nanny started a new process
    keys = [(row["robot"], row["session"]) for row in r.rows]
    assert len(keys) == len(set(keys)) == 18 and not r.errors, r.errors
    for row in r.rows:  # the same seed gives the same bytes, whichever worker ran it, however often
        assert (tmp_path / "out" / row["model_file"]).read_bytes() == (fleet_run.out / row["model_file"]).read_bytes()
    assert len(csv_rows(tmp_path / "out" / "fleet.csv")) == 18
    assert not list((tmp_path / "out").rglob("*.tmp*"))


def test_ctrl_c_writes_the_rows_that_finished(sim_fleet: tuple[Path, dict[str, Any]], client: Any, tmp_path: Path) -> None:
    root, _ = sim_fleet
    seen: list[dict[str, Any]] = []

    def interrupt_after_three(row: dict[str, Any]) -> None:
        seen.append(row)
        if len(seen) == 3:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        fleet.calibrate_fleet(root, tmp_path / "out", client=client, diagnose="none", on_row=interrupt_after_three)
    table = csv_rows(tmp_path / "out" / "fleet.csv")
    assert sorted((t["robot"], t["session"]) for t in table) == sorted((s["robot"], s["session"]) for s in seen)
    assert "Interrupted" in (tmp_path / "out" / "fleet.html").read_text()


def test_trend_and_robust_z() -> None:
    t = fleet.trend([0, 1, 2], [1.0, 0.0, -1.0], [0.1, 0.1, 0.1])
    assert t is not None and t["slope"] == pytest.approx(-1.0) and t["slope_se"] == pytest.approx(0.1 / 2**0.5)
    assert fleet.trend([0], [1.0], [None]) is None
    z = fleet.robust_z([0.0, 1.0, -1.0, 0.5, 10.0])
    # median 0.5, absolute deviations (0.5, 0.5, 1.5, 0, 9.5): MAD 0.5
    assert z == pytest.approx([-0.6745, 0.6745, -2.0235, 0.0, 0.6745 * 9.5 / 0.5])
    assert fleet.robust_z([1.0, 1.0, 1.0, 5.0]) == [0.0] * 4  # MAD 0 and no floor: no outliers
    assert fleet.robust_z([1.0, 1.0, 1.0, 5.0], floor=0.5)[3] == pytest.approx(0.6745 * 4 / 0.5)


def test_fleet_command(sim_fleet: tuple[Path, dict[str, Any]], tmp_path: Path) -> None:
    root, _ = sim_fleet
    small = tmp_path / "fleet"
    for robot in ("r00", "r03"):
        shutil.copytree(root / robot / "s00", small / robot / "s00")
    shutil.copy(root / "robot.toml", small / "robot.toml")
    r = subprocess.run([*omnical_command(), "fleet", str(small), "--out", str(tmp_path / "out"), "--workers", "1", "--quiet"],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    assert r.stdout.startswith("2 of 2 robot-sessions calibrated")
    assert len(csv_rows(tmp_path / "out" / "fleet.csv")) == 2
    missing = subprocess.run([*omnical_command(), "fleet", str(tmp_path / "nowhere"), "--out", str(tmp_path / "o2")], capture_output=True, text=True)
    assert missing.returncode == 2 and "nowhere" in missing.stderr and "does not exist" in missing.stderr
    help_ = subprocess.run([*omnical_command(), "--help"], capture_output=True, text=True)
    assert "fleet" in help_.stdout


def test_simulate_fleet_command(tmp_path: Path) -> None:
    r = subprocess.run([*omnical_command(), "simulate", "--fleet", "4", "--sessions", "2", "--out", str(tmp_path / "f")],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    truth = json.loads((tmp_path / "f" / "truth.json").read_text())
    assert sorted(truth["degrading"]) == ["r01", "r02"] and len(fleet.find_sessions(tmp_path / "f")) == 8
    # A folder that holds a fleet already is refused (its sessions would mix with the new ones) unless
    # --force, which replaces it whole: the library's rule and words, as `omnical simulate --out`'s.
    smaller = [*omnical_command(), "simulate", "--fleet", "3", "--sessions", "1", "--out", str(tmp_path / "f")]
    again = subprocess.run(smaller, capture_output=True, text=True)
    assert again.returncode == 2 and again.stderr == (
        f"error: --out {tmp_path / 'f'}: the folder already holds files (r00, r01, r02, …); give --force to "
        "replace it whole, or another --out\n"), again.stderr
    forced = subprocess.run([*smaller, "--force"], capture_output=True, text=True)
    assert forced.returncode == 0, forced.stderr
    assert len(fleet.find_sessions(tmp_path / "f")) == 3 and sorted(p.name for p in tmp_path.iterdir()) == ["f"]


def test_the_fleet_never_writes_among_its_inputs(sim_fleet: tuple[Path, dict[str, Any]], client: Any, tmp_path: Path) -> None:
    """The library's output-folder rule (issue 47 item 6), as every omnical command follows it: a result
    folder that holds or lies inside the fleet folder the run reads is refused before any work, with the
    library's words (``out=`` from Python, ``--out`` from the command line), and nothing is written or
    deleted."""
    root, _ = sim_fleet
    small = tmp_path / "fleet"
    shutil.copytree(root / "r00" / "s00", small / "r00" / "s00")
    shutil.copy(root / "robot.toml", small / "robot.toml")

    def snapshot() -> dict[str, bytes]:
        return {str(p.relative_to(tmp_path)): p.read_bytes() for p in sorted(tmp_path.rglob("*")) if p.is_file()}

    before = snapshot()
    for out, relation in ((small, "holds"), (small / "out", "is inside"), (small / "r00" / "s00", "is inside"),
                          (tmp_path, "holds")):
        with pytest.raises(ValueError) as e:
            fleet.calibrate_fleet(small, out, client=client, diagnose="none")
        assert str(e.value) == (
            f"out= {out}: this folder {relation} the data {small}, which this command reads; give out= a folder "
            "apart from its inputs (force=True never replaces an input)")
    r = subprocess.run([*omnical_command(), "fleet", str(small), "--out", str(small / "out"), "--quiet"],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 2 and r.stderr == (
        f"error: --out {small / 'out'}: this folder is inside the data {small}, which this command reads; give "
        "--out a folder apart from its inputs (--force never replaces an input)\n"), r.stderr
    assert snapshot() == before and sorted(p.name for p in tmp_path.iterdir()) == ["fleet"]


def test_simulate_fleet_claims_its_folder_by_the_librarys_rule(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """simulate_fleet's folder: new or empty unless force=True, which replaces it whole, but never a folder
    that holds the working directory; each refusal before any work, with the library's words, nothing
    deleted."""
    out = tmp_path / "f"
    fleet.simulate_fleet(out, n_robots=1, n_sessions=1, n_wearing=0, n_lagging=0, duration_s=0.5)
    files = {str(p.relative_to(out)): p.read_bytes() for p in out.rglob("*") if p.is_file()}
    with pytest.raises(FileExistsError) as e:
        fleet.simulate_fleet(out, n_robots=1, n_sessions=1, n_wearing=0, n_lagging=0, duration_s=0.5)
    assert str(e.value) == (f"out= {out}: the folder already holds files (r00, robot.toml, truth.json); give "
                            "force=True to replace it whole, or another out=")
    monkeypatch.chdir(out / "r00")
    with pytest.raises(ValueError) as e:
        fleet.simulate_fleet(out, n_robots=1, n_sessions=1, n_wearing=0, n_lagging=0, duration_s=0.5, force=True)
    assert str(e.value) == f"out= {out}: force=True will not replace a folder that holds the working directory"
    assert {str(p.relative_to(out)): p.read_bytes() for p in out.rglob("*") if p.is_file()} == files
    assert sorted(p.name for p in tmp_path.iterdir()) == ["f"]


def test_a_lidar_session_is_diagnosed_on_its_lidar(tmp_path: Path) -> None:
    """`-- --gt-scans /scan` reaches the diagnosis too: the session (a hidden 60 ms wheel-clock lag, a lidar
    0.2 m ahead at 5°) is diagnosed on the lidar's windows, as `omnical diagnose --gt-scans /scan` would,
    not on the bags' motion-capture topic."""
    import omnical

    truth = omnical.Model.paper().with_effect("time_offset", tau_s=0.06)
    omnical.simulate(truth, runs_per_command=1, duration_s=4.0, seed=3, out=tmp_path / "fleet" / "r00" / "s00",
                     lidar="room", lidar_mount=(0.2, 0.0, 5.0))
    session = fleet.find_sessions(tmp_path / "fleet")[0]
    extra = ["--gt-scans", "/scan"]
    task = {**vars(session), "out": str(tmp_path / "out"), "preset": "default", "seed": 0, "model": "ik",
            "extra": extra, "diagnose": True}
    row = fleet.calibrate_session(task)
    assert row["status"] == "ok" and "diagnose_error" not in row, row
    model = str(tmp_path / "out" / row["model_file"])
    on_lidar = omnical._omnical.diagnose_files(["--model", model, session.path, "--robot", str(session.robot_toml), *extra])
    on_mocap = omnical._omnical.diagnose_files(["--model", model, session.path, "--robot", str(session.robot_toml)])
    assert row["verdict"] == on_lidar["verdict"] == "time_offset"
    assert row["verdict_text"] == on_lidar["verdict_text"] != on_mocap["verdict_text"]
    assert row["time_offset.tau_s"] == pytest.approx(0.06, abs=0.005)
