"""The fleet view's files: ``OUT/fleet.csv`` (and ``fleet.parquet`` with pyarrow) and ``OUT/fleet.html``,
each written atomically by the library (``_omnical._write_atomic``), as every omnical result file is."""

from __future__ import annotations

import csv
import io
from pathlib import Path
from typing import Any, Sequence

from .. import _omnical
from ._sessions import PathLike


def _columns(rows: Sequence[dict[str, Any]]) -> list[str]:
    first = ["robot", "session", "session_index", "status", "error", "start_s", "runs", "seconds", "model_file"]
    cols = [c for c in first if any(c in r for r in rows)]
    for r in rows:
        for k in r:
            if k not in cols:
                cols.append(k)
    return cols


def write_table(rows: Sequence[dict[str, Any]], out: PathLike) -> list[Path]:
    """``OUT/fleet.csv`` (one row per robot-session, empty cells for missing values), and
    ``OUT/fleet.parquet`` when pyarrow is importable. Returns the files written.

    >>> import tempfile
    >>> out = Path(tempfile.mkdtemp())
    >>> _ = write_table([{"robot": "r00", "session": "s00", "cost_fitted": 0.01}], out)
    >>> (out / "fleet.csv").read_text().splitlines()[1]
    'r00,s00,0.01'
    """
    out = Path(out)
    cols = _columns(rows)
    text = io.StringIO()
    w = csv.writer(text, lineterminator="\n")
    w.writerow(cols)
    for r in rows:
        w.writerow(["" if r.get(c) is None else (repr(r[c]) if isinstance(r[c], float) else r[c]) for c in cols])
    files = [out / "fleet.csv"]
    _omnical._write_atomic(files[0], text.getvalue().encode("utf-8"))
    try:
        import pyarrow as pa  # type: ignore[import-not-found, unused-ignore]
        import pyarrow.parquet as pq  # type: ignore[import-not-found, unused-ignore]
    except ImportError:
        return files
    table = pa.Table.from_pylist([{c: r.get(c) for c in cols} for r in rows])
    parquet = io.BytesIO()
    pq.write_table(table, parquet)
    path = out / "fleet.parquet"
    _omnical._write_atomic(path, parquet.getvalue())
    return files + [path]


def write_fleet_view(rows: Sequence[dict[str, Any]], analysis: dict[str, Any], out: PathLike, *, interrupted: bool = False) -> list[Path]:
    """The table (:func:`write_table`) and ``OUT/fleet.html``. Returns the files written.

    >>> import tempfile
    >>> rows = [{"robot": "r00", "session": "s00", "status": "ok", "cost_fitted": 0.01}]
    >>> [p.name for p in write_fleet_view(rows, analyse(rows), tempfile.mkdtemp())][-1]
    'fleet.html'
    """
    from . import _html

    out = Path(out)
    files = write_table(rows, out)
    page = _html.page(rows, analysis, interrupted=interrupted)
    path = out / "fleet.html"
    _omnical._write_atomic(path, page.encode("utf-8"))
    return files + [path]
