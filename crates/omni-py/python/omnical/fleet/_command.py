"""``omnical fleet ...``: the fleet run from the command line (its options are the native parser's)."""

from __future__ import annotations

import sys
from typing import Sequence

from .. import _omnical
from ._run import calibrate_fleet
from ._sessions import find_sessions, fleet_inputs


def main(argv: Sequence[str]) -> int:
    """``omnical fleet ...`` (``argv`` after the subcommand); returns the exit status (0, 2 on bad
    input, 130 after Ctrl-C).

    >>> main(["no-such-fleet/", "--out", "fleet-out/"])  # prints "error: fleet folder ... does not exist"
    2
    """
    # The options are declared once, in the native command line's parser (`omnical fleet --help`).
    a, message, status = _omnical._fleet_args(list(argv))
    if a is None:
        print(message, end="", file=sys.stdout if status == 0 else sys.stderr)
        return status
    try:
        # The output folder checked with the command line's spelling (`--out`) before the run, which checks
        # it again as `out=`: the fleet folder's own errors first, as calibrate_fleet gives them.
        find_sessions(a["fleet_dir"])
        _omnical._prepare_dir(a["out"], flag="--out", inputs=fleet_inputs(a["fleet_dir"]))
        r = calibrate_fleet(
            a["fleet_dir"],
            a["out"],
            scheduler=a["scheduler"],
            n_workers=a["workers"],
            preset=a["preset"],
            seed=a["seed"],
            model=a["model"],
            extra_train_args=a["train_args"],
            diagnose=a["diagnose"],
            progress=False if a["quiet"] else None,
        )
    except KeyboardInterrupt:
        return 130
    except (OSError, ValueError, ImportError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    ok = len(r.rows) - len(r.errors)
    print(f"{ok} of {len(r.rows)} robot-sessions calibrated in {r.seconds:.1f} s; written to {r.out}")
    for bad in r.errors:
        print(f"  error: {bad['robot']}/{bad['session']}: {bad['error']}")
    for rb in r.flagged:
        for why in r.analysis["reasons"][rb]:
            print(f"  robot {rb}: {why}")
    for f in r.files:
        print(f"  {f}")
    return 0
