#!/usr/bin/env python3
"""What a Python user would write instead of `omnical train --preset paper`, timed against it.

The paper's calibration on the same simulated CSV runs: Eq. 1 (Euler, fixed 10 ms steps) from each run's
first ground-truth pose, the Eq. 6 end-pose cost, a ±10 % box around the design matrix (zero entries
pinned), minimised by `scipy.optimize.differential_evolution` with the population vectorised in numpy
(200 individuals per generation, like the GA) for the same number of cost evaluations as omnical used.
Prints both wall times, both costs and the speed ratio.

    pip install numpy scipy
    cargo build --release -p omni-cli
    target/release/omnical simulate --format csv --out /tmp/sim-csv
    python3 benches/python_baseline.py /tmp/sim-csv/train --omnical target/release/omnical

`--evaluations N` caps the Python run (the ratio is then taken per evaluation). Not run by CI.
"""

import argparse
import math
import re
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
from scipy.optimize import differential_evolution

STEP_S = 0.010
DESIGN = np.array(
    [
        [-0.0854478398400646, 0.0, 0.0854478398400646],
        [0.049333333333333333, -0.09866666666666667, 0.049333333333333333],
        [0.2529914529914529, 0.2529914529914529, 0.2529914529914529],
    ]
)


def read_run(path):
    """Wheel stamps, wheel speeds (n, 3) and ground truth (m, 4: t, x, y, θ) of one omnical CSV run."""
    t_w, w, truth = [], [], []
    with open(path, encoding="utf-8-sig") as f:
        header = None
        for line in f:
            line = line.strip()
            if not line or line.startswith("#"):
                continue
            cells = line.split(",")
            if header is None:
                header = cells
                wi = [i for i, h in enumerate(header) if h.endswith("_rad_s")]
                pi = [header.index(h) for h in ("x_m", "y_m", "theta_rad")]
                continue
            t = float(cells[0])
            if cells[wi[0]]:
                t_w.append(t)
                w.append([float(cells[i]) for i in wi])
            if cells[pi[0]]:
                truth.append([t] + [float(cells[i]) for i in pi])
    return np.array(t_w), np.array(w), np.array(truth)


def increments(t, w, truth):
    """Wheel-angle increments f·h·w of each Eq. 1 step between the first and last ground-truth stamps,
    as omnical's walk takes them (a partial first and last step)."""
    t0, t1 = truth[0, 0], truth[-1, 0]
    median = float(np.median(np.diff(t)))
    first = int(np.searchsorted(t, t0, side="right"))
    out, cursor = [], t0
    for k in range(first, len(t)):
        a = t[k - 1] if k > 0 else t[k] - median
        length = t[k] - a
        start = max(a, cursor)
        end = min(t[k], t1)
        out.append(min(max((end - start) / length, 0.0), 1.0) * STEP_S * w[k])
        if t[k] >= t1:
            break
        cursor = t[k]
    return np.array(out)


def load(folder):
    runs = [read_run(p) for p in sorted(Path(folder).glob("*.csv"))]
    steps = [increments(*r) for r in runs]
    k = max(len(s) for s in steps)
    u = np.zeros((k, len(runs), 3))  # steps × runs × wheels, zero-padded
    for i, s in enumerate(steps):
        u[: len(s), i] = s
    start = np.array([r[2][0, 1:] for r in runs])
    end = np.array([r[2][-1, 1:] for r in runs])
    samples = sum(len(s) for s in steps)
    return u, start, end, samples


class EndPoseCost:
    """Eq. 6 for a population at once: the step loop runs over time, numpy over (individual, run)."""

    def __init__(self, u, start, end, free):
        self.u, self.start, self.end, self.free = u, start, end, free
        self.evaluations = 0

    def matrices(self, xs):  # xs: (n_free, pop) → (pop, 3, 3)
        m = np.zeros((xs.shape[1], 9))
        m[:, self.free] = xs.T
        return m.reshape(-1, 3, 3)

    def __call__(self, xs):
        xs = np.atleast_2d(xs.T).T
        m = self.matrices(xs)
        pop = m.shape[0]
        self.evaluations += pop
        x = np.broadcast_to(self.start[:, 0], (pop, len(self.start))).copy()
        y = np.broadcast_to(self.start[:, 1], (pop, len(self.start))).copy()
        th = np.broadcast_to(self.start[:, 2], (pop, len(self.start))).copy()
        for uk in self.u:  # uk: runs × wheels
            d = np.einsum("pij,rj->ipr", m, uk)  # body displacement (3, pop, runs)
            c, s = np.cos(th), np.sin(th)
            x += c * d[0] - s * d[1]
            y += s * d[0] + c * d[1]
            th += d[2]
        dth = np.angle(np.exp(1j * (th - self.end[:, 2])))
        e = np.sqrt((x - self.end[:, 0]) ** 2 + (y - self.end[:, 1]) ** 2 + dth**2)
        return e.mean(axis=1)


def run_omnical(binary, folder):
    out = subprocess.run(
        [binary, "train", str(folder), "--preset", "paper", "-q"], capture_output=True, text=True, check=True
    ).stdout
    m = re.search(r"(\d[\d,]*) evaluations, ([\d.]+) s", out)
    cost = re.search(r"cost \(Eq\. 6\)\s+design ([\d.]+)\s+fitted ([\d.]+)", out)
    if not m or not cost:
        sys.exit(f"could not read omnical's summary:\n{out}")
    return int(m.group(1).replace(",", "")), float(m.group(2)), float(cost.group(2))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("train", help="folder of omnical CSV runs (simulate --format csv)")
    ap.add_argument("--omnical", default="target/release/omnical", help="omnical binary")
    ap.add_argument("--evaluations", type=int, help="cap the Python cost evaluations (default: omnical's)")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()

    rust_evals, rust_s, rust_cost = run_omnical(args.omnical, args.train)
    u, start, end, samples = load(args.train)
    design = DESIGN.ravel()
    free = np.flatnonzero(design != 0.0)
    lo, hi = design[free] - 0.1 * np.abs(design[free]), design[free] + 0.1 * np.abs(design[free])
    f = EndPoseCost(u, start, end, free)
    budget = args.evaluations or rust_evals
    popsize = math.ceil(200 / len(free))  # 200 individuals per generation, as the GA
    per_gen = popsize * len(free)
    t0 = time.perf_counter()
    res = differential_evolution(
        f,
        list(zip(lo, hi)),
        popsize=popsize,
        maxiter=max(budget // per_gen - 1, 0),
        tol=0.0,
        seed=args.seed,
        polish=False,
        vectorized=True,
        updating="deferred",
        x0=design[free],
    )
    py_s = time.perf_counter() - t0
    per_eval_py = py_s / f.evaluations
    per_eval_rust = rust_s / rust_evals
    print(f"runs {u.shape[1]}, {samples} wheel samples per evaluation")
    print(f"omnical  train --preset paper: {rust_evals} evaluations, {rust_s:.2f} s, cost {rust_cost:.5f}")
    print(f"python   numpy + scipy DE:     {f.evaluations} evaluations, {py_s:.2f} s, cost {res.fun:.5f}")
    print(f"python   {samples * f.evaluations / py_s / 1e6:.1f} M wheel samples/s")
    print(f"speed ratio (per cost evaluation, python / omnical): {per_eval_py / per_eval_rust:.0f}x")
    if f.evaluations < rust_evals:
        print(f"python at omnical's {rust_evals} evaluations: ≈ {per_eval_py * rust_evals:.0f} s (extrapolated)")


if __name__ == "__main__":
    main()
