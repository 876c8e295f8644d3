"""Type stubs of the compiled module ``omnical._omnical`` (checked by ``python -m mypy.stubtest omnical``).

Shapes: N wheel samples, W wheels, M ground-truth poses, K residual poses (M - 1), R runs, P parameters.
Units: m, s, rad, rad/s (ROS REP-103).
"""

from collections.abc import Callable, Iterable, Sequence
from os import PathLike
from typing import Any, Literal, Optional, Union, final

import numpy as np
import numpy.typing as npt

_F64 = npt.NDArray[np.float64]
_Path = Union[str, PathLike[str]]
_Runs = Union["Dataset", "Run", Iterable["Run"]]
_EffectArg = Any  # a catalogue id (str) or a Python effect object (see omnical.Effect)
# A model as the CLI's --model: a Model, "design", "paper" or a model file path (train: also "ik",
# "geometry", "diff", "mecanum", "skid").
_ModelArg = Union["Model", str, PathLike[str]]
# Closed choices, as the CLI's (each the library's choice table, checked by crates/omni-cli/tests/python_stubs.rs;
# an id with "_" is also taken with "-").
_Kinematics = Literal["ik", "geometry", "diff", "mecanum", "skid"]
_Preset = Literal["default", "paper"]
_Objective = Literal["path", "end_pose", "end-pose"]
_Unexcited = Literal["hold", "move"]
_GtKind = Literal["absolute", "relative", "end_pose", "end-pose"]
_LidarModel = Literal["ideal", "urg04lx", "rplidar"]

__all__ = [
    "CATALOGUE",
    "Calibration",
    "CalibrationError",
    "Dataset",
    "DatasetError",
    "Diagnosis",
    "Evaluation",
    "Exploration",
    "Model",
    "ModelFileError",
    "OmnicalError",
    "Run",
    "RunResiduals",
    "__version__",
    "cli_main",
    "diagnose",
    "diagnose_files",
    "effect_catalogue",
    "evaluate",
    "explore",
    "export",
    "imu",
    "info",
    "integrate",
    "load",
    "load_model",
    "report",
    "simulate",
    "train",
    "train_files",
    "_calibration_from_state",
    "_dataset_from_state",
    "_fleet_args",
    "_model_from_toml",
    "_OutDir",
    "_prepare_dir",
    "_run_from_bytes",
    "_write_atomic",
]

__version__: str
CATALOGUE: list[str]

class OmnicalError(Exception): ...
class DatasetError(OmnicalError): ...
class ModelFileError(OmnicalError): ...
class CalibrationError(OmnicalError): ...

@final
class Run:
    """One run: wheel-speed samples, ground-truth poses, the command. Validated on construction."""

    def __new__(
        cls,
        t_s: npt.ArrayLike,
        wheel_rad_s: npt.ArrayLike,
        truth: npt.ArrayLike,
        *,
        name: str = "run",
        command: Optional[tuple[float, float, float]] = None,
        repetition: Optional[int] = None,
        wheel_start_rad: Optional[npt.ArrayLike] = None,
    ) -> Run:
        """t_s (N,) [s]; wheel_rad_s (N, W) [rad/s]; truth (M, 4): t_s [s], x_m [m], y_m [m], theta_rad [rad];
        command (v_m_s, alpha_rad, omega_rad_s); wheel_start_rad (W,) [rad]."""
    @property
    def name(self) -> str: ...
    @property
    def n_wheels(self) -> int: ...
    @property
    def n_samples(self) -> int: ...
    @property
    def t_s(self) -> _F64:
        """(N,) wheel-sample stamps [s]."""
    @property
    def wheel_rad_s(self) -> _F64:
        """(N, W) wheel speeds [rad/s]."""
    @property
    def truth(self) -> _F64:
        """(M, 4) ground truth: t_s [s], x_m [m], y_m [m], theta_rad [rad]."""
    @property
    def recorded_odometry(self) -> _F64:
        """(K, 4) the robot's own odometry, columns as ``truth``."""
    @property
    def command(self) -> Optional[tuple[float, float, float]]:
        """(v_m_s, alpha_rad, omega_rad_s) or None."""
    @property
    def repetition(self) -> Optional[int]: ...
    @property
    def truth_position_only(self) -> bool:
        """The ground truth gives positions only (headings are placeholders, never compared)."""

