"""Text of the GUI panels: readout of one decision, sign table, event list, intervals bar.

Pure functions from plain data (``core.explain(...).to_dict()``, analysis rows) to Markdown /
HTML strings; the session assigns them to ``add_markdown``/``add_html`` handles only when the
text changed. No maths here.
"""

from __future__ import annotations

import html
from collections.abc import Mapping, Sequence
from typing import Any

from ..common.shapes import RELATION_HEX

__all__ = [
    "relation_badge",
    "readout_markdown",
    "sign_char",
    "intervals_bar_html",
    "sign_table_markdown",
    "degrees_text",
    "analysed_text",
    "legend_html",
    "copy_button",
    "events_html",
    "guide_link_html",
    "GUIDE_CONCEPTS",
    "GUIDE_CLASS",
    "HIDDEN",
    "hidden_badge",
]

_SUB = {"s0": "s<sub>0</sub>", "s1": "s<sub>1</sub>", "s10": "s<sub>1,0</sub>"}


def sign_char(s: int | None) -> str:
    """"+", "-", "0" or "?" (sign not certified).

    Examples:
        >>> [sign_char(s) for s in (1, -1, 0, None)]
        ['+', '-', '0', '?']
    """
    return {1: "+", -1: "-", 0: "0"}.get(s, "?") if s is not None else "?"


def relation_badge(relation: str | None, palette: Mapping[str, str] = RELATION_HEX) -> str:
    """HTML badge of a relation in its colour (grey "unknown" for None)."""
    if relation is None:
        return _grey_badge("unknown")
    color = palette[relation]
    fg = "#000" if relation == "tangent" else "#fff"
    return (
        f'<span style="background:{color};color:{fg};padding:1px 6px;border-radius:4px;'
        f'font-weight:bold">{relation.upper()}</span>'
    )


def _fmt(q: dict[str, Any] | None) -> str:
    if q is None:
        return "not needed"
    exact = q.get("exact")
    if exact is not None and len(exact) <= 18:
        val = exact
    elif q.get("approx") is None or q["approx"] != q["approx"]:  # NaN: only the sign is known
        val = "(sign only)"
    else:
        val = f"{q['approx']:.6g}"
        if q.get("bound") is not None:
            val += f" ± {q['bound']:.1e}"
    return f"{val} ({sign_char(q.get('sign'))})"


HIDDEN = "Predict first: press *Reveal the answer* (Lesson folder) to see the relation, or change the scene."
"""What stands for the relation while a lesson step's question is open (:attr:`AppState.answer_hidden`)."""


def _grey_badge(text: str) -> str:
    return f'<span style="background:#999;color:#fff;padding:1px 6px;border-radius:4px">{text}</span>'


def hidden_badge() -> str:
    """The grey badge shown instead of the relation while a lesson's question is open."""
    return _grey_badge("press Reveal")


