"""Every public function and class of omnical (the package, its compiled module and omnical.fleet) has a
runnable example (``>>>``) in its docstring, shown by ``help()``, and the examples run (issue 19)."""

from __future__ import annotations

import doctest
import inspect
import os
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import omnical
import omnical._omnical
import omnical.fleet

# Examples that are shown but not run, and why (the rule: as few as possible).
NOT_RUN = {
    "omnical.fleet.calibrate_fleet": "starts a Dask cluster (seconds); tests/test_fleet.py runs it",
}


def public() -> dict[str, Any]:
    """Qualified name -> object: the package's ``__all__``, the compiled module's public names and
    omnical.fleet's public functions and classes (constants have no docstrings of their own)."""
    found: dict[str, Any] = {}
    for module, names in (
        (omnical, omnical.__all__),
        (omnical._omnical, [n for n in dir(omnical._omnical) if not n.startswith("_")]),
        (omnical.fleet, [n for n in vars(omnical.fleet) if not n.startswith("_")]),
    ):
        for name in names:
            obj = getattr(module, name)
            if not (inspect.isclass(obj) or callable(obj)):
                continue  # CATALOGUE, __version__, fleet's thresholds
            if module is omnical.fleet and not str(getattr(obj, "__module__", "")).startswith("omnical.fleet."):
                continue  # fleet's imports (PathLike's Union, ...); its own names come from its modules
            key = f"omnical.{name}" if module is not omnical.fleet else f"omnical.fleet.{name}"
            found.setdefault(key, obj)
    return found


PUBLIC = public()


def test_the_list_is_complete() -> None:
    # A guard against an empty or shrunken selection (then the tests below could not fail).
    for name in ("omnical.train", "omnical.Model", "omnical.export", "omnical.cli_main", "omnical.fleet.analyse",
                 "omnical.Effect", "omnical.DatasetError", "omnical.fleet.FleetResult"):
        assert name in PUBLIC, name
    assert len(PUBLIC) >= 43


@pytest.mark.parametrize("name", sorted(PUBLIC))
def test_has_an_example(name: str) -> None:
    doc = inspect.getdoc(PUBLIC[name]) or ""
    assert ">>> " in doc, f"{name} has no runnable example (>>>) in its docstring"
    assert doc.splitlines()[0].strip(), f"{name}: the docstring's first line is empty"


@pytest.mark.parametrize("name", sorted(PUBLIC))
def test_example_runs(name: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.chdir(tmp_path)  # examples that write files write them here
    obj = PUBLIC[name]
    globs: dict[str, Any] = {"omnical": omnical, "np": np, "Path": Path}
    if name.startswith("omnical.fleet."):
        globs.update(vars(omnical.fleet))
    test = doctest.DocTestParser().get_doctest(inspect.getdoc(obj) or "", globs, name, None, 0)
    if name in NOT_RUN:
        assert all(e.options.get(doctest.SKIP) for e in test.examples), f"{name}: an example not run is marked SKIP"
        return
    assert not any(e.options.get(doctest.SKIP) for e in test.examples), f"{name}: a skipped example; run it or list it in NOT_RUN"
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    out: list[str] = []
    runner.run(test, out=out.append)
    assert runner.failures == 0, "".join(out)
    assert runner.tries > 0 and os.getcwd() == str(tmp_path)
