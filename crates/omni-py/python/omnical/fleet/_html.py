"""The fleet report (``OUT/fleet.html``): one self-contained page in the style of ``omnical report`` (inline
CSS and SVG, no scripts, no fetches)."""

from __future__ import annotations

import html
import math
from typing import Any, Sequence

from .. import __version__
from ._analysis import _trend_text

STYLE = (
    "body{font-family:system-ui,-apple-system,'Segoe UI',sans-serif;max-width:960px;margin:2em auto;"
    "padding:0 1em;color:#222;line-height:1.45}h1{font-size:1.6em;margin-bottom:.2em}h2{margin-top:1.8em;"
    "border-bottom:1px solid #ddd;padding-bottom:.2em}table{border-collapse:collapse;margin:.6em 0}"
    "td,th{border:1px solid #ddd;padding:.25em .6em;text-align:right;font-variant-numeric:tabular-nums}"
    "th{background:#f5f5f5}td.l,th.l{text-align:left}figure{margin:1.2em 0}figure svg{max-width:100%;height:auto;"
    "border:1px solid #eee}figcaption{color:#555;font-size:.93em}.verdict{background:#eef7ee;border-left:4px solid "
    "#2ca02c;padding:.6em 1em}.warn{background:#fdf3e7;border-left:4px solid #ff7f0e;padding:.6em 1em}"
    ".note{color:#777;font-size:.9em}code{background:#f3f3f3;padding:0 .25em}"
)
BLUE, RED, GREY = "#1f77b4", "#d62728", "#999999"


def _e(s: Any) -> str:
    return html.escape(str(s), quote=True)


def _num(v: Any, digits: int = 4) -> str:
    if v is None or (isinstance(v, float) and not math.isfinite(v)):
        return "–"
    if isinstance(v, float):
        return f"{v:.{digits}g}"
    return _e(v)


def page(rows: Sequence[dict[str, Any]], a: dict[str, Any], *, interrupted: bool = False) -> str:
    """The whole page."""
    ok = [r for r in rows if r.get("status") == "ok"]
    h = [
        '<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8">'
        '<meta name="viewport" content="width=device-width, initial-scale=1">'
        f"<title>omnical fleet</title><style>{STYLE}</style></head><body>\n<h1>omnical fleet</h1>\n",
        f'<p class="note">omnical {_e(__version__)} · {len(a["robots"])} robots · {len(rows)} robot-sessions '
        f"({len(rows) - len(ok)} failed) · outliers: robust z-score (median / MAD) beyond ±3.5 on each robot's "
        "latest session · trends: slope per session with its standard error</p>\n",
    ]
    if interrupted:
        h.append('<p class="warn"><b>Interrupted.</b> Only the robot-sessions that finished are shown.</p>\n')
    if a["flagged"]:
        items = "".join(f"<li><b>{_e(rb)}</b>: {_e('; '.join(a['reasons'][rb]))}</li>" for rb in a["flagged"])
        h.append(f'<div class="warn"><b>Robots to look at.</b><ul>{items}</ul></div>\n')
    else:
        h.append('<p class="verdict"><b>Verdict.</b> No robot is an outlier, none drifts over its sessions, and '
                 "no diagnosis names a missing effect.</p>\n")
    h.append(_sessions_table(rows))
    h.append(_distributions(ok, a))
    h.append(_trends(ok, a))
    h.append(_effects(ok, a))
    h.append("</body></html>\n")
    return "".join(h)


