"""What the fields show is exactly what is certified: a seeded random sequence in a real browser.

Issue 22.1. A user (headless Chromium) types shapes (17-digit decimals, fractions, matrices, 2D
angles), retypes fields, picks presets, jumps to events, leaves the motion for static shapes,
presses Touch, switches 2D/3D and mistypes. After EVERY step the test reads from the page the
text of the Shape fields and the readout's relation, and an independent exact classification of
that text (``tests/oracle.py``: the positive roots of the exact P(T) by flint's certified root
isolation, on matrices that core builds exactly from the text) must equal the readout. During a
motion the fields must be marked as rounded ("≈"), the Preset must name what runs, and at a
rational t typed in the t box the oracle on the motion's exact matrices at t must equal it.

``SCENE_FIELDS_SEED`` / ``SCENE_FIELDS_STEPS`` choose another sequence (default: seed 22 and the CI
size of 12 steps, ~17 s in the suite; long runs: ``SCENE_FIELDS_STEPS=200``, see the README).
"""

from __future__ import annotations

import json
import math
import os
import random
import re
from decimal import Decimal
from fractions import Fraction

import numpy as np
import pytest
from oracle import oracle_relation
from test_browser_scene import choose, until

from core import quadric_from_axes
from core.moving.motions import matrix_at_exact, motion_from_dict

pytestmark = [
    pytest.mark.browser,
    pytest.mark.skipif(not os.path.exists("/usr/bin/chromium"), reason="needs Debian chromium at /usr/bin/chromium"),
]

SEED = int(os.environ.get("SCENE_FIELDS_SEED", "22"))
STEPS = int(os.environ.get("SCENE_FIELDS_STEPS", "12"))  # CI size; long runs: SCENE_FIELDS_STEPS=200 (README)
PRESETS = ["example-33", "circles-sqrt2", "example-29", "circles-crossing", "example-31"]

FIELD_JS = """(id) => {
  const label = Array.from(document.querySelectorAll('label')).find(l => l.htmlFor === id && l.offsetParent !== null);
  const row = label && label.closest('.mantine-Flex-root');
  const input = row && row.querySelector('input, textarea');
  return input ? input.value : null;
}"""
"""The text a field shows in the page, found by its label's ``for`` (the handle's id)."""


def field_text(page, handle) -> str:
    value = page.evaluate(FIELD_JS, handle._impl.uuid)
    assert value is not None, f"field {handle.label!r} is not on the page"
    return value


_HANDLED: dict[str, int] = {}
"""Handle uuid -> update callbacks the server has finished (:func:`_count_updates`)."""


def _count_updates(handle) -> None:
    """Count the server's update callbacks of ``handle`` as they finish (wrapped once).

    viser runs them in a thread pool after it stores the new value, so neither the value nor
    the session's idle state says that the edit was handled; the count does.
    """
    impl = handle._impl
    if impl.uuid in _HANDLED:
        return
    assert impl.update_cb, f"field {handle.label!r} has no server callback to wait for"
    _HANDLED[impl.uuid] = 0

    def wrap(cb):
        def run(event):
            try:
                return cb(event)
            finally:
                _HANDLED[impl.uuid] += 1

        return run

    impl.update_cb[:] = [wrap(cb) for cb in impl.update_cb]


def type_field(page, handle, text: str) -> None:
    """Type ``text`` into the field of ``handle`` in the page, press Enter, and wait until the
    server has handled it (Enter reaches the server over the websocket later: a check before
    that would read the old readout beside the new text)."""
    _count_updates(handle)
    before, changed = _HANDLED[handle._impl.uuid], handle.value != text
    box = page.locator(f'[aria-labelledby="label-{handle._impl.uuid}"]')
    box.wait_for(state="visible")
    box.fill(text)
    box.press("Enter")
    if changed:  # viser calls back only on a new value
        until(lambda: _HANDLED[handle._impl.uuid] >= before + len(handle._impl.update_cb), what=f"the server to handle {text!r}")


