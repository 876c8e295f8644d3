"""Shared fixtures: tiny simulated datasets (a few seconds per run) so the suite stays fast."""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import pytest

import omnical

REPO = Path(__file__).resolve().parents[3]


def omnical_command() -> list[str]:
    """The console command installed with the wheel (beside this Python)."""
    exe = Path(sys.executable).parent / "omnical"
    if exe.exists():
        return [str(exe)]
    found = shutil.which("omnical")
    assert found, "the omnical console command is not installed"
    return [found]


@pytest.fixture(scope="session")
def truth() -> omnical.Model:
    """The paper's Eq. 9 robot with a hidden 60 ms wheel-clock lag."""
    return omnical.Model.paper().with_effect("time_offset", tau_s=0.06)


@pytest.fixture(scope="session")
def runs(truth: omnical.Model) -> list[omnical.Run]:
    return omnical.simulate(truth, runs_per_command=1, duration_s=2.5, seed=7)


@pytest.fixture(scope="session")
def validation(truth: omnical.Model) -> list[omnical.Run]:
    return omnical.simulate(truth, runs_per_command=1, duration_s=2.5, seed=8, prefix="validation/")


@pytest.fixture(scope="session")
def sim_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """`omnical simulate` through the wheel's console command: CSV and MCAP copies of a tiny dataset."""
    root = tmp_path_factory.mktemp("sim")
    for fmt in ("csv", "mcap"):
        subprocess.run(
            [*omnical_command(), "simulate", "--out", str(root / fmt), "--runs-per-command", "1", "--duration", "1.5",
             "--format", fmt, "--effect", "time_offset=0.06"],
            check=True,
            capture_output=True,
        )
    return root


@pytest.fixture(scope="session")
def optiodom() -> Path:
    """Real robot logs (shared data beside the repository), when present."""
    for base in (REPO.parent / "shared", Path("/work/shared")):
        p = base / "data" / "optiodom-omni3-square" / "221220201934"
        if p.exists():
            return p
    pytest.skip("OptiOdom data not found beside the repository")
