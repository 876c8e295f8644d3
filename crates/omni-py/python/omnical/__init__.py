"""omnical: calibrate the inverse-kinematic (IK) matrix of omnidirectional wheeled robots from their logs,
and find out which physical effect the model still misses.

The same steps as the ``omnical`` command, on numpy arrays::

    import omnical
    runs = omnical.simulate(omnical.Model.paper().with_effect("time_offset", tau_s=0.06))  # as `omnical simulate`
    fit = omnical.train("ik", runs, robot="apr02", seed=0)  # fit the 3 x W IK matrix around APR-02's design
    print(fit.matrix, fit.costs)
    d = omnical.diagnose(fit.model, runs)         # which effect is missing?
    print(d.verdict, d.ranking[0])

Every call takes the model first, then the runs, then keyword-only options named after the CLI's flags
(``validate=``, ``robot=``, ...); the model as the CLI's ``--model``: a :class:`Model`, ``"design"``,
``"paper"`` or a model file path.

Simulated recordings: ``omnical.simulate(out="sim/train", lidar="room", imu=True)`` writes ROS 2 bags with
a lidar's LaserScan and an IMU's yaw rate beside the wheels (``omnical simulate --lidar room --imu``);
``omnical.info("sim/train")`` says what they hold (``omnical info --json``), and
``omnical.imu("sim/train")`` fits the wheel matrix's rotation row and the gyro's bias from the IMU
(``omnical imu --json``).

Real data: ``omnical.load("bags/", robot="robot.toml")`` (a robot.toml beside the data is picked up
without it, as by the CLI); ``"design"`` is the design of ``robot=``, else of the data's robot, and raises
``ValueError`` saying how to describe the robot when none is known.

Units are SI (m, s, rad, rad/s). Long calls release the GIL; Ctrl-C stops ``train`` and keeps the best
fit so far. Errors: ``ValueError`` for bad input (shapes, NaN, unknown names), ``FileNotFoundError`` /
``OSError`` for files, and :class:`OmnicalError` subclasses for the rest.

Fork safety: omnical uses a rayon thread pool, whose threads do not survive ``os.fork()``; in
``multiprocessing`` use the ``spawn`` start method (or call omnical only in the children).
"""

from __future__ import annotations

from typing import Any, NamedTuple, Sequence

import numpy as np
import numpy.typing as npt

from ._omnical import (
    CATALOGUE,
    CalibrationError,
    Calibration,
    Dataset,
    DatasetError,
    Diagnosis,
    Evaluation,
    Exploration,
    Model,
    ModelFileError,
    OmnicalError,
    Run,
    RunResiduals,
    __version__,
    diagnose,
    effect_catalogue,
    evaluate,
    explore,
    export,
    imu,
    info,
    integrate,
    load,
    load_model,
    report,
    simulate,
    train,
)

__all__ = [
    "CATALOGUE",
    "Calibration",
    "CalibrationError",
    "Dataset",
    "DatasetError",
    "Diagnosis",
    "Effect",
    "Evaluation",
    "Exploration",
    "Model",
    "ModelFileError",
    "OmnicalError",
    "Param",
    "Run",
    "RunResiduals",
    "__version__",
    "diagnose",
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
]


class Param(NamedTuple):
    """One parameter of a user effect.

    >>> p = omnical.Param("k", "1", null=0.0, lower=-0.5, upper=0.5)
    >>> p.name, p.upper - p.lower
    ('k', 1.0)
    """

    name: str
    """Name, unique within the effect, e.g. ``"k"``; the model calls it ``"<effect id>.<name>"``."""
    unit: str
    """Unit, e.g. ``"s"``, ``"m"``, ``"1"``."""
    null: float
    """The value at which the effect does nothing (where fits start)."""
    lower: float
    """Lower bound of the GA's search box."""
    upper: float
    """Upper bound of the GA's search box."""


class Effect:
    """Base class for a physical effect written in Python, usable by ``simulate``, ``train``,
    ``evaluate`` and ``diagnose`` like a built-in one.

    Set ``id``, ``stage`` and ``params`` and override the hook of the stage:

    - ``"wheel"``: :meth:`wheel_rates`, called once per run and cost evaluation on whole columns;
    - ``"twist"``: :meth:`twist`, called once per wheel sample (slow: use it on small data); or, for
      world-frame physics (a tilted floor, a drifting ground-truth frame), define
      ``twist_at(p, twist, wheel_rad_s, heading_rad, since_start_s)`` instead, which also gets the body's
      world heading at the start of the step [rad] and the time since the run's first ground-truth pose
      [s] (see examples/floor_slope.py);
    - ``"clock"``: :meth:`clock_lag_s`; ``"measurement"``: :meth:`sensor_from_body` (once per evaluation).

    At the ``null`` parameter values the effect must change nothing. The hooks run on omnical's worker
    threads and take the GIL, so Python effects serialise the otherwise parallel cost. An exception
    raised by a hook stops the call and is re-raised by it.

    >>> class Slip(omnical.Effect):
    ...     'Every wheel delivers a fraction s less than it turns.'
    ...     id = "slip"
    ...     params = [omnical.Param("s", "1", 0.0, -0.2, 0.2)]
    ...     def wheel_rates(self, p, t_s, dt_s, wheel_rad_s):
    ...         return wheel_rad_s * (1.0 - p[0])
    >>> truth = omnical.Model.paper().with_effect(Slip(), s=0.05)
    >>> runs = omnical.simulate(truth, runs_per_command=1, duration_s=1.0)
    >>> omnical.evaluate(truth, runs).path_cost < omnical.evaluate("paper", runs).path_cost
    True
    """

    id: str = "python_effect"
    stage: str = "wheel"
    params: Sequence[Param] = ()

    def describe(self) -> str:
        """One line of physics for reports (default: the first line of the class docstring)."""
        doc = type(self).__doc__ or ""
        return doc.strip().splitlines()[0] if doc.strip() else self.id

    def wheel_rates(
        self,
        p: npt.NDArray[np.float64],
        t_s: npt.NDArray[np.float64],
        dt_s: npt.NDArray[np.float64],
        wheel_rad_s: npt.NDArray[np.float64],
    ) -> npt.ArrayLike:
        """Wheel stage: the run's wheel speeds as the IK matrix should see them.

        p: (P,) parameters. t_s: (N,) sample times on the ground-truth clock [s]. dt_s: (N,) integrated
        step of each sample [s]. wheel_rad_s: (N, W) measured wheel speeds [rad/s]. Returns (N, W) [rad/s].
        """
        return wheel_rad_s

    def twist(
        self, p: npt.NDArray[np.float64], twist: tuple[float, float, float], wheel_rad_s: npt.NDArray[np.float64]
    ) -> Any:
        """Twist stage: one sample's body twist (vx_m_s, vy_m_s, omega_rad_s) from its wheel speeds (W,)
        [rad/s]. Returns 3 numbers."""
        return twist

    def clock_lag_s(self, p: npt.NDArray[np.float64]) -> float:
        """Clock stage: how late the wheel stamps run against the ground-truth clock [s]."""
        return 0.0

    def sensor_from_body(self, p: npt.NDArray[np.float64]) -> Any:
        """Measurement stage: the ground-truth sensor's pose in the body frame (x_m, y_m, theta_rad)."""
        return (0.0, 0.0, 0.0)

    def __repr__(self) -> str:
        return f"{type(self).__name__}(id={self.id!r}, stage={self.stage!r})"
