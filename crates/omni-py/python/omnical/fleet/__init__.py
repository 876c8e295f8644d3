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

The package's modules, by what they do: ``_sessions`` (finding the robot-sessions), ``_task`` (one
robot-session on a worker), ``_run`` (the Dask run and its progress), ``_analysis`` (robust z-scores,
trends, findings), ``_view`` and ``_html`` (the fleet table and report), ``_sim`` (a simulated fleet) and
``_command`` (``omnical fleet``). Result folders and files follow the library's rules, as every omnical
command's do (``_omnical._OutDir``, ``_omnical._prepare_dir``, ``_omnical._write_atomic``): the output
folder may neither hold nor lie inside the fleet folder it reads, and files are written atomically.
"""

from ._analysis import (
    MIN_EFFECT_SLOPE_REL,
    MIN_RADIUS_SLOPE_PCT,
    OUTLIER_Z,
    TREND_T,
    analyse,
    robust_z,
    trend,
)
from ._command import main
from ._run import DIAGNOSE_COST_RATIO, FleetResult, calibrate_fleet, order_sessions
from ._sessions import MODEL_FILE, ROBOT_FILE, PathLike, Session, find_sessions, robots_without_sessions
from ._sim import simulate_fleet
from ._task import calibrate_session, diagnose_session, train_args
from ._view import write_fleet_view, write_table

__all__ = [
    "DIAGNOSE_COST_RATIO",
    "MIN_EFFECT_SLOPE_REL",
    "MIN_RADIUS_SLOPE_PCT",
    "MODEL_FILE",
    "OUTLIER_Z",
    "ROBOT_FILE",
    "TREND_T",
    "FleetResult",
    "PathLike",
    "Session",
    "analyse",
    "calibrate_fleet",
    "calibrate_session",
    "diagnose_session",
    "find_sessions",
    "main",
    "order_sessions",
    "robots_without_sessions",
    "robust_z",
    "simulate_fleet",
    "train_args",
    "trend",
    "write_fleet_view",
    "write_table",
]
