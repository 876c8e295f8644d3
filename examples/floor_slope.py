"""From the learned correction to a named physical effect (issue 18): a floor slope written in Python.

`omnical explore` names a world-frame drift (`learned:world`); this script writes the physics behind it
as a user effect, a tilted floor that pushes the robot downhill at a constant world-frame velocity while
it moves, fits both on simulated runs with such a drift, and compares their held-out costs and
parameters. Run: `python examples/floor_slope.py` (after `maturin develop -m crates/omni-py/Cargo.toml`).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import numpy.typing as npt

import omnical

# omni_kin::effect::learned: "moving" is faster than 5 mm/s or 0.02 rad/s.
MOVING_SPEED_M_S = 0.005
MOVING_OMEGA_RAD_S = 0.02


class FloorSlope(omnical.Effect):
    """A tilted floor: a constant world-frame drift downhill while the robot moves."""

    id = "floor_slope"
    stage = "twist"
    params = [
        omnical.Param("downhill_x", "m/s", 0.0, -0.05, 0.05),
        omnical.Param("downhill_y", "m/s", 0.0, -0.05, 0.05),
    ]

    def twist_at(
        self,
        p: npt.NDArray[np.float64],
        twist: tuple[float, float, float],
        wheel_rad_s: npt.NDArray[np.float64],
        heading_rad: float,
        since_start_s: float,
    ) -> Any:
        """The body twist plus the world drift (p[0], p[1]) turned into the body frame at `heading_rad`."""
        vx, vy, omega = twist
        if math.hypot(vx, vy) <= MOVING_SPEED_M_S and abs(omega) <= MOVING_OMEGA_RAD_S:
            return twist
        s, c = math.sin(heading_rad), math.cos(heading_rad)
        return (vx + c * p[0] + s * p[1], vy - s * p[0] + c * p[1], omega)


def compare(drift_x: float = 0.0039, drift_y: float = -0.0021, seed: int = 11) -> dict[str, Any]:
    """Simulate runs with a world drift, fit `learned:world` and `FloorSlope`, judge both on held-out runs."""
    truth = omnical.Model.design().with_effect("learned:world", drift_x=drift_x, drift_y=drift_y)
    train = omnical.simulate(truth, runs_per_command=1, duration_s=3.0, seed=seed)
    held_out = omnical.simulate(truth, runs_per_command=1, duration_s=3.0, seed=seed + 1, prefix="validation/")
    learned = omnical.train("design", train, robot="apr02", effects=["learned:world"], seed=0)
    slope = omnical.train("design", train, robot="apr02", effects=[FloorSlope()], seed=0)
    return {
        "true_cost": omnical.evaluate(truth, held_out).path_cost,
        "design_cost": omnical.evaluate(omnical.Model.design(), held_out).path_cost,
        "learned_cost": omnical.evaluate(learned.model, held_out).path_cost,
        "slope_cost": omnical.evaluate(slope.model, held_out).path_cost,
        "learned": (learned.params["learned:world.drift_x"], learned.params["learned:world.drift_y"]),
        "slope": (slope.params["floor_slope.downhill_x"], slope.params["floor_slope.downhill_y"]),
    }


if __name__ == "__main__":
    r = compare()
    print(f"held-out path RMS: design {r['design_cost']:.4f} m, truth {r['true_cost']:.4f} m")
    print(f"  learned:world {r['learned_cost']:.4f} m, drift ({r['learned'][0]:+.5f}, {r['learned'][1]:+.5f}) m/s")
    print(f"  floor_slope   {r['slope_cost']:.4f} m, downhill ({r['slope'][0]:+.5f}, {r['slope'][1]:+.5f}) m/s")
