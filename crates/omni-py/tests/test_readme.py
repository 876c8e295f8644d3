"""The README's Python blocks, and the shell blocks of its Python sections, run as written (issue 30) against
the installed wheel, each in a temporary folder. crates/omni-cli/tests/readme.rs runs the README's other
blocks and checks that every block is claimed by one test."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from conftest import REPO, omnical_command

README = REPO / "README.md"


def block(section: str, lang: str) -> str:
    """The first ``lang`` block under the ``## section`` heading of the README."""
    current, text, inside = "", None, False
    for line in README.read_text(encoding="utf-8").splitlines():
        if inside:
            if line == "```":
                return text or ""
            text = (text or "") + line + "\n"
        elif line.startswith("```") and current == section and line[3:].strip() == lang:
            inside = True
        elif line.startswith("## "):
            current = line[3:].strip()
    raise AssertionError(f"README has no {lang} block under '## {section}'")


def shell(line: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    """One README shell line with bash, the wheel's ``omnical`` command first on the PATH."""
    env = {**os.environ, "PATH": f"{Path(omnical_command()[0]).parent}{os.pathsep}{os.environ['PATH']}"}
    r = subprocess.run(["bash", "-c", f"set -euo pipefail\n{line}"], cwd=cwd, env=env, capture_output=True, text=True)
    assert r.returncode == 0, f"README line failed: {line}\n--- stdout\n{r.stdout}\n--- stderr\n{r.stderr}"
    return r


def pip_lines_are_the_test_commands_install(text: str) -> list[str]:
    """The block's lines but its ``pip install`` ones, which are checked to be what scripts/test.sh installs
    this very wheel with (``pip install ".[fleet]"``, a superset of ``pip install .``): the module these
    tests import."""
    rest = []
    test_sh = (REPO / "scripts" / "test.sh").read_text()
    assert 'pip install --quiet ".[fleet]"' in test_sh
    for line in text.splitlines():
        command = line.split("#")[0].strip()
        if command.startswith("pip install"):
            assert command in ("pip install .", 'pip install ".[fleet]"'), command
        elif command:
            rest.append(line)
    return rest


def test_python_section_shell_block(tmp_path: Path) -> None:
    rest = pip_lines_are_the_test_commands_install(block("Python", "sh"))
    assert [line.split("#")[0].strip() for line in rest] == ["python examples/quickstart.py"]
    (tmp_path / "examples").symlink_to(REPO / "examples")
    r = shell(rest[0].replace("python ", f"{sys.executable} ", 1), tmp_path)
    assert "verdict: add time_offset" in r.stdout, r.stdout
    recovered = re.search(r"'time_offset\.tau_s': ([0-9.]+)", r.stdout)
    assert recovered and abs(float(recovered.group(1)) - 0.06) < 0.005, r.stdout


def test_python_api_block(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)
    scope: dict[str, Any] = {}
    exec(compile(block("Python", "python"), str(README), "exec"), scope)
    assert scope["d"].verdict == "time_offset"
    assert scope["fit"].matrix.shape == (3, 3)
    for f in ("fitted.toml", "report.html", "figs/ladder.png"):
        assert (tmp_path / f).exists(), f
    assert len(list((tmp_path / "tum").glob("*.calibrated.tum"))) == 36 and len(list((tmp_path / "bags").iterdir())) == 36


def test_fleet_blocks(tmp_path: Path) -> None:
    distributed = pytest.importorskip("distributed")
    rest = pip_lines_are_the_test_commands_install(block("Fleet (Dask)", "sh"))
    placeholder = "tcp://10.0.0.5:8786"
    with distributed.LocalCluster(n_workers=1, processes=True, threads_per_worker=1, dashboard_address=None) as cluster:
        for line in rest:
            # The scheduler address stands for any Dask cluster's: here, one started for the test.
            shell(line.replace(placeholder, cluster.scheduler_address), tmp_path)
    assert sum(placeholder in line for line in rest) == 1
    for f in ("fleet.csv", "fleet.html"):
        assert (tmp_path / "fleet-out" / f).is_file()
    cwd = Path.cwd()
    os.chdir(tmp_path)
    try:
        scope: dict[str, Any] = {}
        exec(compile(block("Fleet (Dask)", "python"), str(README), "exec"), scope)
    finally:
        os.chdir(cwd)
    # The README's comment: r01's wheel wears and r02's clock drifts, and the fleet view says why.
    r = scope["r"]
    assert r.flagged == ["r01", "r02"], r.analysis["reasons"]
    assert r.rows[0]["cost_fitted"] < r.rows[0]["cost_design"]
