"""Fleet scale: calibrate every robot-session of a fleet on Dask, and the fleet view.

A fleet is a folder ``FLEET_DIR/<robot_id>/<session>/`` of recordings (one robot on one occasion), with a
``robot.toml`` per robot folder or one for the whole fleet (a session folder's own wins, then the robot's,
then the fleet's). Each robot-session is one Dask task that reads its recordings from their path on the
worker (nothing large is shipped), trains exactly as ``omnical train SESSION --robot ROBOT_TOML --seed SEED
--out OUT/<robot>/<session>/model.toml`` (the same Rust code path, so the model file is byte-identical)
and returns one small row::

    from omnical.fleet import calibrate_fleet
    result = calibrate_fleet("fleet/", "fleet-out/", n_workers=2, seed=0)   # local cluster of 2 processes
    result = calibrate_fleet("fleet/", "fleet-out/", scheduler="tcp://10.0.0.5:8786")   # any Dask cluster
    print(result.rows[0]["cost_fitted"], result.flagged)

Outputs: ``OUT/<robot>/<session>/model.toml``, ``OUT/fleet.csv`` (one row per robot-session; also
``fleet.parquet`` when pyarrow is importable) and ``OUT/fleet.html`` (distributions across robots, robust
outliers, per-robot trends over sessions, diagnosed effects).

Faults: a session whose recordings do not load or fit gets its error in its row and the others finish; a
worker process that dies is replaced and its task runs again elsewhere (tasks are idempotent: the same
seed gives the same bytes, and files are written atomically, so nothing is lost or duplicated); Ctrl-C
writes the rows that finished and raises ``KeyboardInterrupt``.

Needs ``dask[distributed]`` (``pip install "omnical[fleet]"``); the rest of omnical does not.
"""

from __future__ import annotations

import csv
import logging
import math
import os
import re
import shutil
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Iterable, Optional, Sequence, Union

from . import _omnical

PathLike = Union[str, "os.PathLike[str]"]

ROBOT_FILE = "robot.toml"
"""The robot description's file name, looked up in a session, its robot and the fleet folder."""
MODEL_FILE = "model.toml"
"""Each robot-session's model file: ``OUT/<robot>/<session>/model.toml``."""
OUTLIER_Z = 3.5
"""Robust z-score (median / MAD, Iglewicz and Hoaglin) above which a robot is an outlier."""
TREND_T = 3.0
"""A trend is flagged when its slope is this many standard errors from zero ..."""
MIN_RADIUS_SLOPE_PCT = 0.3
"""... and, for a wheel's effective radius, at least this large [% of design per session]."""
MIN_EFFECT_SLOPE_REL = 0.1
"""... and, for an effect's parameter, at least this fraction of its largest |value| per session."""
DIAGNOSE_COST_RATIO = 1.5
"""``diagnose="auto"``: diagnose a session whose fitted path objective exceeds this multiple of the fleet's
median, or whose robust z-score exceeds :data:`OUTLIER_Z`."""

_TASK_KEYS = ("robot", "session", "path")


@dataclass
class Session:
    """One robot-session: its recordings' folder and the robot description used for it.

    >>> Session("r00", "s00", "fleet/r00/s00", "fleet/robot.toml").session
    's00'
    """

    robot: str
    session: str
    path: str
    robot_toml: Optional[str]


@dataclass
class FleetResult:
    """What :func:`calibrate_fleet` produced.

    >>> rows = [{"robot": "r00", "session": "s00", "status": "ok"}, {"robot": "r01", "session": "s00", "status": "error"}]
    >>> result = FleetResult(rows, Path("fleet-out"), [], {"flagged": ["r00"]})
    >>> result.flagged, [r["robot"] for r in result.errors]
    (['r00'], ['r01'])
    """

    rows: list[dict[str, Any]]
    """One per robot-session, ordered by robot, then session start time (then name)."""
    out: Path
    """The output folder."""
    files: list[Path]
    """The fleet table(s) and report written."""
    analysis: dict[str, Any]
    """Outliers, trends, diagnosed effects and the flagged robots (see :func:`analyse`)."""
    interrupted: bool = False
    """Ctrl-C stopped the run; ``rows`` holds the sessions that finished."""
    seconds: float = 0.0
    """Wall time [s]."""

    @property
    def flagged(self) -> list[str]:
        """Robots with an outlier, a trend or a diagnosed effect."""
        return list(self.analysis.get("flagged", []))

    @property
    def errors(self) -> list[dict[str, Any]]:
        """Rows of sessions that failed (``error`` says why)."""
        return [r for r in self.rows if r.get("status") != "ok"]


# ---------------------------------------------------------------------------------------------- discovery


def find_sessions(fleet_dir: PathLike) -> list[Session]:
    """The robot-sessions of a fleet folder, by robot and session name (hidden folders skipped).

    Raises ``FileNotFoundError`` when ``fleet_dir`` is not a folder and ``ValueError`` when it holds no
    session folder.

    >>> import tempfile
    >>> fleet = Path(tempfile.mkdtemp())
    >>> for d in ("r00/s00", "r00/s01", "r01/s00"):
    ...     (fleet / d).mkdir(parents=True)
    >>> [(s.robot, s.session, s.robot_toml) for s in find_sessions(fleet)]
    [('r00', 's00', None), ('r00', 's01', None), ('r01', 's00', None)]
    """
    root = Path(fleet_dir)
    if not root.is_dir():
        raise FileNotFoundError(f"fleet folder {root} does not exist or is not a folder")
    fleet_robot = root / ROBOT_FILE
    sessions = []
    for robot_dir in sorted(p for p in root.iterdir() if p.is_dir() and not p.name.startswith(".")):
        robot_file = robot_dir / ROBOT_FILE
        for session_dir in sorted(p for p in robot_dir.iterdir() if p.is_dir() and not p.name.startswith(".")):
            own = session_dir / ROBOT_FILE
            chosen = next((f for f in (own, robot_file, fleet_robot) if f.is_file()), None)
            sessions.append(
                Session(robot_dir.name, session_dir.name, str(session_dir), str(chosen) if chosen else None)
            )
    if not sessions:
        raise ValueError(f"fleet folder {root} has no session folders (expected FLEET_DIR/<robot>/<session>/)")
    return sessions