@final
class Dataset:
    """Runs loaded from files; a sequence of Run."""

    @property
    def runs(self) -> list[Run]: ...
    @property
    def notes(self) -> list[str]: ...
    @property
    def skipped(self) -> list[tuple[str, str]]:
        """(source, reason) per skipped input."""
    @property
    def design(self) -> Optional[Model]:
        """The design model of the data's robot (``robot=``, the data's geometry, or a ``robot.toml`` found
        beside the data; when its inputs declare different designs, the one of the most runs, which
        ``train`` starts from); None when the data names no robot."""
    @property
    def robot(self) -> Optional[str]:
        """The robot description the runs were read with (``"PATH (found beside the data)"``, a path, or
        ``"apr02 (built in: the paper's APR-02)"``), or None."""
    @property
    def ground_truth_clocks(self) -> list[dict[str, Any]]:
        """The clock offset of each ``gt=`` file: recording, file, offset_s [s], std_error_s [s], estimated,
        r_squared."""
    def __len__(self) -> int: ...
    def __getitem__(self, key: int, /) -> Run: ...

@final
class Model:
    """Base kinematics (``ik`` matrix or ``geometry``) plus effects, with parameter values. Immutable."""

    @staticmethod
    def design(robot: _Path = "apr02", *, kinematics: _Kinematics = "ik") -> Model:
        """The design model of ``robot`` (a robot.toml path, or ``"apr02"``: the paper's robot, Eq. 7);
        ``kinematics`` is ``"ik"``, ``"geometry"``, ``"diff"``, ``"mecanum"`` or ``"skid"``. Wheel names: its joints."""
    @staticmethod
    def paper() -> Model:
        """The paper's calibrated matrix (Eq. 9)."""
    @staticmethod
    def from_matrix(matrix: npt.ArrayLike, *, design: Optional[npt.ArrayLike] = None) -> Model:
        """An ``ik`` model from a (3, W) matrix [m/s, m/s, rad/s per rad/s]."""
    @property
    def kinematics(self) -> str: ...
    @property
    def n_wheels(self) -> int: ...
    @property
    def wheel_names(self) -> list[str]:
        """Wheel (joint) names in column order (a robot description's joints, else wheel_a, ...)."""
    @property
    def matrix(self) -> _F64:
        """(3, W) IK matrix: rows vx [m/s], vy [m/s], omega [rad/s] per wheel speed [rad/s]."""
    @property
    def design_matrix(self) -> _F64:
        """(3, W) IK matrix at the design parameters."""
    @property
    def effects(self) -> list[str]: ...
    @property
    def param_names(self) -> list[str]: ...
    @property
    def param_values(self) -> _F64:
        """(P,) parameter values in ``param_names`` order."""
    @property
    def params(self) -> dict[str, float]: ...
    @property
    def param_specs(self) -> list[dict[str, Any]]:
        """name, unit, null, lower, upper per parameter."""
    def get(self, name: str) -> float: ...
    def with_effect(self, effect: _EffectArg, **values: float) -> Model: ...
    def with_params(self, values: dict[str, float]) -> Model: ...
    def to_toml(self) -> str: ...
    def save(self, path: _Path) -> None: ...

@final
class Calibration:
    """The outcome of ``train``."""

    def save(self, path: _Path) -> None:
        """Write the model file as ``omnical train --out`` writes it (the model and its ``[fit]`` summary),
        atomically: the same runs, preset and seed give the CLI's bytes."""

    @property
    def model(self) -> Model: ...
    @property
    def start(self) -> Model: ...
    @property
    def matrix(self) -> _F64:
        """(3, W) fitted IK matrix."""
    @property
    def effects(self) -> list[str]: ...
    @property
    def params(self) -> dict[str, float]: ...
    @property
    def warnings(self) -> list[str]:
        """One line per direction of parameter space the training runs do not constrain."""
    @property
    def held(self) -> list[str]:
        """Directions held at the start values by the truncated update."""
    @property
    def identifiability(self) -> dict[str, Any]:
        """Standard errors (``params``), ``condition_number``, ``covariance_kind``, ``residual_rms`` [m],
        ``weak`` directions."""
    @property
    def costs(self) -> dict[str, float]:
        """cost_start, cost_fitted (Eq. 6), objective_start, objective_fitted, improvement_pct."""
    @property
    def history(self) -> list[dict[str, Any]]:
        """optimizer, iteration, best_cost, mean_cost, evaluations, elapsed_s per iteration."""
    @property
    def objective(self) -> str: ...
    @property
    def objective_start(self) -> float: ...
    @property
    def objective_fitted(self) -> float: ...
    @property
    def cost_start(self) -> float: ...
    @property
    def cost_fitted(self) -> float: ...
    @property
    def evaluations(self) -> int: ...
    @property
    def seconds(self) -> float: ...
    @property
    def at_bound(self) -> list[str]: ...
    @property
    def outside_box(self) -> list[str]: ...
    @property
    def interrupted(self) -> bool: ...
    @property
    def stopped(self) -> bool: ...

