"""The fleet run: one Dask task per robot-session (a local cluster or any scheduler), the rows collected as
they finish (Ctrl-C keeps them), a second wave diagnosing the sessions that are off, then the fleet view."""

from __future__ import annotations

import logging
import os
import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Iterable, Optional, Sequence

from .. import _omnical
from ._analysis import OUTLIER_Z, _median, analyse, robust_z
from ._sessions import MODEL_FILE, PathLike, Session, _no_session_row, fleet_inputs, find_sessions, robots_without_sessions
from ._task import calibrate_session
from ._view import write_fleet_view

DIAGNOSE_COST_RATIO = 1.5
"""``diagnose="auto"``: diagnose a session whose fitted path objective exceeds this multiple of the fleet's
median, or whose robust z-score exceeds :data:`OUTLIER_Z`."""


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

    ``out`` is created when missing and may already hold files (a run's files replace the same names); it
    is refused (``ValueError``) when it holds or lies inside ``fleet_dir``, as every omnical command refuses
    a result folder among its inputs.

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
    out = Path(out)
    # The library's rule for a folder of fixed file names (`export --robot-config`'s): never one that holds
    # or lies inside the fleet folder it reads; created when missing; files already in it stay.
    _omnical._prepare_dir(out, flag="out=", inputs=fleet_inputs(fleet_dir))
    empty = [_no_session_row(fleet_dir, robot) for robot in robots_without_sessions(fleet_dir)]
    for row in empty:
        print(f"omnical fleet: warning: robot {row['robot']} skipped: {row['error']}", file=sys.stderr)
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
    """Removes the temporary model files of workers killed while writing (the library's atomic writes'
    ``.model.toml.tmp-<pid>``; the task ran again and renamed its own), once every task has finished."""
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