def robots_without_sessions(fleet_dir: PathLike) -> list[str]:
    """The robot folders of a fleet folder that hold no session folder (recordings put straight into the
    robot's folder, say), by name; :func:`calibrate_fleet` gives each a row with the reason.

    >>> import tempfile
    >>> fleet = Path(tempfile.mkdtemp())
    >>> for d in ("r00/s00", "r01"):
    ...     (fleet / d).mkdir(parents=True)
    >>> robots_without_sessions(fleet)
    ['r01']
    """
    root = Path(fleet_dir)
    return [
        p.name
        for p in sorted(root.iterdir())
        if p.is_dir() and not p.name.startswith(".") and not any(s.is_dir() and not s.name.startswith(".") for s in p.iterdir())
    ]


def _no_session_row(fleet_dir: PathLike, robot: str) -> dict[str, Any]:
    """The fleet table's row of a robot folder without sessions: status ``error`` and why."""
    error = f"{Path(fleet_dir) / robot} holds no session folder: its recordings go in FLEET_DIR/{robot}/<session>/"
    return {"robot": robot, "session": "", "status": "error", "error": error}


# ----------------------------------------------------------------------------------------- one task


def train_args(session: Session, model_path: str, *, preset: str, seed: int, model: str, extra: Sequence[str]) -> list[str]:
    """The arguments of ``omnical train`` that a task runs for ``session`` (also the command to reproduce
    it: ``omnical train ARGS...``).

    >>> train_args(Session("r00", "s00", "fleet/r00/s00", None), "out/model.toml", preset="default", seed=0,
    ...            model="ik", extra=["--effect", "time_offset"])  # doctest: +NORMALIZE_WHITESPACE
    ['fleet/r00/s00', '--preset', 'default', '--seed', '0', '--model', 'ik', '--effect', 'time_offset',
     '--out', 'out/model.toml']
    """
    args = [session.path, "--preset", preset, "--seed", str(seed), "--model", model]
    if session.robot_toml:
        args += ["--robot", session.robot_toml]
    return [*args, *extra, "--out", model_path]


def calibrate_session(task: dict[str, Any]) -> dict[str, Any]:
    """One robot-session on a worker: train (writing the model file atomically) and, when ``task["diagnose"]``
    is true, diagnose (``"only"``: diagnose the model file a first task wrote). Never raises for bad data:
    the row's ``status`` is ``"error"`` and ``error`` holds the message. ``seconds``: the task's wall time.

    >>> import tempfile
    >>> fleet, out = Path(tempfile.mkdtemp()), tempfile.mkdtemp()
    >>> _ = simulate_fleet(fleet, n_robots=1, n_sessions=1, n_wearing=0, n_lagging=0, duration_s=1.0)
    >>> task = {**vars(find_sessions(fleet)[0]), "out": out, "preset": "default", "seed": 0, "model": "ik",
    ...         "extra": []}
    >>> row = calibrate_session(task)
    >>> row["status"], row["runs"], row["cost_fitted"] < row["cost_design"]
    ('ok', 36, True)
    """
    t0 = time.perf_counter()
    session = Session(**{k: task[k] for k in (*_TASK_KEYS, "robot_toml")})
    row: dict[str, Any] = {"robot": session.robot, "session": session.session, "status": "ok", "error": ""}
    model_path = os.path.join(task["out"], session.robot, session.session, MODEL_FILE)
    if task.get("diagnose") != "only":
        try:
            os.makedirs(os.path.dirname(model_path), exist_ok=True)
            args = train_args(
                session, model_path, preset=task["preset"], seed=task["seed"], model=task["model"], extra=task["extra"]
            )
            row.update(_row_from_training(_omnical.train_files(args)))
            row["model_file"] = os.path.relpath(model_path, task["out"])
        except Exception as e:  # a bad recording, a failed fit: reported in the row, the fleet goes on
            row["status"] = "error"
            row["error"] = f"{type(e).__name__}: {e}".strip()
        row["seconds"] = time.perf_counter() - t0
    if task.get("diagnose") and row["status"] == "ok":
        t1 = time.perf_counter()
        try:
            row.update(diagnose_session(session, model_path, task.get("extra", ())))
        except Exception as e:  # the fit stands; the row says why it has no diagnosis
            row["diagnose_error"] = f"{type(e).__name__}: {e}".strip()
        row["diagnose_seconds"] = time.perf_counter() - t1
    return row


def diagnose_session(session: Session, model_path: str, extra_train_args: Sequence[str] = ()) -> dict[str, Any]:
    """``omnical diagnose --model MODEL SESSION`` as row fields: verdict (an effect id or empty), its
    text, and the named effect's fitted parameters with standard errors. The runs are read as the session's
    training read them (``extra_train_args``' data options: ``--gt-scans /scan`` diagnoses on the lidar).

    >>> import tempfile
    >>> fleet = Path(tempfile.mkdtemp())
    >>> _ = simulate_fleet(fleet, n_robots=2, n_sessions=1, n_wearing=0, n_lagging=1, lag_per_session_s=0.06,
    ...                    duration_s=1.0)
    >>> row = diagnose_session(find_sessions(fleet)[0], "design")  # r00: the design but for its radii
    >>> row["diagnosed"], sorted(row)[:3]
    (True, ['diagnosed', 'verdict', 'verdict_text'])
    """
    args = ["--model", model_path, session.path]
    if session.robot_toml:
        args += ["--robot", session.robot_toml]
    reading = [session.path, *(["--robot", session.robot_toml] if session.robot_toml else []), *extra_train_args]
    d = _omnical.diagnose_files(args, train_args=reading)
    out: dict[str, Any] = {"diagnosed": True, "verdict": d.get("verdict") or "", "verdict_text": d.get("verdict_text", "")}
    named = next((c for c in d.get("ranking", []) if c.get("effect") == d.get("verdict")), None)
    for p in (named or {}).get("params", []):
        out[f"{d['verdict']}.{p['name']}"] = p.get("value")
        out[f"{d['verdict']}.{p['name']}_se"] = p.get("std_error")
    return out


