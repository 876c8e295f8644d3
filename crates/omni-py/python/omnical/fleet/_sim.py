"""A simulated fleet (``omnical simulate --fleet``): every robot the design but for its wheels' radii, some
wearing a wheel or lagging a clock more each session, written with ``omnical simulate`` per session."""

from __future__ import annotations

import json
import os
import random
import shutil
import sys
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .. import _omnical
from ._sessions import ROBOT_FILE, PathLike


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
    first). ``truth["degrading"]`` names them. ``out`` is claimed as ``omnical simulate --out`` claims its
    folder (the library's rule): it must be new or empty (runs left in it would join the fleet) unless
    ``force``, which replaces it whole, and it is written beside and renamed into place at the end, so a
    failure leaves it as it was.

    >>> import tempfile
    >>> out = Path(tempfile.mkdtemp())
    >>> truth = simulate_fleet(out, n_robots=3, n_sessions=1, duration_s=0.5)
    >>> truth["degrading"]["r02"], len(list((out / "r00" / "s00").glob("*.csv")))
    (['clock lag +30 ms per session (time_offset)'], 36)
    """
    if n_robots < 1 or n_sessions < 1:
        raise ValueError("simulate_fleet needs at least one robot and one session")
    if 1 + n_wearing + n_lagging > n_robots and (n_wearing or n_lagging):
        raise ValueError(f"{n_robots} robots are too few for {n_wearing} wearing and {n_lagging} lagging ones after r00")
    rng = random.Random(seed)
    with _omnical._OutDir.claim(out, flag="out=", force=force) as claimed:
        truth = _simulate_fleet_into(Path(claimed.path), rng, n_robots, n_sessions, spread, wear_per_session,
                                     lag_per_session_s, n_wearing, n_lagging, duration_s)
        claimed.commit()
    return truth


def _simulate_fleet_into(
    out: Path,
    rng: random.Random,
    n_robots: int,
    n_sessions: int,
    spread: float,
    wear_per_session: float,
    lag_per_session_s: float,
    n_wearing: int,
    n_lagging: int,
    duration_s: float,
) -> dict[str, Any]:
    """:func:`simulate_fleet`'s work, into the (staging) folder ``out``."""
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
    (out / "truth.json").write_text(json.dumps(truth, indent=2, sort_keys=True) + "\n", encoding="utf-8")
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
