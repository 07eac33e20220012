"""The analysis of a motion as files for a researcher: JSON (everything, exact) and CSV (tables).

JSON: core's own ``MotionAnalysis.to_dict()`` (events with isolating intervals, intervals, the
sign table, the exact polynomials a_i, ŝ0, ŝ1, ŝ1,0 as parseable strings, the paper's case) plus,
for each event, its exact form: the closed form when its defining factor has degree <= 2
(``(12 - 2*sqrt(2))/17``), otherwise the minimal polynomial and the isolating interval; and the
motion as typed. CSV: one table with a ``table`` column ("event", "interval", "sign row").
"""

from __future__ import annotations

import csv
import io
import json
from typing import Any

from core.algebra.closedform import closed_form, polynomial_text

from .analysis import AnalysisView
from .motion import MotionModel

__all__ = ["analysis_json", "analysis_csv"]


def analysis_json(model: MotionModel, an: AnalysisView) -> dict[str, Any]:
    """The whole analysis, exact, JSON-ready."""
    out = an.result.to_dict(polynomials=True)
    for d, ev in zip(out["events"], an.result.events, strict=True):
        form = closed_form(ev.time)
        d["closed_form"] = form
        d["minimal_polynomial"] = None if form is not None and ev.time.poly.degree() <= 2 else polynomial_text(ev.time)
    out["motion"] = model.texts()
    out["preset"] = model.preset
    return out


def analysis_csv(model: MotionModel, an: AnalysisView) -> str:
    """Events, intervals and the sign table as one CSV table (exact values as text).

    Examples:
        >>> from app.scene.pair.motion import load_motion
        >>> from core import analyse
        >>> m = load_motion(preset="circles-crossing", motion=None)
        >>> text = analysis_csv(m, AnalysisView.of(analyse(m.A, m.B, m.interval)))
        >>> text.splitlines()[1]
        'event,1,-1,-1,-1,-1,tangent,change,,,,,,,,,'
    """
    data = analysis_json(model, an)
    n = an.n
    a_cols = [f"a{i}" for i in range(n, -1, -1)]
    head = ["table", "index", "t", "exact", "lo", "hi", "relation", "kind", *a_cols, "s0", "s1", "s1,0", "var", "rule"]
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(head)
    blank = [""] * (len(a_cols) + 5)
    for k, e in enumerate(data["events"], start=1):
        exact = e["closed_form"] or e["minimal_polynomial"]
        w.writerow(["event", k, e["value"], exact, *e["isolating"], e["relation"], e["kind"], *blank])
    for k, iv in enumerate(data["intervals"], start=1):
        lo = "" if iv["lo"] is None else iv["lo"]["value"]
        hi = "" if iv["hi"] is None else iv["hi"]["value"]
        w.writerow(["interval", k, iv["sample"], "", lo, hi, iv["relation"], "", *blank])
    for k, r in enumerate(data["sign_table"], start=1):
        w.writerow(["sign row", k, r["t"], "", "", "", r["relation"], r["where"], *r["a"], r["s0"], r["s1"], r["s10"], r["var"], r["rule"]])
    return buf.getvalue()


def dumps(data: dict[str, Any]) -> bytes:
    """JSON bytes for a download (UTF-8, indented)."""
    return json.dumps(data, indent=2, ensure_ascii=False).encode()