def readout_relation(page) -> str:
    m = re.search(r"Relation\s+(SEPARATE|TANGENT|OVERLAP|unknown)", page.evaluate("() => document.body.innerText"))
    assert m is not None, "no readout on the page"
    return m.group(1).lower()


# ---------------------------------------------------------------------------- the oracle on text
def numbers(text: str) -> list[Fraction]:
    return [Fraction(p) for p in text.replace(",", " ").replace(";", " ").split()]


def angle_quaternion(text: str) -> list[Fraction]:
    """The scene's documented meaning of a 2D angle θ: (cos θ/2, 0, 0, sin θ/2) in float64, exactly."""
    h = float(Fraction(text)) / 2
    return [Fraction(math.cos(h)), Fraction(0), Fraction(0), Fraction(math.sin(h))]


def shape_matrix(texts: dict[str, str], dim: int):
    """The exact matrix the Shape fields' text says (the Matrix field, else centre/axes/orientation)."""
    if texts["matrix"].strip():
        rows = [r for r in texts["matrix"].split(";") if r.strip()]
        return [numbers(r) for r in rows]
    for key in ("center", "semi_axes", "orientation"):
        assert not texts[key].startswith("≈"), f"static shapes with a rounded {key}: {texts}"
    center, axes = numbers(texts["center"]), numbers(texts["semi_axes"])
    o = numbers(texts["orientation"])
    if dim == 2 and len(o) == 1:
        o = None if o[0] == 0 else angle_quaternion(texts["orientation"])
    elif dim == 2:
        o = [o[0], Fraction(0), Fraction(0), o[1]] if len(o) == 2 else o
    return quadric_from_axes(center, axes, o, exact=True)


# ---------------------------------------------------------------------------- random input
def decimal(rng: random.Random, lo: float, hi: float) -> str:
    """A decimal with 1 to 17 significant digits (17: beyond what a float holds)."""
    digits = rng.choice([1, 2, 3, 6, 17, 17])
    x = rng.uniform(lo, hi)
    return f"{x:.{digits}g}" if digits < 17 else f"{x:.16f}"


def number(rng: random.Random, lo: float, hi: float) -> str:
    if rng.random() < 0.25:
        q = rng.randint(2, 9)
        return f"{rng.randint(int(lo * q), int(hi * q))}/{q}"
    return decimal(rng, lo, hi)