@final
class RunResiduals:
    """One run's residuals at its ground-truth poses after the first."""

    @property
    def name(self) -> str: ...
    @property
    def path_rms(self) -> float: ...
    @property
    def t_s(self) -> _F64:
        """(K,) [s]."""
    @property
    def truth_index(self) -> list[int]: ...
    @property
    def predicted(self) -> _F64:
        """(K, 3) x_m [m], y_m [m], theta_rad [rad]."""
    @property
    def error(self) -> _F64:
        """(K, 3) dx_m [m], dy_m [m], dtheta_rad [rad]."""
    @property
    def end_error(self) -> _F64:
        """(3,) end-pose error (the run's Eq. 6 term)."""
    @property
    def rpe(self) -> dict[str, Any]:
        """The run's relative pose error: pairs, translation_m [m], rotation_rad [rad] (each mean, median,
        rmse, max), drift_pairs, drift_pct [% of distance]."""

@final
class Evaluation:
    """Costs of a model on runs."""

    @property
    def cost(self) -> float:
        """Eq. 6: mean end-pose error."""
    @property
    def path_cost(self) -> float:
        """RMS over every ground-truth pose [m, 1 m/rad]."""
    @property
    def runs(self) -> list[RunResiduals]: ...
    @property
    def names(self) -> list[str]: ...
    @property
    def end_errors(self) -> _F64:
        """(R, 3) dx_m, dy_m, dtheta_rad."""
    @property
    def rpe(self) -> dict[str, Any]:
        """The relative pose error over every pair of every run: delta, delta_unit ("m" or "s"), pairs,
        translation_m [m], rotation_rad [rad] (each mean, median, rmse, max), drift_pairs, drift_pct [%]."""

@final
class Diagnosis:
    """The outcome of ``diagnose``."""

    @property
    def verdict(self) -> Optional[str]: ...
    @property
    def verdict_text(self) -> str: ...
    @property
    def unexplained(self) -> bool: ...
    @property
    def unexplained_evidence(self) -> dict[str, Any]: ...
    @property
    def explored(self) -> Optional[dict[str, Any]]: ...
    @property
    def held_out(self) -> str: ...
    @property
    def costs(self) -> dict[str, float]: ...
    @property
    def design_costs(self) -> dict[str, float]: ...
    @property
    def ranking(self) -> list[dict[str, Any]]: ...
    @property
    def ladder(self) -> list[dict[str, Any]]: ...
    @property
    def findings(self) -> list[str]: ...
    @property
    def noise_floor(self) -> Optional[dict[str, Any]]: ...
    @property
    def coverage(self) -> Optional[dict[str, Any]]:
        """The training runs' motions against the held-out runs' (with ``validate``): what they lack."""
    @property
    def final_model(self) -> Optional[Model]: ...
    def to_dict(self) -> dict[str, Any]: ...

@final
class Exploration:
    """The outcome of ``explore``: each family of features (wheel, body, world, time, ground_truth) fitted
    on the training runs, as ``train(..., effects=["learned:<family>"])`` fits it, and judged by its
    held-out gain."""

    @property
    def families(self) -> list[dict[str, Any]]:
        """Largest held-out gain first: family, effect, status (``fitted``, ``not_excited``, ``singular``,
        ``not_converged``), status_reason, status_text, held_out_gain, gain_std_error, passes,
        held_out_cost_m, terms (name, value, std_error, unit, held), held, hint, curve."""
    @property
    def unexplained(self) -> bool: ...
    @property
    def best(self) -> Optional[str]: ...
    @property
    def coverage(self) -> dict[str, Any]:
        """The training runs' motions against the held-out runs': what they lack."""
    @property
    def conclusion(self) -> str: ...
    @property
    def model(self) -> Optional[Model]: ...
    def to_dict(self) -> dict[str, Any]: ...