def _sessions_table(rows: Sequence[dict[str, Any]]) -> str:
    radii = sorted({k for r in rows for k in r if k.startswith("radius_") and not k.endswith("_se")})
    head = "".join(f"<th>{_e(k[len('radius_'):-len('_pct')])} radius %</th>" for k in radii)
    out = [
        '<h2 id="sessions">Robot-sessions</h2>\n<table><tr><th class="l">robot</th><th class="l">session</th>'
        f"<th>Eq. 6 design</th><th>Eq. 6 fitted</th><th>path RMS fitted</th>{head}<th class=\"l\">verdict</th></tr>\n"
    ]
    for r in rows:
        if r.get("status") != "ok":
            out.append(
                f'<tr><td class="l">{_e(r["robot"])}</td><td class="l">{_e(r["session"])}</td>'
                f'<td class="l" colspan="{4 + len(radii)}">error: {_e(r.get("error", ""))}</td></tr>\n'
            )
            continue
        cells = "".join(
            f"<td>{_num(r.get(k), 3)} ± {_num(r.get(k + '_se'), 2)}</td>" if r.get(k) is not None else "<td>–</td>"
            for k in radii
        )
        verdict = r.get("verdict") or ("none" if r.get("diagnosed") else "not diagnosed")
        out.append(
            f'<tr><td class="l">{_e(r["robot"])}</td><td class="l">{_e(r["session"])}</td>'
            f"<td>{_num(r.get('cost_design'))}</td><td>{_num(r.get('cost_fitted'))}</td>"
            f"<td>{_num(r.get('objective_fitted'))}</td>{cells}<td class=\"l\">{_e(verdict)}</td></tr>\n"
        )
    out.append("</table>\n")
    if any(r.get("diagnosed") is False for r in rows):
        out.append('<p class="note">Diagnosis ran only on sessions whose fitted path cost is off (above 1.5× the '
                   "fleet's median or a robust outlier); the others show “not diagnosed”.</p>\n")
    return "".join(out)


def _strip(values: list[tuple[str, float]], flagged: set[str], unit: str) -> str:
    """One parameter's values across robots as a dot strip (SVG), outliers in red."""
    w, hgt, pad = 640, 54, 40
    vs = [v for _, v in values]
    lo, hi = min(vs), max(vs)
    if hi == lo:
        lo, hi = lo - 1e-9 - abs(lo) * 1e-6, hi + 1e-9 + abs(hi) * 1e-6
    x = lambda v: pad + (w - 2 * pad) * (v - lo) / (hi - lo)  # noqa: E731
    dots = []
    for rb, v in values:
        c = RED if rb in flagged else BLUE
        dots.append(f'<circle cx="{x(v):.1f}" cy="24" r="5" fill="{c}" fill-opacity="0.75"><title>{_e(rb)}: {v:.6g} {_e(unit)}</title></circle>')
        if rb in flagged:
            dots.append(f'<text x="{x(v):.1f}" y="14" font-size="11" text-anchor="middle" fill="{RED}">{_e(rb)}</text>')
    axis = (
        f'<line x1="{pad}" y1="38" x2="{w - pad}" y2="38" stroke="{GREY}"/>'
        f'<text x="{pad}" y="51" font-size="11" text-anchor="middle">{lo:.4g}</text>'
        f'<text x="{w - pad}" y="51" font-size="11" text-anchor="middle">{hi:.4g}</text>'
    )
    return f'<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 {w} {hgt}" width="{w}" height="{hgt}" font-family="sans-serif">{axis}{"".join(dots)}</svg>'


def _distributions(ok: Sequence[dict[str, Any]], a: dict[str, Any]) -> str:
    out = ['<h2 id="distributions">Parameters across robots</h2>\n<p class="note">Each robot\'s latest session; '
           "red: a robust outlier (|z| &gt; 3.5). Effective wheel radii are the fitted matrix columns' lengths "
           "against the design's.</p>\n"]
    latest = {}
    for r in ok:
        latest[r["robot"]] = r
    for q in a["quantities"]:
        values = [(rb, r[q]) for rb, r in sorted(latest.items()) if r.get(q) is not None]
        if len(values) < 2:
            continue
        flagged = {o["robot"] for o in a["outliers"].get(q, [])}
        unit = "%" if q.endswith("_pct") else ""
        label = f"wheel {q[len('radius_'):-len('_pct')]}: effective radius against design (%)" if q.startswith("radius_") else q
        out.append(f"<figure>{_strip(values, flagged, unit)}<figcaption>{_e(label)}</figcaption></figure>\n")
    return "".join(out)