class Driver:
    """Runs random steps on one tab and checks the oracle after each."""

    def __init__(self, hs, rng: random.Random) -> None:
        self.hs, self.rng = hs, rng
        self.s = hs.session
        self.page = hs.page
        self.log: list[str] = []
        self.seen: set[str] = set()

    @property
    def dim(self) -> int:
        return self.s.state.dim

    def open_shape_folders(self) -> None:
        for name in ("A", "B"):
            h = self.s.ui.shapes[name].fields["center"]
            if self.page.evaluate(FIELD_JS, h._impl.uuid) is None:
                self.page.get_by_text(f"Shape {name}", exact=True).click()
                self.page.wait_for_function(f"(id) => ({FIELD_JS})(id) !== null", arg=h._impl.uuid)

    def settle(self) -> None:
        self.hs.session = self.s
        self.hs.wait_settled()

    # ------------------------------------------------------------------ steps
    def type_shape(self) -> None:
        name, dim, rng = self.rng.choice("AB"), self.dim, self.rng
        key = rng.choice(["center", "center", "semi_axes", "orientation", "matrix", "tangent", "tangent"])
        f = self.s.ui.shapes[name].fields
        if key == "tangent":  # unit sphere/circle and one of radius r: 1 + r apart, or not quite
            r = rng.choice(["1", "0.5", "0.75"])
            x = Decimal(1) + Decimal(r)  # centres x apart: tangent; 1e-17 more / 1e-18 less: separate / overlap
            text = str(rng.choice([x, x + Decimal("1e-17"), x - Decimal("1e-18")]).quantize(Decimal("1e-20")).normalize())
            type_field(self.page, self.s.ui.shapes["A"].fields["semi_axes"], ", ".join(["1"] * dim))
            self.settle()
            type_field(self.page, self.s.ui.shapes["A"].fields["center"], ", ".join(["0"] * dim))
            self.settle()
            type_field(self.page, self.s.ui.shapes["B"].fields["semi_axes"], ", ".join([r] * dim))
            self.settle()
            type_field(self.page, self.s.ui.shapes["B"].fields["center"], ", ".join([text] + ["0"] * (dim - 1)))
            self.log.append(f"tangent setup B centre {text}")
            return
        if key == "center":
            text = ", ".join(number(rng, -3, 3) for _ in range(dim))
        elif key == "semi_axes":
            text = ", ".join(number(rng, 0.3, 2.5) for _ in range(dim))
        elif key == "orientation":
            if dim == 2:  # an angle (radians) or a quaternion (w, 0, 0, z) about z
                text = rng.choice([decimal(rng, -3, 3), f"{rng.randint(1, 9)}, 0, 0, {rng.randint(-9, 9)}"])
            else:  # a quaternion w, x, y, z (need not be unit)
                text = ", ".join([str(rng.randint(1, 5)), *(number(rng, -2, 2) for _ in range(3))])
        else:  # an exact matrix typed: a shape's matrix as fractions or decimals
            c = [Fraction(number(rng, -3, 3)) for _ in range(dim)]
            a = [Fraction(number(rng, 0.5, 2)) for _ in range(dim)]
            M = quadric_from_axes(c, a, None, exact=True)
            text = "; ".join(", ".join(str(Fraction(int(v.p), int(v.q))) for v in row) for row in M)
        type_field(self.page, f[key], text)
        self.log.append(f"type {name}.{key} = {text}")

    def retype(self) -> None:
        name, key = self.rng.choice("AB"), self.rng.choice(["center", "semi_axes", "orientation"])
        h = self.s.ui.shapes[name].fields[key]
        text = field_text(self.page, h).removeprefix("≈ ")
        type_field(self.page, h, text)
        self.log.append(f"retype {name}.{key} = {text}")

    def mistype(self) -> None:
        name = self.rng.choice("AB")
        h = self.s.ui.shapes[name].fields["center"]
        type_field(self.page, h, "1, x")
        self.page.wait_for_function("() => document.body.innerText.includes('not a number')")
        self.log.append(f"mistype {name}.center")
        type_field(self.page, h, ", ".join(["1/3"] + ["0"] * (self.dim - 1)))

    def preset(self) -> None:
        name = self.rng.choice(PRESETS)
        choose(self.page, "Preset", name)
        until(lambda: self.s.state.motion is not None and self.s.state.motion.preset == name and self.s.ready.is_set()
              and self.s.state.analysis is not None, what=name)
        self.log.append(f"preset {name}")
        if self.rng.random() < 0.6 and self.s.state.analysis.events:
            k = self.rng.randint(1, len(self.s.state.analysis.events))
            self.page.get_by_role("button", name=f"Jump to α{k}", exact=False).click()
            until(lambda: self.s.state.event == k, what=f"α{k}")
            self.log.append(f"jump α{k}")
        elif self.rng.random() < 0.7:
            lo, hi = self.s.state.analysis.result.interval
            lo, hi = Fraction(str(lo if lo is not None else -2)), Fraction(str(hi if hi is not None else 2))
            t = lo + (hi - lo) * Fraction(self.rng.randint(1, 29), 30)
            type_field(self.page, self.s.ui.timeline.t_box, str(t))
            until(lambda: self.s.state.t_text == str(t) or self.s.state.event is not None or
                  (self.s.state.t_exact is None and Fraction(self.s.state.t) == t), what=f"t = {t}")
            self.log.append(f"t = {t}")

    def static(self) -> None:
        if self.s.state.motion is None:
            return self.type_shape()
        choose(self.page, "Preset", "(static shapes)")
        until(lambda: self.s.state.motion is None, what="static")
        self.log.append("static")

    def touch(self) -> None:
        if self.s.state.motion is not None:
            self.static()
            self.check()
        self.page.get_by_role("button", name="Touch: slide B to A").click()
        until(lambda: (self.s.state.motion is not None and self.s.state.motion.kind == "touch" and self.s.state.analysis is not None)
              or "touch" in self.s.state.errors, what="touch")
        self.log.append("touch" + (" (error)" if "touch" in self.s.state.errors else ""))

    def dimension(self) -> None:
        label = "2D ellipses" if self.dim == 3 else "3D ellipsoids"
        want = 2 if self.dim == 3 else 3
        choose(self.page, "Dimension", label, folder="View")
        until(lambda: self.s.state.dim == want and self.s.ready.is_set(), what=label)
        self.log.append(label)

    # ------------------------------------------------------------------ the check
    def check(self) -> None:
        self.settle()
        page, st = self.page, self.s.state
        texts = {name: {k: field_text(page, h) for k, h in self.s.ui.shapes[name].fields.items()} for name in "AB"}
        preset_shown = field_text(page, self.s.ui.motion.preset)
        shown = readout_relation(page)
        where = f"after {self.log[-1] if self.log else 'opening'} (seed {SEED}); fields {texts}"
        assert not any(k.startswith("shape") for k in st.errors), f"a field was refused: {st.errors} {where}"
        if st.motion is None:
            assert preset_shown == "(static shapes)", where
            want = oracle_relation(shape_matrix(texts["A"], self.dim), shape_matrix(texts["B"], self.dim))
            assert shown == want, f"readout {shown}, exact oracle on the fields' text {want} {where}"
            self.seen.add(want)
            return
        kind = st.motion.kind
        assert preset_shown == {"preset": st.motion.preset, "typed": "(typed motion)", "touch": "(Touch: B slides to A)"}[kind], where
        for name in "AB":  # computed poses: marked as rounded, never a number that looks exact
            for key in ("center", "semi_axes", "orientation"):
                assert texts[name][key].startswith("≈ "), where
        t_text = field_text(page, self.s.ui.timeline.t_box)
        try:
            t = Fraction(t_text)
        except ValueError:
            return  # an event (α_k, a closed form): certified by the analysis' own exact signs
        motions = [motion_from_dict(json.loads(field_text(page, self.s.ui.motion.fields[k]))) for k in "AB"]
        try:
            A, B = (matrix_at_exact(m, t) for m in motions)
        except ValueError:
            return  # entries irrational at t (sqrt in the motion): no rational matrices to test
        want = oracle_relation(A, B)
        assert shown == want, f"readout {shown} at t = {t_text}, exact oracle {want} {where}"
        self.seen.add(want)


