"""The fleet view's statistics: robust z-scores across robots, per-robot trends over sessions, and the
findings (outliers, trends, diagnosed effects, flagged robots) in words."""

from __future__ import annotations

import math
import re
from typing import Any, Optional, Sequence

OUTLIER_Z = 3.5
"""Robust z-score (median / MAD, Iglewicz and Hoaglin) above which a robot is an outlier."""
TREND_T = 3.0
"""A trend is flagged when its slope is this many standard errors from zero ..."""
MIN_RADIUS_SLOPE_PCT = 0.3
"""... and, for a wheel's effective radius, at least this large [% of design per session]."""
MIN_EFFECT_SLOPE_REL = 0.1
"""... and, for an effect's parameter, at least this fraction of its largest |value| per session."""


def _median(values: Sequence[float]) -> float:
    v = sorted(values)
    n = len(v)
    return 0.0 if n == 0 else (v[n // 2] if n % 2 else 0.5 * (v[n // 2 - 1] + v[n // 2]))


def robust_z(values: Sequence[float], floor: float = 0.0) -> list[float]:
    """Robust z-scores 0.6745 (x - median) / MAD (Iglewicz and Hoaglin); ``floor`` bounds the MAD from
    below (e.g. by the values' typical standard error, so that a fleet of near-identical robots does not
    turn noise into outliers). All zeros when the MAD and the floor are 0.

    >>> [round(z, 2) for z in robust_z([1.0, 1.1, 0.9, 1.0, 3.0])]
    [0.0, 0.67, -0.67, 0.0, 13.49]
    """
    med = _median(values)
    mad = max(_median([abs(x - med) for x in values]), floor)
    if mad == 0:
        return [0.0 for _ in values]
    return [0.6745 * (x - med) / mad for x in values]


def trend(x: Sequence[float], y: Sequence[float], se: Sequence[Optional[float]]) -> Optional[dict[str, float]]:
    """Straight-line fit of ``y`` over ``x`` (weighted by 1/se² when every se is known): slope, its
    standard error (the larger of the one from the stated errors and the one from the scatter when there
    are more than 2 points), intercept. None for fewer than 2 points or one x.

    >>> t = trend([0, 1, 2], [1.0, 0.9, 0.8], [0.01, 0.01, 0.01])
    >>> round(t["slope"], 3), round(t["intercept"], 3)
    (-0.1, 1.0)
    """
    n = len(x)
    if n < 2 or len(set(x)) < 2:
        return None
    known = all(s is not None and s > 0 for s in se)
    w = [1.0 / (s * s) for s in se] if known else [1.0] * n  # type: ignore[operator]
    sw = sum(w)
    xm = sum(wi * xi for wi, xi in zip(w, x)) / sw
    ym = sum(wi * yi for wi, yi in zip(w, y)) / sw
    sxx = sum(wi * (xi - xm) ** 2 for wi, xi in zip(w, x))
    slope = sum(wi * (xi - xm) * (yi - ym) for wi, xi, yi in zip(w, x, y)) / sxx
    intercept = ym - slope * xm
    se_stated = math.sqrt(1.0 / sxx) if known else 0.0
    se_scatter = 0.0
    if n > 2:
        chi2 = sum(wi * (yi - intercept - slope * xi) ** 2 for wi, xi, yi in zip(w, x, y)) / (n - 2)
        se_scatter = math.sqrt(chi2 / sxx)
    return {"slope": slope, "slope_se": max(se_stated, se_scatter), "intercept": intercept, "n": float(n)}


def _quantities(rows: Sequence[dict[str, Any]]) -> list[str]:
    """Numeric per-session quantities to analyse: the wheels' effective radii, the fitted parameters and
    the diagnosed effects' parameters (each with a ``_se`` column)."""
    names: list[str] = []
    for r in rows:
        for k in r:
            if k.endswith("_se") and k[:-3] in r and k[:-3] not in names:
                names.append(k[:-3])
    radius = sorted(n for n in names if n.startswith("radius_"))
    return radius + [n for n in names if not n.startswith("radius_")]


def analyse(rows: Sequence[dict[str, Any]]) -> dict[str, Any]:
    """The fleet view's findings from the rows (ordered, see :func:`order_sessions`):

    - ``outliers``: per quantity, robots whose latest session is a robust outlier (|z| > :data:`OUTLIER_Z`);
    - ``trends``: per robot and quantity with 2+ sessions, the slope per session and its standard error;
      ``flagged`` trends are |slope| > :data:`TREND_T` standard errors and of a size that matters;
    - ``effects``: per robot, the sessions whose diagnosis names an effect;
    - ``flagged``: robots with any of the above, and ``reasons`` per robot in words.

    >>> rows = [{"robot": f"r{i}", "session": "s00", "status": "ok", "radius_a_pct": x, "radius_a_pct_se": 0.05}
    ...         for i, x in enumerate([0.1, -0.1, 0.0, 0.2, 4.0])]
    >>> analyse(order_sessions(rows))["flagged"]
    ['r4']
    """
    ok = [r for r in rows if r.get("status") == "ok"]
    quantities = _quantities(ok)
    robots = sorted({r["robot"] for r in ok})
    latest = {rb: [r for r in ok if r["robot"] == rb][-1] for rb in robots}
    outliers: dict[str, list[dict[str, Any]]] = {}
    for q in quantities:
        have = [(rb, latest[rb][q], latest[rb].get(f"{q}_se")) for rb in robots if latest[rb].get(q) is not None]
        if len(have) < 3:
            continue
        ses = [s for _, _, s in have if s is not None]
        z = robust_z([v for _, v, _ in have], floor=_median(ses) if ses else 0.0)
        found: list[dict[str, Any]] = [{"robot": rb, "value": v, "z": zi} for (rb, v, _), zi in zip(have, z) if abs(zi) > OUTLIER_Z]
        if found:
            outliers[q] = found
    trends: list[dict[str, Any]] = []
    for rb in robots:
        rs = [r for r in ok if r["robot"] == rb]
        for q in quantities:
            pts = [(r["session_index"], r[q], r.get(f"{q}_se")) for r in rs if r.get(q) is not None]
            t = trend([p[0] for p in pts], [p[1] for p in pts], [p[2] for p in pts])
            if t is None:
                continue
            largest = max(abs(p[1]) for p in pts)
            if q.startswith("radius_"):
                big = abs(t["slope"]) >= MIN_RADIUS_SLOPE_PCT
            elif "." in q:
                big = abs(t["slope"]) >= MIN_EFFECT_SLOPE_REL * largest
            else:
                big = False  # raw matrix entries: shown, the wheels' radii carry the verdict
            sig = t["slope_se"] == 0 or abs(t["slope"]) > TREND_T * t["slope_se"]
            trends.append({"robot": rb, "quantity": q, **t, "flagged": bool(big and sig), "sessions": len(pts)})
    effects: dict[str, list[dict[str, Any]]] = {}
    for r in ok:
        if r.get("verdict"):
            effects.setdefault(r["robot"], []).append({"session": r["session"], "effect": r["verdict"], "text": r.get("verdict_text", "")})
    reasons: dict[str, list[str]] = {}
    for q, found in outliers.items():
        for o in found:
            reasons.setdefault(o["robot"], []).append(f"{_label(q)} {_fmt(o['value'], q)} is an outlier (robust z {o['z']:+.1f})")
    for tr in trends:
        if tr["flagged"]:
            reasons.setdefault(tr["robot"], []).append(_trend_text(tr, with_robot=False))
    for rb, es in effects.items():
        names = sorted({e["effect"] for e in es})
        reasons.setdefault(rb, []).append(
            f"diagnosis names {', '.join(names)} in session(s) {', '.join(e['session'] for e in es)}"
        )
    return {
        "quantities": quantities,
        "robots": robots,
        "outliers": outliers,
        "trends": trends,
        "effects": effects,
        "reasons": reasons,
        "flagged": sorted(reasons),
        "errors": [{"robot": r["robot"], "session": r["session"], "error": r.get("error", "")} for r in rows if r.get("status") != "ok"],
    }


def _label(q: str) -> str:
    m = re.match(r"^radius_(\w+)_pct$", q)
    if m:
        return f"wheel {m.group(1)}: effective radius"
    return q


def _fmt(v: float, q: str) -> str:
    return f"{v:+.2f} %" if q.endswith("_pct") else f"{v:.4g}"


def _trend_text(t: dict[str, Any], with_robot: bool = True) -> str:
    """"robot r17, wheel b: effective radius -0.90 ± 0.05 % per session, wear"."""
    q = t["quantity"]
    who = f"robot {t['robot']}, " if with_robot else ""
    if q.startswith("radius_"):
        what = "wear" if t["slope"] < 0 else "growing"
        return f"{who}{_label(q)} {t['slope']:+.2f} ± {t['slope_se']:.2f} % per session, {what}"
    return f"{who}{q} {t['slope']:+.4g} ± {t['slope_se']:.2g} per session, drift"