def readout_markdown(
    expl: dict[str, Any] | None,
    *,
    where: str = "",
    error: str | None = None,
    witness: str | None = None,
    palette: Mapping[str, str] = RELATION_HEX,
    hidden: bool = False,
) -> str:
    """Markdown readout: relation, certification, P(T) coefficients, signs, Var, rule.

    Args:
        expl: ``core.explain(A, B).to_dict()``, or None when no pair is classified.
        where: what the numbers refer to (e.g. "at t = 0.7").
        error: message shown instead when the shapes are invalid.
        witness: Markdown of the witness (margin, sentence: ``WitnessView.readout()`` of
            :mod:`app.scene.pair.contact`), shown under the relation.
        palette: relation -> colour.
        hidden: a lesson's question is open: the coefficients and Var only (what to predict
            from); relation, witness, certification and rule give way to :data:`HIDDEN`.

    Examples:
        >>> print(readout_markdown(None, error="A.semi_axes: must be positive"))
        **Relation** <span style="background:#999;color:#fff;padding:1px 6px;border-radius:4px">unknown</span>
        <BLANKLINE>
        ⚠ A.semi_axes: must be positive
    """
    if expl is None:
        return f"**Relation** {relation_badge(None)}\n\n⚠ {html.escape(error or 'no shapes')}"
    n = expl["n"]
    if hidden:
        lines = [f"**Relation** {hidden_badge()} {where}".rstrip(), "", HIDDEN]
    else:
        lines = [f"**Relation** {relation_badge(expl['relation'], palette)} {where}".rstrip()]
        if witness:
            lines += ["", html.escape(witness, quote=False)]
        cert = "float filter (proven error bound)" if expl["certified_by"] == "float" else "exact arithmetic"
        lines.append("")
        lines.append(f"Certified by: {cert}")
    coeffs = expl["coefficients"]
    lines.append("")
    lines.append(f"P(T) = det(T A + B), degree {n}:")
    lines.append("")
    lines.append("| | value | sign |")
    lines.append("|---|---|---|")
    for q in reversed(coeffs):  # a_n .. a_0, the order of Var and of the sign table
        text = _fmt(q).rsplit(" (", 1)[0]
        lines.append(f"| a<sub>{q['name'][1:]}</sub> | {text} | {sign_char(q.get('sign'))} |")
    for key in ("s0", "s1", "s10"):
        q = expl.get(key)
        if q is None:
            lines.append(f"| {_SUB[key]} | not needed | |")
        else:
            text = _fmt(q).rsplit(" (", 1)[0]
            lines.append(f"| {_SUB[key]} | {text} | {sign_char(q.get('sign'))} |")
    signs = "".join(sign_char(q.get("sign")) for q in reversed(coeffs))
    lines.append("")
    lines.append(f"Var({', '.join(signs)}) = **{expl['var']}**")
    if not hidden:
        lines.append("")
        lines.append(f"Rule: {html.escape(expl['rule_text'])}")
    return "\n".join(lines)


def intervals_bar_html(
    lo: float,
    hi: float,
    segments: Sequence[tuple[float, float, str]],
    events: Sequence[tuple[float, str]],
    cursor: float | None,
    *,
    width: int = 300,
    palette: Mapping[str, str] = RELATION_HEX,
) -> str:
    """SVG bar along I = [lo, hi]: coloured segments per relation, ticks at events, a cursor.

    Args:
        lo: left end of the interval I (float, display only).
        hi: right end of I.
        segments: (a, b, relation) open intervals between events.
        events: (t, relation) of each event.
        cursor: current t (None: no cursor).
        width: drawing width in px (the SVG scales to the panel).
        palette: relation -> colour.
    """
    span = (hi - lo) or 1.0

    def x(t: float) -> float:
        return 6 + (width - 12) * (min(max(t, lo), hi) - lo) / span

    parts = [
        f'<svg viewBox="0 0 {width} 56" width="100%" xmlns="http://www.w3.org/2000/svg" '
        'style="font:10px sans-serif">'
    ]
    for a, b, rel in segments:
        parts.append(
            f'<rect x="{x(a):.1f}" y="6" width="{max(x(b) - x(a), 0.5):.1f}" height="14" '
            f'fill="{palette.get(rel, "#999")}"/>'
        )
    last_label = {0: -1e9, 1: -1e9}
    for k, (t, rel) in enumerate(events, start=1):
        xe = x(t)
        row = 0 if xe - last_label[0] >= 18 else 1  # close events: second row of labels
        last_label[row] = xe
        parts.append(
            f'<line x1="{xe:.1f}" y1="2" x2="{xe:.1f}" y2="{24 + 10 * row}" stroke="#000" stroke-width="1.5"/>'
            f'<circle cx="{xe:.1f}" cy="13" r="3.5" fill="{palette.get(rel, "#999")}" stroke="#000"/>'
            f'<text x="{xe:.1f}" y="{34 + 10 * row}" text-anchor="middle">α{k}</text>'
        )
    parts.append(f'<text x="6" y="53">{lo:.4g}</text>')
    parts.append(f'<text x="{width - 6}" y="53" text-anchor="end">{hi:.4g}</text>')
    if cursor is not None:
        xc = x(cursor)
        parts.append(
            f'<path d="M{xc - 5:.1f},0 L{xc + 5:.1f},0 L{xc:.1f},6 Z" fill="#1f4e9c"/>'
            f'<line x1="{xc:.1f}" y1="0" x2="{xc:.1f}" y2="24" stroke="#1f4e9c" stroke-width="2"/>'
        )
    parts.append("</svg>")
    return "".join(parts)