def test_fields_always_show_what_is_certified(headless_scene):
    hs = headless_scene
    rng = random.Random(SEED)
    cfg = {"preset": None, "A": {"center": ["0", "0", "0"], "semi_axes": ["2", "1", "1"]},
           "B": {"center": ["3", "0", "0"], "semi_axes": ["1", "1", "1"]}}
    hs.open(cfg)
    d = Driver(hs, rng)
    d.open_shape_folders()
    d.check()
    actions = [d.type_shape] * 6 + [d.retype] * 2 + [d.preset] * 3 + [d.static] * 3 + [d.touch] * 2 + [d.mistype, d.dimension]
    for _ in range(STEPS):
        rng.choice(actions)()
        d.check()
    assert {"separate", "overlap"} <= d.seen, d.log  # the sequence went through different relations


ARROW_JS = """([name, dx]) => {
  const m = window.__viserMutable, root = m.nodeRefFromName[name], cam = m.camera, canvas = m.canvas;
  const V = root.position.constructor;
  let best = null;  // the visible cone of the gizmo's x arrow: in the node's own frame, farthest along +x
  root.traverse((o) => {
    if (o.type !== 'Mesh' || !o.visible || o.parent === root) return;
    const w = new V(); o.getWorldPosition(w);
    const p = root.worldToLocal(w.clone());
    if (Math.abs(p.y) < 1e-6 && Math.abs(p.z) < 1e-6 && p.x > 0.5 && (!best || p.x > best.p.x)) best = {p, w};
  });
  if (!best) return null;
  const rect = canvas.getBoundingClientRect();
  const screen = (v) => { const q = v.clone().project(cam); return [rect.left + (q.x + 1) / 2 * rect.width, rect.top + (1 - q.y) / 2 * rect.height]; };
  const to = root.localToWorld(new V(best.p.x + dx, 0, 0));
  return {from: screen(best.w), to: screen(to)};
}"""
"""Screen points of the x arrow of a gizmo and of where it is after moving it by dx along x."""


