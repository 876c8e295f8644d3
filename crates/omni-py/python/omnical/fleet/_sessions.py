"""Finding a fleet's robot-sessions: ``FLEET_DIR/<robot>/<session>/`` and the robot description each uses
(a session folder's own ``robot.toml`` wins, then the robot's, then the fleet's)."""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Optional, Union

PathLike = Union[str, "os.PathLike[str]"]

ROBOT_FILE = "robot.toml"
"""The robot description's file name, looked up in a session, its robot and the fleet folder."""
MODEL_FILE = "model.toml"
"""Each robot-session's model file: ``OUT/<robot>/<session>/model.toml``."""


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


def fleet_inputs(fleet_dir: PathLike) -> list[tuple[str, str]]:
    """What a fleet run reads, for the library's output-folder rules (``_omnical._prepare_dir``): the fleet
    folder (its recordings and robot files), which no result folder may hold or lie inside."""
    return [("the data", os.fspath(fleet_dir))]