def _trend_svg(pts: list[tuple[int, float, Any]], t: dict[str, Any], colour: str) -> str:
    w, hgt, pad = 300, 140, 34
    xs = [p[0] for p in pts]
    ys = [p[1] for p in pts] + [t["intercept"] + t["slope"] * x for x in xs]
    lo, hi = min(ys), max(ys)
    span = hi - lo or 1e-9
    lo, hi = lo - 0.1 * span, hi + 0.1 * span
    x0, x1 = min(xs), max(xs)
    X = lambda v: pad + (w - 2 * pad) * (v - x0) / ((x1 - x0) or 1)  # noqa: E731
    Y = lambda v: hgt - pad + (2 * pad - hgt) * (v - lo) / (hi - lo)  # noqa: E731
    line = f'<line x1="{X(x0):.1f}" y1="{Y(t["intercept"] + t["slope"] * x0):.1f}" x2="{X(x1):.1f}" y2="{Y(t["intercept"] + t["slope"] * x1):.1f}" stroke="{colour}" stroke-dasharray="4 3"/>'
    dots = "".join(f'<circle cx="{X(x):.1f}" cy="{Y(y):.1f}" r="4" fill="{colour}"/>' for x, y, _ in pts)
    axis = (
        f'<line x1="{pad}" y1="{hgt - pad}" x2="{w - pad}" y2="{hgt - pad}" stroke="{GREY}"/>'
        f'<text x="{w / 2}" y="{hgt - 8}" font-size="11" text-anchor="middle">session</text>'
        f'<text x="4" y="{Y(hi - 0.1 * span) + 4:.1f}" font-size="10">{hi - 0.1 * span:.3g}</text>'
        f'<text x="4" y="{Y(lo + 0.1 * span) + 4:.1f}" font-size="10">{lo + 0.1 * span:.3g}</text>'
    )
    return f'<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 {w} {hgt}" width="{w}" height="{hgt}" font-family="sans-serif">{axis}{line}{dots}</svg>'


def _trends(ok: Sequence[dict[str, Any]], a: dict[str, Any]) -> str:
    out = ['<h2 id="trends">Trends over sessions</h2>\n']
    flagged = [t for t in a["trends"] if t["flagged"]]
    if flagged:
        out.append("<ul>" + "".join(f"<li>{_e(_trend_text(t))}</li>" for t in flagged) + "</ul>\n")
        for t in flagged:
            pts = [(r["session_index"], r[t["quantity"]], r.get(t["quantity"] + "_se")) for r in ok if r["robot"] == t["robot"] and r.get(t["quantity"]) is not None]
            out.append(f"<figure>{_trend_svg(pts, t, RED)}<figcaption>{_e(_trend_text(t))}</figcaption></figure>\n")
    else:
        out.append('<p class="verdict">No parameter drifts over the sessions of any robot.</p>\n')
    rad = [t for t in a["trends"] if t["quantity"].startswith("radius_") or "." in t["quantity"]]
    if rad:
        out.append('<table><tr><th class="l">robot</th><th class="l">quantity</th><th>sessions</th><th>slope per session</th>'
                   '<th>standard error</th><th class="l">flag</th></tr>\n')
        for t in rad:
            out.append(
                f'<tr><td class="l">{_e(t["robot"])}</td><td class="l">{_e(t["quantity"])}</td><td>{t["sessions"]}</td>'
                f'<td>{t["slope"]:+.4g}</td><td>{t["slope_se"]:.2g}</td><td class="l">{"<b>drift</b>" if t["flagged"] else ""}</td></tr>\n'
            )
        out.append("</table>\n")
    return "".join(out)


def _effects(ok: Sequence[dict[str, Any]], a: dict[str, Any]) -> str:
    out = ['<h2 id="effects">Diagnosed effects</h2>\n']
    if not a["effects"]:
        out.append('<p class="note">No diagnosis names a missing effect.</p>\n')
        return "".join(out)
    out.append('<table><tr><th class="l">robot</th><th class="l">session</th><th class="l">effect</th><th class="l">verdict</th></tr>\n')
    for rb, es in sorted(a["effects"].items()):
        for e in es:
            out.append(f'<tr><td class="l">{_e(rb)}</td><td class="l">{_e(e["session"])}</td><td class="l">{_e(e["effect"])}</td><td class="l">{_e(e["text"])}</td></tr>\n')
    out.append("</table>\n")
    return "".join(out)