def degrees_text(degrees: dict[str, Any]) -> str:
    """One line on the degrees in t: the paper's s0, s1, s1,0 and the plotted ŝ_j = -s_j/a_n.

    Examples:
        >>> degrees_text({"a": [4, 4, 4, 4, 4], "s0": 22, "paper_s0": 26, "s1": 16, "paper_s1": 20,
        ...               "s10": 16, "paper_s10": 20})
        ' Degrees in t: a_i ≤ 4; s0 26, s1 20, s1,0 20 (plots and signs use ŝ = −s/a_n: 22, 16, 16).'
        >>> degrees_text({})
        ''
    """
    if not degrees:
        return ""

    def deg(k: str) -> str:
        d = degrees.get(k, -1)
        return "≡ 0" if d < 0 else str(d)

    names = (("s0", "s0"), ("s1", "s1"), ("s10", "s1,0"))
    paper = ", ".join(f"{label} {deg('paper_' + k)}" for k, label in names)
    hats = ", ".join(deg(k) for k, _ in names)
    return (
        f" Degrees in t: a_i ≤ {max(degrees.get('a', [0]))}; {paper}"
        f" (plots and signs use ŝ = −s/a_n: {hats})."
    )


def sign_table_markdown(rows: Sequence[dict[str, Any]], degree: int, palette: Mapping[str, str] = RELATION_HEX) -> str:
    """The paper's table: one row per event/interval sample, signs of a_i, s0, s1, s1,0, Var.

    Args:
        rows: dicts with "where" (label), "signs" (dict name -> sign), "var", "relation".
        degree: n (3 or 4): which a_i columns to show.
        palette: relation -> colour.
    """
    names = [f"a{i}" for i in range(degree, -1, -1)] + ["s0", "s1", "s10"]
    head = ["t"] + [f"a<sub>{n[1:]}</sub>" if n[0] == "a" else _SUB[n] for n in names] + ["Var", "relation"]
    out = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for r in rows:
        signs = r.get("signs", {})
        cells = [r["where"]] + [sign_char(signs.get(n)) if n in signs else "" for n in names]
        var = r.get("var")
        rel = r.get("relation") or ""
        color = palette.get(rel, "#999")
        cells += ["" if var is None else str(var), f'<span style="color:{color}">■</span> {rel}']
        out.append("| " + " | ".join(cells) + " |")
    return "\n".join(out)


def analysed_text(seconds: float, events: int, intervals: int, degrees: dict[str, Any]) -> str:
    """Status line once a motion is analysed.

    Examples:
        >>> analysed_text(0.0123, 1, 2, {})
        'Analysed in 0.01 s: 1 event, 2 intervals.'
    """
    return (
        f"Analysed in {seconds:.2f} s: {events} event{'s' * (events != 1)}, "
        f"{intervals} interval{'s' * (intervals != 1)}." + degrees_text(degrees)
    )


def legend_html(palette: Mapping[str, str] = RELATION_HEX) -> str:
    """The colour key: each relation's colour, its name and how the 3D view marks it besides colour.

    Examples:
        >>> "separate" in legend_html() and "#ffbf00" in legend_html()
        True
    """
    marks = {
        "separate": "apart (a plane fits between)",
        "tangent": "touching (opaque, contact point)",
        "overlap": "interiors meet (point inside both)",
    }
    items = "".join(
        f'<span style="white-space:nowrap;margin-right:10px"><span style="display:inline-block;width:11px;height:11px;'
        f'background:{palette[rel]};border:1px solid #333;vertical-align:-1px"></span> <b>{rel}</b>: {marks[rel]}</span> '
        for rel in ("separate", "tangent", "overlap")
    )
    return f'<div style="font-size:12px;line-height:1.6">{items}</div>'


