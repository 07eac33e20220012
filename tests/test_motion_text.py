"""Core owns the motion's text (issue 23, item 3): one reader, one grammar, each expression parsed once.

* :func:`core.moving.motions.read_interval` is the one grammar of intervals: an open end is None,
  "none", -inf / inf / infinity / -infinity / +inf / +infinity (any case, on its side), or a float
  infinity; the library, the HTTP API and the scene accept exactly the same texts.
* :func:`core.moving.motions.read_motion` builds the exact matrix while reading: every
  expression is parsed once on the API path (was twice), and an error names its place.
* One JSON form of an algebraic number (events, intervals and witnesses alike).
* The layers: core.algebra imports nothing above it (was: qsqrt imported core.moving.polysign).
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest
from fastapi.testclient import TestClient
from flint import fmpq, fmpq_poly

import core.moving.motions as motions
from app.api import ApiSettings, create_api
from app.jobs import analyse_job
from app.scene.pair.motion import MotionError
from app.scene.pair.motion import read_interval as scene_read_interval
from core import analyse
from core.moving.motions import ExpressionError, read_interval, read_motion
from core.shapes.limits import SERVER

ROOT = Path(__file__).resolve().parents[1]
OPEN_LO = ["none", "None", "-inf", "-INF", "-infinity", "-Infinity"]
OPEN_HI = ["none", "inf", "+inf", "infinity", "+infinity", "Infinity"]


def circle(x: str) -> dict:
    return {"shape": {"center": [0, 0], "semi_axes": [1, 1]}, "translation": [x, "0"]}


@pytest.mark.parametrize("lo", OPEN_LO)
@pytest.mark.parametrize("hi", OPEN_HI)
def test_every_open_end_is_read_the_same_in_pairs_and_in_text(lo, hi):
    assert read_interval((lo, hi)) == read_interval(f"{lo}, {hi}") == read_interval(f" {lo} ; {hi} ") == (None, None)
    assert read_interval((lo, "3/2")) == (None, fmpq(3, 2))
    assert read_interval(("-0.25", hi)) == (fmpq(-1, 4), None)


@pytest.mark.parametrize("end", ["inf", "+inf", "infinity", "+Infinity"])
def test_an_infinity_on_the_wrong_side_is_refused(end):
    with pytest.raises(ValueError, match=r"^interval lo = .* is on the wrong side$"):
        read_interval((end, "0"))
    with pytest.raises(ValueError, match=r"^interval hi = .* is on the wrong side$"):
        read_interval(("0", "-" + end.lstrip("+")))


@pytest.mark.parametrize(
    "interval, message",
    [
        (("1", "1"), "empty interval: need lo < hi, got [1, 1]"),
        ("1", "interval: expected 'lo, hi' (none, -inf or inf for an open end), got '1'"),
        (("0", "1e1001"), "interval hi: exponent out of range in '1e1001': |e| <= 1000 after 'e'"),
        (("x", "1"), None),
    ],
)
def test_bad_intervals_say_what_is_wrong(interval, message):
    with pytest.raises(ValueError) as e:
        read_interval(interval, SERVER)
    if message is not None:
        assert str(e.value) == message
    else:
        assert str(e.value).startswith("interval lo: ")


def test_the_api_the_scene_and_the_library_accept_the_same_open_ends():
    """Was: the scene accepted "none" and refused "-infinity"; core and the API the opposite."""
    for lo, hi in [("-infinity", "none"), ("none", "Infinity"), ("-inf", "+inf")]:
        assert scene_read_interval(f"{lo}, {hi}") == (None, None)
        assert [e.value for e in analyse([["1", "0", "-t"], ["0", "1", "0"], ["-t", "0", "t^2 - 1"]],
                                         [["1", "0", "t"], ["0", "1", "0"], ["t", "0", "t^2 - 1"]], (lo, hi)).events] == ["-1", "1"]
    with TestClient(create_api(ApiSettings())) as c:
        for interval in (["-infinity", "none"], [None, "infinity"], ["none", None]):
            r = c.post("/api/analyse", json={"a": circle("t"), "b": circle("-t"), "interval": interval})
            assert r.status_code == 200, r.text
            assert ([e["value"] for e in r.json()["events"]], r.json()["interval"]) == (["-1", "1"], [None, None])
    with pytest.raises(MotionError, match="is on the wrong side"):
        scene_read_interval("inf, 0")


def test_each_expression_is_parsed_once_on_the_api_path(monkeypatch):
    """analyse_job (the API's and the scene's job) parses every expression string exactly once."""
    seen: list[str] = []
    real = motions.parse_expression

    def counting(text, *args, **kwargs):
        seen.append(text)
        return real(text, *args, **kwargs)

    monkeypatch.setattr(motions, "parse_expression", counting)
    a = {"shape": {"center": ["0", "0"], "semi_axes": ["1", "2"]}, "translation": ["2*t - 1", "t^2"],
         "rotation": {"quaternion": ["1", "t"]}}
    b = {"matrix": [["1", "0", "-t"], ["0", "1", "0"], ["-t", "0", "t^2 - 1"]]}
    r = analyse_job(a, b, ["-3", "3"], 20, SERVER)
    assert sorted(seen) == sorted(["0", "0", "1", "2", "2*t - 1", "t^2", "1", "t", *["1", "0", "-t", "0", "1", "0", "-t", "0", "t^2 - 1"]])
    assert r.events  # the analysis ran on the motions read once


def test_read_motion_names_the_place_of_an_error():
    with pytest.raises(ExpressionError) as e:
        read_motion(circle("(1e1000)^64*t"), limits=SERVER, name="a")
    assert (e.value.path, str(e.value).split(": ")[0]) == ("a.translation[0]", "a.translation[0]")
    assert e.value.reason.startswith("constant too large: about 2^")
    with pytest.raises(ValueError, match=r"^b: matrix is not symmetric: entry \(0,2\) = t but \(2,0\) = 0$"):
        read_motion({"matrix": [["1", "0", "t"], ["0", "1", "0"], ["0", "0", "-1"]]}, name="b")
    with pytest.raises(ValueError, match=r"^shape\.center\[1\]: unexpected 'y'"):
        read_motion({"shape": {"center": ["0", "y"], "semi_axes": [1, 1]}})


def test_one_json_form_of_an_algebraic_number():
    """Events and interval ends carry the polynomial that witness values carry."""
    from core.moving.presets import preset

    p = preset("example-29")
    r = analyse(p["A"], p["B"], p["interval"], digits=10)
    keys = {"value", "approx", "exact", "isolating", "polynomial"}
    for e in r.to_dict()["events"]:
        assert keys <= set(e) and e["exact"] is None
        poly = fmpq_poly([int(c) for c in e["polynomial"]])
        lo, hi = (fmpq(*(int(v) for v in (x.split("/") + ["1"])[:2])) for x in e["isolating"])
        assert poly(lo) * poly(hi) < 0  # a root of the polynomial lies between
    for iv in r.to_dict()["intervals"]:
        for end in (iv["lo"], iv["hi"]):
            assert end is None or set(end) == keys


def test_core_algebra_imports_nothing_above_it():
    """Not even inside a function (was: qsqrt.float_sign_at imported core.moving.polysign)."""
    above = ("moving", "witness", "bodies", "fixed", "formulae")
    for path in sorted((ROOT / "core" / "algebra").glob("*.py")):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom):
                module = node.module or ""
                target = module.split(".")[0] if node.level == 2 else module.split(".")[1] if module.startswith("core.") else ""
                assert target not in above, f"{path.name} imports {'.' * node.level}{module}"