def explore(
    model: _ModelArg, runs: _Runs, *, validate: _Runs, min_gain: float = 0.05, robot: Optional[_Path] = None
) -> Exploration:
    """Which family of physical features explains the error ``model`` leaves on ``runs``, judged on the
    held-out ``validate`` runs."""

def export(
    model: _ModelArg,
    runs: _Runs,
    *,
    tum: Optional[_Path] = None,
    mcap: Optional[_Path] = None,
    robot: Optional[_Path] = None,
    force: bool = False,
) -> list[str]:
    """TUM files and/or MCAP bags of ``model``'s odometry on ``runs`` (``omnical export``); the paths written.
    A folder that already holds files raises ``FileExistsError`` unless ``force=True`` (replaced whole)."""

def load(
    *paths: _Path,
    robot: Optional[_Path] = None,
    joints: Optional[Sequence[str]] = None,
    joints_topic: Optional[str] = None,
    gt_topic: Optional[str] = None,
    gt_parent_frame: Optional[str] = None,
    gt_child_frame: Optional[str] = None,
    gt: Optional[_Path] = None,
    gt_time_offset: Optional[float] = None,
    gt_columns: Optional[dict[str, str]] = None,
    gt_units: Optional[dict[str, str]] = None,
    gt_kind: Optional[_GtKind] = None,
    gt_window_s: Optional[float] = None,
    gt_mount: Optional[tuple[float, float, float]] = None,
    gt_mount_start: Optional[tuple[float, float, float]] = None,
    gt_scans: Optional[str] = None,
    split_s: Optional[float] = None,
    skip_invalid: bool = False,
    ticks_per_rev: Optional[float] = None,
    max_file_mb: int = 1024,
    recorded_odometry: bool = False,
) -> Dataset:
    """Load runs from .csv, .mcap, folders of them or OptiOdom set folders. ``robot``: a robot.toml or
    ``"apr02"`` (default: a robot.toml beside the data or in the working directory, as the CLI)."""

def info(
    *paths: _Path,
    robot: Optional[_Path] = None,
    joints: Optional[Sequence[str]] = None,
    joints_topic: Optional[str] = None,
    gt_topic: Optional[str] = None,
    gt_parent_frame: Optional[str] = None,
    gt_child_frame: Optional[str] = None,
    gt: Optional[_Path] = None,
    gt_time_offset: Optional[float] = None,
    gt_columns: Optional[dict[str, str]] = None,
    gt_units: Optional[dict[str, str]] = None,
    gt_kind: Optional[_GtKind] = None,
    gt_window_s: Optional[float] = None,
    gt_mount: Optional[tuple[float, float, float]] = None,
    gt_mount_start: Optional[tuple[float, float, float]] = None,
    gt_scans: Optional[str] = None,
    split_s: Optional[float] = None,
    skip_invalid: bool = False,
    ticks_per_rev: Optional[float] = None,
    max_file_mb: int = 1024,
) -> dict[str, Any]:
    """What ROS recordings hold and what :func:`load` with the same keywords makes of them: ``omnical info
    --json``'s document, ``{"recordings": [{"path", "start_unix_s", "duration_s", "messages", "topics",
    "read"}, ...], "schema_version", "command"}`` (seconds, Hz, metres)."""

def imu(
    *recordings: _Path,
    topic: str = "/imu",
    window_s: float = 1.0,
    out: Optional[_Path] = None,
    mount: Union[tuple[float, float, float], str, None] = None,
    model: Optional[_Path] = None,
    robot: Optional[_Path] = None,
    joints: Optional[Sequence[str]] = None,
    joints_topic: Optional[str] = None,
    skip_invalid: bool = False,
    max_file_mb: int = 1024,
) -> dict[str, Any]:
    """The wheel matrix's rotation row and the gyro's bias from an IMU's yaw rate (``topic``'s angular
    velocity turned into the base frame by the IMU's mount: ``mount`` ``(roll_deg, pitch_deg, yaw_deg)``,
    else the recording's static transforms, else upright) over windows of ``window_s`` seconds: ``omnical
    imu --json``'s document, ``{"fit": {"row", "row_std" (rad/s per wheel rad/s), "bias_rad_s",
    "bias_std_rad_s" (rad/s), "windows", "turned_rad", "residual_rms_rad" (rad)}, "design_row",
    "wheel_names", "topic", "window_s", "out", "mounts", "against_design", "against_model", "schema_version",
    "command"}``. ``out`` writes the design's matrix with this row as a model file. ``model``: a model file
    fitted on a reference that senses the turning (or ``"design"``, ``"paper"``); its rotation row calibrates
    the gyro (``against_model``: the gyro's scale and bias, and the IMU's row against the model's). A recording without the topic, or an
    IMU read upright whose row points against the design's (upside down, no mount stated), raises
    ``DatasetError`` naming the files and the topic."""