_COPY_JS = (
    "(function(b){const t=b.dataset.url?new URL(b.dataset.copy,location.href).href:b.dataset.copy;"
    "const done=()=>{b.textContent='copied'};"
    "if(navigator.clipboard&&window.isSecureContext){navigator.clipboard.writeText(t).then(done,done)}"
    "else{const a=document.createElement('textarea');a.value=t;document.body.appendChild(a);a.select();"
    "document.execCommand('copy');a.remove();done()}})(this)"
)


GUIDE_CONCEPTS = "concepts.html"
"""The guide's page that says what the scene shows (docs/concepts.md), relative to the guide's address."""

GUIDE_CLASS = "tutorials/paper-class.html"
"""The guide's page on teaching with lessons (docs/tutorials/paper-class.md)."""


_SAME_HOST_JS = "const u=new URL(this.href);u.hostname=location.hostname;this.href=u.href"
"""On click: the guide on the host the page came from (the API listens where the scene does; the
address the server printed may be 127.0.0.1 for a wildcard host, wrong for a student's browser)."""


def guide_link_html(guide: str, page: str, label: str) -> str:
    """A small link to ``page`` of the documentation site at ``guide`` (opens in a new tab).

    Examples:
        >>> link = guide_link_html("http://127.0.0.1:8000/guide/", GUIDE_CONCEPTS, "What am I seeing?")
        >>> 'href="http://127.0.0.1:8000/guide/concepts.html"' in link
        True
    """
    href = html.escape(guide.rstrip("/") + "/" + page, quote=True)
    return (f'<div style="font-size:12px"><a href="{href}" target="_blank" rel="noopener" onclick="{_SAME_HOST_JS}">'
            f'{html.escape(label)}</a> '
            '<span style="color:#666">(the guide)</span></div>')


def copy_button(text: str, label: str = "copy", *, url: bool = False) -> str:
    """A small HTML button that copies ``text`` to the clipboard (for ``add_html``; the text is escaped).

    With ``url``, ``text`` is a path and the absolute address (the page's origin) is copied.

    Examples:
        >>> 'data-copy="(12 - 2*sqrt(2))/17"' in copy_button("(12 - 2*sqrt(2))/17")
        True
    """
    mark = ' data-url="1"' if url else ""
    return (
        f'<button type="button" data-copy="{html.escape(text, quote=True)}"{mark} onclick="{_COPY_JS}" '
        'style="font-size:11px;padding:0 5px;margin-left:4px;cursor:pointer">'
        f"{html.escape(label)}</button>"
    )


def events_html(events: Sequence[Any], palette: Mapping[str, str] = RELATION_HEX) -> str:
    """The event list: each alpha_k exactly, its relation and kind, a button copying its exact form.

    The exact form is the closed form when the defining factor has degree <= 2, else the minimal
    polynomial with the isolating interval.

    Args:
        events: :class:`app.scene.pair.analysis.EventView` objects.
        palette: relation -> colour.
    """
    if not events:
        return "No events: one relation on all of I."
    rows = []
    for ev in events:
        swatch = f'<span style="color:{palette.get(ev.relation, "#999")}">■</span>'
        exact = html.escape(ev.shown)
        if not ev.closed:
            exact += f' <span style="color:#666">({html.escape(ev.origin or "root of a polynomial")}: copy the exact form)</span>'
        rows.append(
            f'<div style="margin:2px 0">α{ev.k} {exact} {swatch} {ev.relation}, {ev.kind}'
            f"{copy_button(ev.definition)}</div>"
        )
    return '<div style="font-size:13px">' + "".join(rows) + "</div>"
