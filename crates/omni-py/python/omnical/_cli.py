"""The ``omnical`` console command installed with the wheel (no Rust toolchain needed).

Every subcommand is the native command line's (``cli_main``) except the Python-side ones: ``omnical fleet``
(:mod:`omnical.fleet`, on Dask) and ``omnical simulate --fleet N`` (:func:`omnical.fleet.simulate_fleet`).
"""

from __future__ import annotations

import signal
import sys
from typing import Sequence

from ._omnical import _OutDir, cli_main


def _simulate_fleet(argv: Sequence[str]) -> int:
    """``omnical simulate --fleet N [--sessions S] --out DIR [--seed N]``."""
    import argparse

    from .fleet import simulate_fleet

    p = argparse.ArgumentParser(
        prog="omnical simulate --fleet",
        description="Write a simulated fleet DIR/<robot>/<session>/ (spread wheel radii, one robot whose wheel b "
        "wears, one whose wheel clock lags more each session) with DIR/robot.toml and DIR/truth.json.",
    )
    p.add_argument("--fleet", type=int, required=True, metavar="N", help="robots")
    p.add_argument("--sessions", type=int, default=3, metavar="S", help="sessions per robot (default 3)")
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument("--seed", type=int, default=0, help="seed (default 0)")
    p.add_argument("--force", action="store_true", help="replace an output folder that already holds files, whole")
    p.add_argument("--quiet", "-q", action="store_true")
    a = p.parse_args(list(argv))
    try:
        # The folder is claimed with the command line's spelling (`--out`, `--force`), as `omnical simulate
        # --out` claims its own; simulate_fleet fills the claim's (empty) staging folder.
        with _OutDir.claim(a.out, flag="--out", force=a.force) as claimed:
            truth = simulate_fleet(claimed.path, a.fleet, a.sessions, seed=a.seed)
            claimed.commit()
    except (OSError, ValueError, RuntimeError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    print(f"{a.fleet} robots × {a.sessions} sessions written to {a.out} (truth: {a.out}/truth.json)")
    for robot, what in sorted(truth["degrading"].items()):
        print(f"  degrading: {robot}: {'; '.join(what)}")
    return 0


def dispatch(argv: Sequence[str]) -> int:
    """Runs ``argv`` (program name first); returns the exit status."""
    args = list(argv[1:])
    if args[:1] == ["fleet"]:
        from .fleet import main as fleet_main

        return fleet_main(args[1:])
    if args[:1] == ["simulate"] and any(a == "--fleet" or a.startswith("--fleet=") for a in args):
        return _simulate_fleet(args[1:])
    # Everything else is the native command line; Ctrl-C acts as in the native binary (it ends the command
    # at once, except during `train`, where it stops the search and keeps the best model so far).
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    return cli_main(list(argv))


def main() -> None:
    """The console entry point."""
    sys.exit(dispatch(sys.argv))


if __name__ == "__main__":
    main()