def load_model(path: _Path, *, effects: Sequence[Any] = ...) -> Model:
    """Read a model file (TOML); ``effects``: Python effects it names."""

def effect_catalogue(*, n_wheels: int = 3) -> list[dict[str, Any]]: ...
def simulate(
    truth: Optional[Model] = None,
    *,
    robot: Optional[_Path] = None,
    runs_per_command: int = 5,
    duration_s: float = 10.0,
    seed: int = 7,
    noise_free: bool = False,
    prefix: str = "train/",
    sample_drop_probability: float = 0.0,
    sample_jitter_s: float = 0.0,
    out: Optional[_Path] = None,
    force: bool = False,
    lidar: Optional[str] = None,
    lidar_mount: Union[tuple[float, float, float], str] = "0,0,0",
    lidar_tf: Union[tuple[float, float, float], str, None] = None,
    lidar_rate: float = 10.0,
    lidar_beams: int = 720,
    lidar_fov: float = 360.0,
    lidar_max_range: float = 12.0,
    lidar_noise: float = 0.01,
    lidar_dropout: float = 0.01,
    lidar_sweep: bool = False,
    lidar_model: _LidarModel = "ideal",
    imu: bool = False,
    imu_rate: float = 100.0,
    imu_bias: float = 0.005,
    imu_noise: float = 0.002,
    imu_mount: Union[tuple[float, float, float], str] = "0,0,0",
    imu_tf: Union[tuple[float, float, float], str, None] = None,
) -> list[Run]:
    """The benchmark commands x runs_per_command of ``robot`` (default ``"apr02"``: the flower) on the true
    robot ``truth`` (default: Eq. 9 on APR-02, else the robot's design). ``out``: also write them as ROS 2
    bags (one per run, robot.toml beside them; a folder holding files raises ``FileExistsError`` unless
    ``force=True``), with a simulated 2D lidar in the room ``lidar`` (``"room"``, ``"corridor"`` or a room
    file; mount ``(x_m, y_m, yaw_deg)``, rate [Hz], field of view ``lidar_fov`` [degrees], max range
    and noise [m]; or ``lidar_model="urg04lx"`` / ``"rplidar"``: scans made as a real URG-04LX's or
    RPLidar A2's come out) and/or an IMU's yaw rate
    (``imu=True``; rate [Hz], bias and noise [rad/s], mount ``(roll_deg, pitch_deg, yaw_deg)`` and the mount
    ``/tf_static`` states, or ``"none"``); the sensors need ``out``."""

def train(
    model: _ModelArg,
    runs: _Runs,
    *,
    robot: Optional[_Path] = None,
    effects: Sequence[_EffectArg] = ...,
    preset: _Preset = "default",
    seed: int = 0,
    objective: Optional[_Objective] = None,
    every: int = 1,
    heading_weight: float = 1.0,
    unexcited: Optional[_Unexcited] = None,
    max_std_error: float = 0.05,
    min_excitation: float = 0.01,
    progress: Optional[Callable[[dict[str, Any]], Optional[bool]]] = None,
    force: bool = False,
) -> Calibration:
    """Fit a model to training runs from ``model`` (a kinematics at the design, ``"design"``, or a start
    model); Ctrl-C keeps the best so far. ``CalibrationError`` for a preset whose fixed step misses the
    runs' sampling and for a fit worse than its start on its own training runs; ``force=True`` returns it
    with a ``UserWarning``."""

def evaluate(model: _ModelArg, runs: _Runs, *, robot: Optional[_Path] = None, rpe_delta: str = "1m") -> Evaluation:
    """Costs of ``model`` (a Model, ``"design"``, ``"paper"`` or a model file) on ``runs``; ``"design"`` is
    each run's own input's design when a Dataset's inputs declare different designs. ``rpe_delta``: the
    relative pose error's window, a distance travelled (``"1m"``) or a time (``"2s"``)."""
def integrate(model: _ModelArg, run: Run, *, robot: Optional[_Path] = None) -> _F64:
    """(N, 4) t_s [s], x_m [m], y_m [m], theta_rad [rad] through ``model``."""

