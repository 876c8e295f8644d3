"""omnical from Python, the whole story in a minute.

1. simulate a robot whose wheel clock lags its ground truth by 60 ms (an effect the IK matrix cannot
   express, hidden in the data);
2. train the 3 x 3 IK matrix (the paper's non-parametric model) and see how far it gets;
3. diagnose: which physical effect is missing? (the built-in catalogue plus a user effect written here
   in Python);
4. add the effect the diagnosis names, retrain, and watch the held-out cost fall;
5. plot the error of one validation run before and after (when matplotlib is installed).

Run:  pip install .  &&  python examples/quickstart.py
"""

from __future__ import annotations

import numpy as np

import omnical


class BrakeDrag(omnical.Effect):
    """wheel a loses a constant speed while it turns (a dragging brake pad)"""

    id = "brake_drag"
    stage = "wheel"
    params = [omnical.Param("d_rad_s", "rad/s", 0.0, 0.0, 1.0)]

    def wheel_rates(self, p, t_s, dt_s, wheel_rad_s):  # type: ignore[no-untyped-def]
        # Whole columns of one run: (N,) times, (N,) steps, (N, W) wheel speeds in rad/s.
        w = wheel_rad_s.copy()
        a = w[:, 0]
        w[:, 0] = np.where(np.abs(a) > p[0], a - p[0] * np.sign(a), a)
        return w


def main() -> None:
    # 1. The true robot: the paper's calibrated matrix (Eq. 9) plus a hidden 60 ms clock lag.
    truth = omnical.Model.paper().with_effect("time_offset", tau_s=0.06)
    train_runs = omnical.simulate(truth, runs_per_command=1, duration_s=5.0, seed=7, prefix="train/")
    val_runs = omnical.simulate(truth, runs_per_command=1, duration_s=5.0, seed=8, prefix="validation/")
    print(f"simulated {len(train_runs)} training and {len(val_runs)} validation runs "
          f"(first: {train_runs[0].n_samples} samples x {train_runs[0].n_wheels} wheels)")

    design = omnical.Model.design("apr02")  # the simulated robot is the paper's APR-02
    print(f"design model (Eq. 7): held-out Eq. 6 cost {omnical.evaluate(design, val_runs).cost:.4f}")

    # 2. Fit the 9 matrix entries.
    fit = omnical.train("design", train_runs, robot="apr02", seed=0, progress=lambda it: None)
    print(f"fitted matrix: held-out Eq. 6 cost {omnical.evaluate(fit.model, val_runs).cost:.4f}")
    print(np.array2string(fit.matrix, precision=5))

    # 3. What is missing? Candidates: the built-in catalogue and our Python effect.
    d = omnical.diagnose(fit.model, train_runs, validate=val_runs, candidates=[*omnical.CATALOGUE, BrakeDrag()])
    print("\ndiagnosis (held-out gain of refitting with each effect):")
    for c in d.ranking[:4]:
        params = ", ".join(f"{p['name']}={p['value']:.4f} {p['unit']}" for p in c["params"])
        print(f"  {c['effect']:<20} {100 * c['held_out_gain']:6.1f} %  {params}")
    print(f"verdict: {d.verdict_text}")

    # 4. Add the named effect and retrain: the cost falls.
    effect = d.verdict or "time_offset"
    fit2 = omnical.train("design", train_runs, robot="apr02", effects=[effect], seed=0)
    before = omnical.evaluate(fit.model, val_runs)
    after = omnical.evaluate(fit2.model, val_runs)
    print(f"\nheld-out cost, Eq. 6:  design {omnical.evaluate(design, val_runs).cost:.4f}"
          f"  ->  matrix {before.cost:.4f}  ->  matrix + {effect} {after.cost:.4f}")
    print(f"held-out path RMS [m]: matrix {before.path_cost:.4f}  ->  matrix + {effect} {after.path_cost:.4f}")
    found = {k: round(v, 4) for k, v in fit2.params.items() if k.startswith(effect + ".")}
    print(f"recovered: {found} (hidden: time_offset.tau_s = 0.06 s)")

    # 5. Plot one validation run's position error along the path.
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("\n(install matplotlib to get quickstart.png)")
        return
    fig, ax = plt.subplots(figsize=(7, 4))
    for label, ev in (("matrix only", before), (f"matrix + {effect}", after)):
        r = ev.runs[3]
        ax.plot(r.t_s - r.t_s[0], 1000 * np.hypot(r.error[:, 0], r.error[:, 1]), label=label)
    ax.set_xlabel("time along the run [s]")
    ax.set_ylabel("position error [mm]")
    ax.set_title(f"validation run {before.runs[3].name}")
    ax.legend()
    fig.tight_layout()
    fig.savefig("quickstart.png", dpi=100)
    print("\nwrote quickstart.png")


if __name__ == "__main__":
    main()