_M_ENTRY = re.compile(r"^m([1-3])(\d+)$")


def _row_from_training(t: dict[str, Any]) -> dict[str, Any]:
    """Row fields from ``train_files``' result: costs, each parameter with its design value, deviation
    and standard error, and (for an ``ik`` model) each wheel's effective radius against the design."""
    s = t["summary"]
    row: dict[str, Any] = {
        "start_s": t.get("start_s"),
        "runs": t.get("runs"),
        "cost_design": s["cost_design"],
        "cost_fitted": s["cost_fitted"],
        "improvement_pct": s["improvement_pct"],
        "objective": s["objective"],
        "objective_design": s["objective_design"],
        "objective_fitted": s["objective_fitted"],
        "evaluations": s["evaluations"],
        "held": len(s.get("held_at_start", [])),
        "warnings": " | ".join([*t.get("warnings", []), *s.get("warnings", [])]),
    }
    se = {p["name"]: p.get("std_error") for p in s["identifiability"]["params"]}
    design = t["design"]
    for p in s["params"]:
        name, value = p["name"], p["value"]
        d = design.get(name)
        row[name] = value
        row[f"{name}_design"] = d
        row[f"{name}_dev_pct"] = 100.0 * (value - d) / abs(d) if d else None
        row[f"{name}_se"] = se.get(name)
    row.update(_wheel_scales(s["params"], design, se))
    return row


def _wheel_scales(params: list[dict[str, Any]], design: dict[str, float], se: dict[str, Any]) -> dict[str, Any]:
    """An ``ik`` matrix column is the wheel's radius times its geometry: the ratio of the fitted column's
    length to the design's is the wheel's effective radius against the design. Returns
    ``radius_<wheel>_pct`` (deviation, %) and its standard error (first order, entries taken as
    independent)."""
    cols: dict[int, list[tuple[float, float, Optional[float]]]] = {}
    for p in params:
        m = _M_ENTRY.match(p["name"])
        if m and p["name"] in design:
            cols.setdefault(int(m.group(2)), []).append((p["value"], design[p["name"]], se.get(p["name"])))
    out: dict[str, Any] = {}
    for j, entries in sorted(cols.items()):
        norm = math.sqrt(sum(v * v for v, _, _ in entries))
        dnorm = math.sqrt(sum(d * d for _, d, _ in entries))
        if norm == 0 or dnorm == 0:
            continue
        wheel = _wheel_letter(j - 1)
        out[f"radius_{wheel}_pct"] = 100.0 * (norm / dnorm - 1.0)
        ses = [s for _, _, s in entries if s is not None]
        if len(ses) == len(entries):
            var = sum((v / norm) ** 2 * s * s for (v, _, _), s in zip(entries, ses))
            out[f"radius_{wheel}_pct_se"] = 100.0 * math.sqrt(var) / dnorm
        else:
            out[f"radius_{wheel}_pct_se"] = None
    return out


def _wheel_letter(i: int) -> str:
    return "abcdefgh"[i] if i < 8 else f"w{i}"


# ---------------------------------------------------------------------------------------------- the run


def calibrate_fleet(
    fleet_dir: PathLike,
    out: PathLike,
    scheduler: Optional[str] = None,
    n_workers: int = 2,
    *,
    preset: str = "default",
    seed: int = 0,
    model: str = "ik",
    extra_train_args: Sequence[str] = (),
    diagnose: str = "auto",
    client: Any = None,
    progress: Optional[bool] = None,
    on_row: Optional[Callable[[dict[str, Any]], None]] = None,
) -> FleetResult:
    """Calibrate every robot-session of ``fleet_dir`` on Dask and write the fleet view into ``out``.

    Without ``scheduler`` (an address such as ``tcp://host:8786``) or ``client`` (a
    ``distributed.Client``), a ``LocalCluster`` of ``n_workers`` worker processes (one thread each) runs on
    this machine and is closed at the end. ``preset``, ``seed``, ``model`` and ``extra_train_args`` are
    ``omnical train``'s (every session is trained with the same ones). ``diagnose``: ``"all"`` diagnoses
    every session, ``"auto"`` (default) only those whose fitted path objective is off (above
    :data:`DIAGNOSE_COST_RATIO` times the fleet's median, or a robust outlier), ``"none"`` none.
    ``progress``: a progress bar on stderr (default: when stderr is a terminal). ``on_row(row)`` is called
    as each session finishes. Ctrl-C writes the rows that finished, then raises ``KeyboardInterrupt``.

    Starting a Dask cluster takes seconds, so this example is not run by the doctests (tests/test_fleet.py
    runs it on a simulated fleet):

    >>> result = calibrate_fleet("fleet/", "fleet-out/", n_workers=2, seed=0)  # doctest: +SKIP
    >>> result.rows[0]["cost_fitted"], result.flagged  # doctest: +SKIP
    (0.0123, ['r01', 'r02'])
    """
    if diagnose not in ("all", "auto", "none"):
        raise ValueError(f"diagnose must be 'all', 'auto' or 'none', got {diagnose!r}")
    t0 = time.perf_counter()
    sessions = find_sessions(fleet_dir)
    empty = [_no_session_row(fleet_dir, robot) for robot in robots_without_sessions(fleet_dir)]
    for row in empty:
        print(f"omnical fleet: warning: robot {row['robot']} skipped: {row['error']}", file=sys.stderr)
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    base = {"out": str(out.resolve()), "preset": preset, "seed": int(seed), "model": model, "extra": list(extra_train_args)}
    tasks = [{**vars(s), **base, "diagnose": diagnose == "all"} for s in sessions]
    show = sys.stderr.isatty() if progress is None else progress
    rows: list[dict[str, Any]] = list(empty)
    interrupted = False
    with _DaskClient(scheduler, n_workers, client) as c:
        try:
            _run_tasks(c, tasks, rows, "calibrating", show, on_row)
            if diagnose == "auto":
                _diagnose_off_sessions(c, tasks, rows, show, on_row)
            _wait_for_stragglers(c)
        except KeyboardInterrupt:
            interrupted = True
    if not interrupted:
        _remove_stale_temporaries(out, sessions)
    rows = order_sessions(rows)
    analysis = analyse(rows)
    files = write_fleet_view(rows, analysis, out, interrupted=interrupted)
    result = FleetResult(rows, out, files, analysis, interrupted, time.perf_counter() - t0)
    if interrupted:
        print(f"omnical fleet: interrupted (Ctrl-C): {len(rows)} finished robot-sessions written to {files[0]}", file=sys.stderr)
        raise KeyboardInterrupt
    return result