def diagnose(
    model: _ModelArg,
    runs: _Runs,
    *,
    validate: Optional[_Runs] = None,
    candidates: Optional[Sequence[_EffectArg]] = None,
    auto: bool = False,
    min_gain: float = 0.05,
    every: int = 1,
    robot: Optional[_Path] = None,
) -> Diagnosis: ...
def report(
    model: _ModelArg,
    runs: _Runs,
    *,
    out: _Path,
    validate: Optional[_Runs] = None,
    png: Optional[_Path] = None,
    diagnose: bool = True,
    explore: bool = False,
    title: Optional[str] = None,
    robot: Optional[_Path] = None,
) -> list[str]:
    """Write the HTML report (inline SVG figures) of ``model`` on ``runs`` to ``out``; with ``png``
    also each figure as PNG. Returns the figure ids (``ladder``, ``overlay-worst``, ...)."""
def cli_main(argv: list[str]) -> int:
    """Run the omnical command line; returns the exit status. ``train`` installs a process-wide Ctrl-C
    handler (a first Ctrl-C stops the search with the best model so far, exit status 130; a second one
    exits the process), so call it from the ``omnical`` console command rather than an interactive
    session."""
def train_files(args: list[str]) -> dict[str, Any]:
    """``omnical train ARGS...`` (without the program and subcommand names) inside this process, the
    command's own code path (the ``--out`` model file is byte-identical), printing nothing and installing no
    Ctrl-C handler. Returns ``summary`` (``--json``'s; ``summary["noise"]`` is the odometry noise model the
    model file keeps as ``[noise]``: rates, standard errors, systematic part), ``design`` (name -> start value), ``start_s`` /
    ``end_s`` [s], ``runs``, ``notes``, ``skipped``, ``warnings``. ``ValueError`` for bad arguments,
    ``OmnicalError`` with the command's message for a failed load or fit."""

def diagnose_files(args: list[str], train_args: Optional[list[str]] = None) -> dict[str, Any]:
    """``omnical diagnose ARGS...`` inside this process; returns what ``--json`` prints. With ``train_args``
    the runs are read as ``omnical train TRAIN_ARGS...`` reads them (its data options replace those of
    ``args``)."""

def _fleet_args(args: list[str]) -> tuple[Optional[dict[str, Any]], str, int]:
    """``omnical fleet ARGS...`` parsed by the command line's parser: (options, "", 0), or (None, text,
    status) for ``--help`` and bad arguments."""

# The library's output-folder rules (omni_cli::out_path, omni_cli::atomic) for omnical's Python parts
# (omnical.fleet). ``flag`` names the option in messages: ``"out="`` (then ``force=True``) or ``"--out"``.
@final
class _OutDir:
    """A result folder of per-run files claimed by the library's rule: refused when it holds or lies inside
    one of ``inputs`` (``(what, path)`` pairs; whatever ``force``), or holds files without ``force``. Fill
    ``path`` (a staging folder beside the target), then ``commit()``; leaving a ``with`` block without a
    commit, or ``discard()``, removes what was written."""

    @staticmethod
    def claim(
        target: _Path, *, flag: str, force: bool = False, inputs: Sequence[tuple[str, _Path]] = ...
    ) -> _OutDir: ...
    @property
    def path(self) -> str: ...
    @property
    def target(self) -> str: ...
    def commit(self) -> None: ...
    def discard(self) -> None: ...
    def __enter__(self) -> _OutDir: ...
    def __exit__(self, *_exc: object) -> bool: ...

def _prepare_dir(dir: _Path, *, flag: str, inputs: Sequence[tuple[str, _Path]] = ...) -> None:
    """A folder of fixed file names: refused when it holds or lies inside an input, created when missing."""
def _write_atomic(path: _Path, data: bytes) -> None:
    """``data`` written to ``path`` atomically (a temporary file beside it, synced, renamed)."""

# Unpickling (the targets of the classes' __reduce__).
def _run_from_bytes(data: bytes) -> Run: ...
def _dataset_from_state(
    runs: list[bytes],
    notes: list[str],
    skipped: list[tuple[str, str]],
    design: str,
    robot: Optional[str] = None,
    declared: str = "",
    reading: str = "",
) -> Dataset: ...
def _model_from_toml(text: str, effects: list[Any] = ...) -> Model: ...
def _calibration_from_state(state: dict[str, Any]) -> Calibration: ...