def test_dragging_a_gizmo_certifies_the_shape_the_fields_show(headless_scene):
    """Issue 22.4: a drag in the browser (mouse on B's gizmo arrow) moves B; afterwards the label on
    B and the readout name the certified relation, and the fields show B's new centre exactly
    (decimals, no "≈") with the exact oracle on that text equal to the readout."""
    hs = headless_scene
    # B left of A: its +x arrow points at A, in the middle of the canvas (not under the GUI panel)
    cfg = {"preset": None, "A": {"center": ["3", "0", "0"], "semi_axes": ["1", "1", "1"]},
           "B": {"center": ["0", "0", "0"], "semi_axes": ["1", "1", "1"]}, "gizmos": True}  # "Move the shapes" on
    s = hs.open(cfg)
    page = hs.page
    d = Driver(hs, random.Random(0))
    d.open_shape_folders()
    assert readout_relation(page) == "separate"
    pts = page.evaluate(ARROW_JS, ["/shapes/B", 1.6])
    assert pts is not None, "no gizmo arrow on B"
    page.mouse.move(*pts["from"])
    page.mouse.down()
    for k in range(1, 11):  # a user's drag: several pointer moves
        x = pts["from"][0] + (pts["to"][0] - pts["from"][0]) * k / 10
        y = pts["from"][1] + (pts["to"][1] - pts["from"][1]) * k / 10
        page.mouse.move(x, y)
    page.mouse.up()
    until(lambda: s.state.shapes["B"].center[0] > 1, what="B dragged towards A")
    d.log.append("drag B")
    d.check()  # fields exact, oracle on their text = readout
    centre = field_text(page, s.ui.shapes["B"].fields["center"])
    assert not centre.startswith("≈") and float(numbers(centre)[0]) > 1, centre
    assert readout_relation(page) == "overlap"
    assert s.views["B"].label.text == "B · overlap"  # the label sent to the page (viser keeps no ref to read it back)
    np.testing.assert_allclose(hs.drawn_pose("B")[:3], [float(v) for v in numbers(centre)], atol=1e-12)  # drawn as shown
    assert hs.mesh_color("B") == "#d62728"


def test_field_labels_are_tied_to_their_inputs(headless_scene):
    """Issue 22.4 (accessibility): every text field's label names its input, so a screen reader reads
    "Centre" for it and get_by_label finds it (viser's labels pointed at ids no input had)."""
    hs = headless_scene
    s = hs.open({"preset": "example-29", "t": 0.3})
    page = hs.page
    Driver(hs, random.Random(0)).open_shape_folders()
    page.wait_for_function("() => document.querySelectorAll('[aria-labelledby]').length > 10")
    assert page.get_by_label("t (exact)", exact=True).input_value() == s.ui.timeline.t_box.value
    centres = page.get_by_label("Centre", exact=True)
    assert centres.count() == 2
    assert [centres.nth(i).input_value() for i in range(2)] == [s.ui.shapes[n].fields["center"].value for n in "AB"]
    untied = page.evaluate("""() => Array.from(document.querySelectorAll('label[for]')).filter(l => l.offsetParent !== null
      && l.closest('.mantine-Flex-root')?.querySelector('input:not([type=file]), textarea')
      && !document.querySelector(`[aria-labelledby="${l.id}"]`)).map(l => l.textContent)""")
    assert untied == []