def _wait_for_stragglers(client: Any, timeout_s: float = 60.0) -> None:
    """Waits (at most ``timeout_s``) until no task this process submitted still runs on a worker: a result
    lost with a killed worker before its release reached the scheduler is computed again, and that task
    writes its model file (the same bytes) while the fleet would already be clearing temporaries."""
    mark = f"-{os.getpid()}-"
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        running = [k for keys in client.processing().values() for k in keys if str(k).startswith("omnical-") and mark in str(k)]
        if not running:
            return
        time.sleep(0.05)


def _remove_stale_temporaries(out: Path, sessions: Sequence[Session]) -> None:
    """Removes the temporary model files of workers killed while writing (``.model.toml.tmp-<pid>``; the
    task ran again and renamed its own), once every task has finished."""
    for s in sessions:
        for tmp in (out / s.robot / s.session).glob(f".{MODEL_FILE}.tmp-*"):
            tmp.unlink(missing_ok=True)


class _DaskClient:
    """The Dask client to use: the caller's, one connected to ``scheduler``, or a new local cluster of
    worker processes (closed on exit)."""

    def __init__(self, scheduler: Optional[str], n_workers: int, client: Any) -> None:
        self.scheduler, self.n_workers, self.given = scheduler, n_workers, client
        self.owned: list[Any] = []

    def __enter__(self) -> Any:
        if self.given is not None:
            return self.given
        try:
            from distributed import Client, LocalCluster
        except ImportError as e:  # pragma: no cover - depends on the environment
            raise ImportError('omnical.fleet needs Dask: pip install "omnical[fleet]"') from e
        if self.scheduler:
            c = Client(self.scheduler)
            self.owned.append(c)
            return c
        if self.n_workers < 1:
            raise ValueError(f"n_workers must be at least 1, got {self.n_workers}")
        # Each worker trains with rayon's threads; share the cores out instead of oversubscribing them (the
        # results do not depend on the thread count).
        threads = max(1, (os.cpu_count() or 1) // self.n_workers)
        cluster = LocalCluster(
            n_workers=self.n_workers,
            processes=True,
            threads_per_worker=1,
            dashboard_address=None,
            env={"RAYON_NUM_THREADS": str(threads)},
            # The workers' own log lines (a heartbeat cut short while the cluster closes) are noise here:
            # every task's outcome is in its row.
            silence_logs=logging.CRITICAL,
        )
        c = Client(cluster)
        self.owned += [c, cluster]
        return c

    def __exit__(self, *exc: Any) -> None:
        for o in self.owned:
            try:
                o.close()
            except Exception:  # closing after Ctrl-C or a lost scheduler: nothing left to save
                pass


def _run_tasks(
    client: Any,
    tasks: list[dict[str, Any]],
    rows: list[dict[str, Any]],
    what: str,
    show: bool,
    on_row: Optional[Callable[[dict[str, Any]], None]],
    replace: bool = False,
) -> None:
    """Submits one task per session and collects the rows as they finish (into ``rows``, so that Ctrl-C
    keeps what finished). A task whose workers kept dying (``KilledWorker``) becomes an error row."""
    from distributed import as_completed

    if not tasks:
        return
    futures = {}
    for t in tasks:
        key = f"omnical-{what}-{t['robot']}-{t['session']}-{os.getpid()}-{time.monotonic_ns()}"
        futures[client.submit(calibrate_session, t, key=key, pure=False, retries=1)] = t
    bar = _Progress(len(tasks), what, show)
    index = {(r["robot"], r["session"]): i for i, r in enumerate(rows)} if replace else {}
    try:
        for fut in as_completed(list(futures)):
            t = futures[fut]
            try:
                row = fut.result()
                # Its row is here: the scheduler may forget it. Held, a result lost with a worker that dies
                # later would be computed again, and that task would write its model file again after the
                # fleet's end (and its temporary file after they were cleared).
                fut.release()
            except Exception as e:  # KilledWorker, a lost connection: the session's row says so
                why = f"{type(e).__name__}: {e}"
                row = {"robot": t["robot"], "session": t["session"]}
                row.update({"diagnose_error": why} if replace else {"status": "error", "error": why})
            k = (row["robot"], row["session"])
            if k in index:
                rows[index[k]] = {**rows[index[k]], **row}
            else:
                rows.append(row)
            bar.update(row.get("status", "ok") != "ok")
            if on_row is not None:
                on_row(row)
    except KeyboardInterrupt:
        client.cancel(list(futures))
        raise
    finally:
        bar.close()


def _diagnose_off_sessions(
    client: Any,
    tasks: list[dict[str, Any]],
    rows: list[dict[str, Any]],
    show: bool,
    on_row: Optional[Callable[[dict[str, Any]], None]],
) -> None:
    """``diagnose="auto"``: a second wave over the sessions whose fitted path objective is off (see
    :data:`DIAGNOSE_COST_RATIO`), each diagnosing the model file its training wrote."""
    ok = [r for r in rows if r.get("status") == "ok" and r.get("objective_fitted") is not None]
    values = [r["objective_fitted"] for r in ok]
    if not values:
        return
    med = _median(values)
    z = robust_z(values)
    off = {(r["robot"], r["session"]) for r, zi in zip(ok, z) if r["objective_fitted"] > DIAGNOSE_COST_RATIO * med or zi > OUTLIER_Z}
    for r in ok:
        r["diagnosed"] = False
    again = [{**t, "diagnose": "only"} for t in tasks if (t["robot"], t["session"]) in off]
    _run_tasks(client, again, rows, "diagnosing", show, on_row, replace=True)


class _Progress:
    """A one-line progress bar over robot-sessions on stderr (no dependency)."""

    def __init__(self, total: int, what: str, show: bool) -> None:
        self.total, self.what, self.show = total, what, show
        self.done = self.failed = 0
        self.t0 = time.perf_counter()
        self._draw()

    def update(self, failed: bool) -> None:
        self.done += 1
        self.failed += failed
        self._draw()

    def _draw(self) -> None:
        if not self.show:
            return
        width = 30
        filled = width * self.done // max(self.total, 1)
        elapsed = time.perf_counter() - self.t0
        eta = elapsed / self.done * (self.total - self.done) if self.done else float("nan")
        fail = f", {self.failed} failed" if self.failed else ""
        sys.stderr.write(
            f"\r{self.what} [{'#' * filled}{'.' * (width - filled)}] {self.done}/{self.total} robot-sessions{fail}"
            f"  {elapsed:5.1f} s" + (f", ~{eta:.0f} s left" if self.done and self.done < self.total else "") + "   "
        )
        sys.stderr.flush()

    def close(self) -> None:
        if self.show:
            sys.stderr.write("\n")
            sys.stderr.flush()


def order_sessions(rows: Iterable[dict[str, Any]]) -> list[dict[str, Any]]:
    """Rows by robot, then by the session's start time (its recordings' earliest wheel stamp), then by
    session name (sessions whose recordings all start at 0 s, as simulated CSV runs do, keep name order);
    sets ``session_index`` (0, 1, ... per robot).

    >>> rows = order_sessions([{"robot": "r00", "session": "b", "start_s": 5.0},
    ...                        {"robot": "r00", "session": "a", "start_s": 9.0}])
    >>> [(r["session"], r["session_index"]) for r in rows]
    [('b', 0), ('a', 1)]
    """
    rows = list(rows)

    def key(r: dict[str, Any]) -> tuple[Any, ...]:
        start = r.get("start_s")
        return (r["robot"], start is None, start if start is not None else 0.0, r["session"])

    rows.sort(key=key)
    count: dict[str, int] = {}
    for r in rows:
        r["session_index"] = count.get(r["robot"], 0)
        count[r["robot"]] = r["session_index"] + 1
    return rows


# ------------------------------------------------------------------------------------------- statistics


def _median(values: Sequence[float]) -> float:
    v = sorted(values)
    n = len(v)
    return 0.0 if n == 0 else (v[n // 2] if n % 2 else 0.5 * (v[n // 2 - 1] + v[n // 2]))


def robust_z(values: Sequence[float], floor: float = 0.0) -> list[float]:
    """Robust z-scores 0.6745 (x - median) / MAD (Iglewicz and Hoaglin); ``floor`` bounds the MAD from
    below (e.g. by the values' typical standard error, so that a fleet of near-identical robots does not
    turn noise into outliers). All zeros when the MAD and the floor are 0.

    >>> [round(z, 2) for z in robust_z([1.0, 1.1, 0.9, 1.0, 3.0])]
    [0.0, 0.67, -0.67, 0.0, 13.49]
    """
    med = _median(values)
    mad = max(_median([abs(x - med) for x in values]), floor)
    if mad == 0:
        return [0.0 for _ in values]
    return [0.6745 * (x - med) / mad for x in values]


def trend(x: Sequence[float], y: Sequence[float], se: Sequence[Optional[float]]) -> Optional[dict[str, float]]:
    """Straight-line fit of ``y`` over ``x`` (weighted by 1/se² when every se is known): slope, its
    standard error (the larger of the one from the stated errors and the one from the scatter when there
    are more than 2 points), intercept. None for fewer than 2 points or one x.

    >>> t = trend([0, 1, 2], [1.0, 0.9, 0.8], [0.01, 0.01, 0.01])
    >>> round(t["slope"], 3), round(t["intercept"], 3)
    (-0.1, 1.0)
    """
    n = len(x)
    if n < 2 or len(set(x)) < 2:
        return None
    known = all(s is not None and s > 0 for s in se)
    w = [1.0 / (s * s) for s in se] if known else [1.0] * n  # type: ignore[operator]
    sw = sum(w)
    xm = sum(wi * xi for wi, xi in zip(w, x)) / sw
    ym = sum(wi * yi for wi, yi in zip(w, y)) / sw
    sxx = sum(wi * (xi - xm) ** 2 for wi, xi in zip(w, x))
    slope = sum(wi * (xi - xm) * (yi - ym) for wi, xi, yi in zip(w, x, y)) / sxx
    intercept = ym - slope * xm
    se_stated = math.sqrt(1.0 / sxx) if known else 0.0
    se_scatter = 0.0
    if n > 2:
        chi2 = sum(wi * (yi - intercept - slope * xi) ** 2 for wi, xi, yi in zip(w, x, y)) / (n - 2)
        se_scatter = math.sqrt(chi2 / sxx)
    return {"slope": slope, "slope_se": max(se_stated, se_scatter), "intercept": intercept, "n": float(n)}


def _quantities(rows: Sequence[dict[str, Any]]) -> list[str]:
    """Numeric per-session quantities to analyse: the wheels' effective radii, the fitted parameters and
    the diagnosed effects' parameters (each with a ``_se`` column)."""
    names: list[str] = []
    for r in rows:
        for k in r:
            if k.endswith("_se") and k[:-3] in r and k[:-3] not in names:
                names.append(k[:-3])
    radius = sorted(n for n in names if n.startswith("radius_"))
    return radius + [n for n in names if not n.startswith("radius_")]


def analyse(rows: Sequence[dict[str, Any]]) -> dict[str, Any]:
    """The fleet view's findings from the rows (ordered, see :func:`order_sessions`):

    - ``outliers``: per quantity, robots whose latest session is a robust outlier (|z| > :data:`OUTLIER_Z`);
    - ``trends``: per robot and quantity with 2+ sessions, the slope per session and its standard error;
      ``flagged`` trends are |slope| > :data:`TREND_T` standard errors and of a size that matters;
    - ``effects``: per robot, the sessions whose diagnosis names an effect;
    - ``flagged``: robots with any of the above, and ``reasons`` per robot in words.

    >>> rows = [{"robot": f"r{i}", "session": "s00", "status": "ok", "radius_a_pct": x, "radius_a_pct_se": 0.05}
    ...         for i, x in enumerate([0.1, -0.1, 0.0, 0.2, 4.0])]
    >>> analyse(order_sessions(rows))["flagged"]
    ['r4']
    """
    ok = [r for r in rows if r.get("status") == "ok"]
    quantities = _quantities(ok)
    robots = sorted({r["robot"] for r in ok})
    latest = {rb: [r for r in ok if r["robot"] == rb][-1] for rb in robots}
    outliers: dict[str, list[dict[str, Any]]] = {}
    for q in quantities:
        have = [(rb, latest[rb][q], latest[rb].get(f"{q}_se")) for rb in robots if latest[rb].get(q) is not None]
        if len(have) < 3:
            continue
        ses = [s for _, _, s in have if s is not None]
        z = robust_z([v for _, v, _ in have], floor=_median(ses) if ses else 0.0)
        found: list[dict[str, Any]] = [{"robot": rb, "value": v, "z": zi} for (rb, v, _), zi in zip(have, z) if abs(zi) > OUTLIER_Z]
        if found:
            outliers[q] = found
    trends: list[dict[str, Any]] = []
    for rb in robots:
        rs = [r for r in ok if r["robot"] == rb]
        for q in quantities:
            pts = [(r["session_index"], r[q], r.get(f"{q}_se")) for r in rs if r.get(q) is not None]
            t = trend([p[0] for p in pts], [p[1] for p in pts], [p[2] for p in pts])
            if t is None:
                continue
            largest = max(abs(p[1]) for p in pts)
            if q.startswith("radius_"):
                big = abs(t["slope"]) >= MIN_RADIUS_SLOPE_PCT
            elif "." in q:
                big = abs(t["slope"]) >= MIN_EFFECT_SLOPE_REL * largest
            else:
                big = False  # raw matrix entries: shown, the wheels' radii carry the verdict
            sig = t["slope_se"] == 0 or abs(t["slope"]) > TREND_T * t["slope_se"]
            trends.append({"robot": rb, "quantity": q, **t, "flagged": bool(big and sig), "sessions": len(pts)})
    effects: dict[str, list[dict[str, Any]]] = {}
    for r in ok:
        if r.get("verdict"):
            effects.setdefault(r["robot"], []).append({"session": r["session"], "effect": r["verdict"], "text": r.get("verdict_text", "")})
    reasons: dict[str, list[str]] = {}
    for q, found in outliers.items():
        for o in found:
            reasons.setdefault(o["robot"], []).append(f"{_label(q)} {_fmt(o['value'], q)} is an outlier (robust z {o['z']:+.1f})")
    for tr in trends:
        if tr["flagged"]:
            reasons.setdefault(tr["robot"], []).append(_trend_text(tr, with_robot=False))
    for rb, es in effects.items():
        names = sorted({e["effect"] for e in es})
        reasons.setdefault(rb, []).append(
            f"diagnosis names {', '.join(names)} in session(s) {', '.join(e['session'] for e in es)}"
        )
    return {
        "quantities": quantities,
        "robots": robots,
        "outliers": outliers,
        "trends": trends,
        "effects": effects,
        "reasons": reasons,
        "flagged": sorted(reasons),
        "errors": [{"robot": r["robot"], "session": r["session"], "error": r.get("error", "")} for r in rows if r.get("status") != "ok"],
    }


def _label(q: str) -> str:
    m = re.match(r"^radius_(\w+)_pct$", q)
    if m:
        return f"wheel {m.group(1)}: effective radius"
    return q


def _fmt(v: float, q: str) -> str:
    return f"{v:+.2f} %" if q.endswith("_pct") else f"{v:.4g}"


def _trend_text(t: dict[str, Any], with_robot: bool = True) -> str:
    """"robot r17, wheel b: effective radius -0.90 ± 0.05 % per session, wear"."""
    q = t["quantity"]
    who = f"robot {t['robot']}, " if with_robot else ""
    if q.startswith("radius_"):
        what = "wear" if t["slope"] < 0 else "growing"
        return f"{who}{_label(q)} {t['slope']:+.2f} ± {t['slope_se']:.2f} % per session, {what}"
    return f"{who}{q} {t['slope']:+.4g} ± {t['slope_se']:.2g} per session, drift"


# ------------------------------------------------------------------------------------------- the view


def _columns(rows: Sequence[dict[str, Any]]) -> list[str]:
    first = ["robot", "session", "session_index", "status", "error", "start_s", "runs", "seconds", "model_file"]
    cols = [c for c in first if any(c in r for r in rows)]
    for r in rows:
        for k in r:
            if k not in cols:
                cols.append(k)
    return cols


def _atomic_write(path: Path, write: Callable[[Any], None], mode: str = "w") -> None:
    """Writes through a temporary file in the same folder and renames it (never half written)."""
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    umask = os.umask(0)
    os.umask(umask)
    try:
        os.chmod(tmp, 0o666 & ~umask)  # as open() would create it (mkstemp makes it private)
        if "b" in mode:
            with os.fdopen(fd, "wb") as fb:
                write(fb)
        else:
            with os.fdopen(fd, "w", newline="", encoding="utf-8") as ft:
                write(ft)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


def write_table(rows: Sequence[dict[str, Any]], out: PathLike) -> list[Path]:
    """``OUT/fleet.csv`` (one row per robot-session, empty cells for missing values), and
    ``OUT/fleet.parquet`` when pyarrow is importable. Returns the files written.

    >>> import tempfile
    >>> out = Path(tempfile.mkdtemp())
    >>> _ = write_table([{"robot": "r00", "session": "s00", "cost_fitted": 0.01}], out)
    >>> (out / "fleet.csv").read_text().splitlines()[1]
    'r00,s00,0.01'
    """
    out = Path(out)
    cols = _columns(rows)

    def write_csv(f: Any) -> None:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(cols)
        for r in rows:
            w.writerow(["" if r.get(c) is None else (repr(r[c]) if isinstance(r[c], float) else r[c]) for c in cols])

    files = [out / "fleet.csv"]
    _atomic_write(files[0], write_csv)
    try:
        import pyarrow as pa  # type: ignore[import-not-found, unused-ignore]
        import pyarrow.parquet as pq  # type: ignore[import-not-found, unused-ignore]
    except ImportError:
        return files
    table = pa.Table.from_pylist([{c: r.get(c) for c in cols} for r in rows])
    path = out / "fleet.parquet"
    _atomic_write(path, lambda f: pq.write_table(table, f), mode="wb")
    return files + [path]


def write_fleet_view(rows: Sequence[dict[str, Any]], analysis: dict[str, Any], out: PathLike, *, interrupted: bool = False) -> list[Path]:
    """The table (:func:`write_table`) and ``OUT/fleet.html``. Returns the files written.

    >>> import tempfile
    >>> rows = [{"robot": "r00", "session": "s00", "status": "ok", "cost_fitted": 0.01}]
    >>> [p.name for p in write_fleet_view(rows, analyse(rows), tempfile.mkdtemp())][-1]
    'fleet.html'
    """
    from . import _fleet_html

    out = Path(out)
    files = write_table(rows, out)
    page = _fleet_html.page(rows, analysis, interrupted=interrupted)
    path = out / "fleet.html"
    _atomic_write(path, lambda f: f.write(page))
    return files + [path]


# ----------------------------------------------------------------------------------- a simulated fleet


@dataclass
class _SimRobot:
    robot: str
    radius: dict[str, float]
    wear: dict[str, float] = field(default_factory=dict)
    lag_per_session_s: float = 0.0


def simulate_fleet(
    out: PathLike,
    n_robots: int = 6,
    n_sessions: int = 3,
    *,
    seed: int = 0,
    spread: float = 0.004,
    wear_per_session: float = -0.01,
    lag_per_session_s: float = 0.03,
    n_wearing: int = 1,
    n_lagging: int = 1,
    duration_s: float = 2.0,
    force: bool = False,
) -> dict[str, Any]:
    """Write a simulated fleet ``OUT/<robot>/<session>/*.csv`` (the paper's APR-02 flower benchmark, one
    run of ``duration_s`` per command) with ``OUT/robot.toml`` and ``OUT/truth.json``, and return the truth.

    Every robot is the design but for its wheels' radii, each off by a random fraction (normal, sd
    ``spread``, the same in every session); the
    first ``n_wearing`` robots after ``r00`` lose ``wear_per_session`` of wheel b's radius per session,
    the next ``n_lagging`` have a wheel-clock lag growing by ``lag_per_session_s`` per session (0 in the
    first). ``truth["degrading"]`` names them. ``out`` must be new or empty (runs left in it would join the
    fleet) unless ``force``, which replaces it whole; it is written beside and renamed into place at the end.

    >>> import tempfile
    >>> out = Path(tempfile.mkdtemp())
    >>> truth = simulate_fleet(out, n_robots=3, n_sessions=1, duration_s=0.5)
    >>> truth["degrading"]["r02"], len(list((out / "r00" / "s00").glob("*.csv")))
    (['clock lag +30 ms per session (time_offset)'], 36)
    """
    import random

    if n_robots < 1 or n_sessions < 1:
        raise ValueError("simulate_fleet needs at least one robot and one session")
    if 1 + n_wearing + n_lagging > n_robots and (n_wearing or n_lagging):
        raise ValueError(f"{n_robots} robots are too few for {n_wearing} wearing and {n_lagging} lagging ones after r00")
    rng = random.Random(seed)
    final = Path(out)
    _check_new_folder(final, force)
    out = final.parent / f".{final.name}.omnical-tmp-{os.getpid()}"
    shutil.rmtree(out, ignore_errors=True)
    out.mkdir(parents=True)
    try:
        truth = _simulate_fleet_into(out, rng, n_robots, n_sessions, spread, wear_per_session, lag_per_session_s,
                                     n_wearing, n_lagging, duration_s)
        _swap_in(out, final)
    finally:
        shutil.rmtree(out, ignore_errors=True)
    return truth


def _check_new_folder(folder: Path, force: bool) -> None:
    """Refuses an output folder that already holds files, unless ``force`` (as ``--force`` does)."""
    if folder.exists() and not folder.is_dir():
        raise FileExistsError(f"{folder}: this is a file, not a folder")
    entries = sorted(p.name for p in folder.iterdir()) if folder.is_dir() else []
    if entries and not force:
        shown = ", ".join(entries[:3]) + (", …" if len(entries) > 3 else "")
        raise FileExistsError(
            f"{folder}: the folder already holds files ({shown}); give --force (force=True) to replace it whole, "
            "or another folder"
        )
    if entries and Path.cwd().resolve().is_relative_to(folder.resolve()):
        raise ValueError(f"{folder}: --force will not replace a folder that holds the working directory")


def _swap_in(staging: Path, target: Path) -> None:
    """Renames ``staging`` to ``target``, replacing an existing ``target`` folder whole."""
    if not target.exists():
        os.replace(staging, target)
        return
    old = target.parent / f".{target.name}.omnical-old-{os.getpid()}"
    os.replace(target, old)
    try:
        os.replace(staging, target)
    except BaseException:
        os.replace(old, target)
        raise
    shutil.rmtree(old)


def _simulate_fleet_into(
    out: Path,
    rng: Any,
    n_robots: int,
    n_sessions: int,
    spread: float,
    wear_per_session: float,
    lag_per_session_s: float,
    n_wearing: int,
    n_lagging: int,
    duration_s: float,
) -> dict[str, Any]:
    """:func:`simulate_fleet`'s work, into the folder ``out``."""
    import json

    robots = []
    for i in range(n_robots):
        r = _SimRobot(f"r{i:02d}", {w: rng.gauss(0.0, spread) for w in "abc"})
        if 1 <= i <= n_wearing:
            r.wear = {"b": wear_per_session}
        elif n_wearing < i <= n_wearing + n_lagging:
            r.lag_per_session_s = lag_per_session_s
        robots.append(r)
    truth: dict[str, Any] = {"robots": {}, "degrading": {}}
    for i, r in enumerate(robots):
        sessions = {}
        for s in range(n_sessions):
            radius = {w: e + s * r.wear.get(w, 0.0) for w, e in r.radius.items()}
            lag = s * r.lag_per_session_s
            effects = [f"wheel_radius:{w}={e!r}" for w, e in radius.items()]
            if lag:
                effects.append(f"time_offset={lag!r}")
            name = f"s{s:02d}"
            _simulate_session(out / r.robot / name, 1000 * (i + 1) + s, effects, duration_s)
            sessions[name] = {"wheel_radius": radius, "time_offset_s": lag}
        truth["robots"][r.robot] = sessions
        if r.wear:
            truth["degrading"][r.robot] = [f"wheel {w}: radius {100 * v:+.1f} % per session (wear)" for w, v in r.wear.items()]
        if r.lag_per_session_s:
            truth["degrading"][r.robot] = [f"clock lag +{1000 * r.lag_per_session_s:.0f} ms per session (time_offset)"]
    shutil.copyfile(out / robots[0].robot / "s00" / ".sim" / "train" / ROBOT_FILE, out / ROBOT_FILE)
    for r in robots:
        for s in range(n_sessions):
            shutil.rmtree(out / r.robot / f"s{s:02d}" / ".sim")
    text = json.dumps(truth, indent=2, sort_keys=True) + "\n"
    _atomic_write(out / "truth.json", lambda f: f.write(text))
    return truth


def _simulate_session(session_dir: Path, seed: int, effects: list[str], duration_s: float) -> None:
    """``omnical simulate`` into ``session_dir/.sim`` (its summary lines silenced) and its training runs
    moved up into the session (its robot.toml stays in ``.sim``)."""
    sim = session_dir / ".sim"
    args = ["omnical", "simulate", "--out", str(sim), "--seed", str(seed), "--format", "csv", "--quiet", "--truth", "design"]
    args += ["--runs-per-command", "1", "--duration", repr(duration_s)]
    for e in effects:
        args += ["--effect", e]
    sys.stdout.flush()
    saved = os.dup(1)
    try:
        with open(os.devnull, "w") as null:
            os.dup2(null.fileno(), 1)
            status = _omnical.cli_main(args)
    finally:
        os.dup2(saved, 1)
        os.close(saved)
    if status != 0:
        raise RuntimeError(f"omnical simulate failed (status {status}) for {session_dir}")
    for f in sorted((sim / "train").iterdir()):
        if f.name != ROBOT_FILE:
            shutil.move(str(f), str(session_dir / f.name))


# ---------------------------------------------------------------------------------------- the command


def main(argv: Sequence[str]) -> int:
    """``omnical fleet ...`` (``argv`` after the subcommand); returns the exit status (0, 2 on bad
    input, 130 after Ctrl-C).

    >>> main(["no-such-fleet/", "--out", "fleet-out/"])  # prints "error: fleet folder ... does not exist"
    2
    """
    # The options are declared once, in the native command line's parser (`omnical fleet --help`).
    a, message, status = _omnical._fleet_args(list(argv))
    if a is None:
        print(message, end="", file=sys.stdout if status == 0 else sys.stderr)
        return status
    try:
        r = calibrate_fleet(
            a["fleet_dir"],
            a["out"],
            scheduler=a["scheduler"],
            n_workers=a["workers"],
            preset=a["preset"],
            seed=a["seed"],
            model=a["model"],
            extra_train_args=a["train_args"],
            diagnose=a["diagnose"],
            progress=False if a["quiet"] else None,
        )
    except KeyboardInterrupt:
        return 130
    except (OSError, ValueError, ImportError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    ok = len(r.rows) - len(r.errors)
    print(f"{ok} of {len(r.rows)} robot-sessions calibrated in {r.seconds:.1f} s; written to {r.out}")
    for bad in r.errors:
        print(f"  error: {bad['robot']}/{bad['session']}: {bad['error']}")
    for rb in r.flagged:
        for why in r.analysis["reasons"][rb]:
            print(f"  robot {rb}: {why}")
    for f in r.files:
        print(f"  {f}")
    return 0
