"""One robot-session on a Dask worker: train it as ``omnical train`` does (the same Rust code path, so the
model file is byte-identical), diagnose it when asked, and return one small row of the fleet table."""

from __future__ import annotations

import math
import os
import re
import time
from typing import Any, Optional, Sequence

from .. import _omnical
from ._sessions import MODEL_FILE, Session

_TASK_KEYS = ("robot", "session", "path")


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
