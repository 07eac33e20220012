"""Witness endpoints: whole JSON bodies on hand-checkable exact cases, and the 422s.

Golden values by hand: unit circles with centres 3 apart must both grow by 3/2 to touch, and the
plane x = 3/2 separates them; centres 2 apart touch at (1, 0) with P(T) = -(T + 1)(T - 1)^2
(double root T* = 1); centres 1 apart overlap and (1/2, 0) is inside both; centres (0, 0) and
(1, 1) give mu* = sqrt(2)/2, a root of 2x^2 - 1.
"""

from __future__ import annotations

from fractions import Fraction

import pytest
from fastapi.testclient import TestClient

from app.api import ApiSettings, create_api


def circle(x, y=0, r=1):
    x, y, r = Fraction(x), Fraction(y), Fraction(r)
    return [[1, 0, str(-x)], [0, 1, str(-y)], [str(-x), str(-y), str(x * x + y * y - r * r)]]


UNIT = circle(0)


@pytest.fixture(scope="module")
def client():
    with TestClient(create_api(ApiSettings(max_digits=60))) as c:
        yield c


def test_contact_scale_separate(client):
    r = client.post("/api/contact-scale", json={"a": UNIT, "b": circle(3)})
    assert r.status_code == 200
    assert r.json() == {
        "relation": "separate",
        "kind": "ellipse",
        "lo": "3/2",
        "hi": "3/2",
        "approx": 1.5,
        "margin": 0.5,
        "margin_text": "50 % apart",
        "exact": None,
        "certified_by": "exact",
    }


def test_contact_scale_tangent_and_overlap(client):
    r = client.post("/api/contact-scale", json={"a": UNIT, "b": circle(2)}).json()
    assert (r["relation"], r["lo"], r["hi"], r["margin_text"]) == ("tangent", "1", "1", "touching")
    r = client.post("/api/contact-scale", json={"a": UNIT, "b": circle("1.94")}).json()
    assert (r["relation"], r["lo"], r["margin_text"]) == ("overlap", "97/100", "overlapping by 3 %")


def test_contact_scale_exact_irrational(client):
    r = client.post("/api/contact-scale", json={"a": UNIT, "b": circle(1, 1), "exact": True, "digits": 30}).json()
    assert r["relation"] == "overlap"
    ex = r["exact"]
    assert ex["value"] == "0.707106781186547524400844362105"  # sqrt(2)/2 to 30 digits
    assert ex["exact"] is None and [int(c) for c in ex["polynomial"]] == [-1, 0, 2]
    lo, hi = (Fraction(v) for v in ex["isolating"])
    assert 2 * lo * lo < 1 < 2 * hi * hi
    blo, bhi = Fraction(r["lo"]), Fraction(r["hi"])
    assert 2 * blo * blo <= 1 <= 2 * bhi * bhi and bhi - blo <= Fraction(1, 10**12) * bhi


def test_contact_scale_shapes_and_floats(client):
    body = {"a": {"center": [0, 0, 0], "semi_axes": [2, 1, 1]}, "b": {"center": [5, 0, 0], "semi_axes": [1, 1, 1]}}
    r = client.post("/api/contact-scale", json=body).json()
    assert (r["kind"], r["lo"], r["hi"]) == ("ellipsoid", "5/3", "5/3")  # along x: 5 = mu (2 + 1)
    body = {"a": [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, -1.0]], "b": [[1.0, 0.0, -4.0], [0.0, 1.0, 0.0], [-4.0, 0.0, 15.0]], "rtol": 1e-6}
    r = client.post("/api/contact-scale", json=body).json()
    assert (r["relation"], r["lo"], r["hi"]) == ("separate", "2", "2")  # floats bracket it, an exact check pins 2
    r = client.post("/api/separating-plane", json={k: body[k] for k in ("a", "b")}).json()
    assert (r["normal"], r["offset"], r["certified_by"]) == (["1", "0"], "2", "float")  # binary64 input: floats certify x = 2


def test_separating_plane(client):
    r = client.post("/api/separating-plane", json={"a": UNIT, "b": circle(3)})
    assert r.status_code == 200
    assert r.json() == {
        "relation": "separate",
        "sentence": "separate: this plane separates them",
        "normal": ["1", "0"],
        "offset": "3/2",
        "unit_normal_approx": [1.0, 0.0],
        "offset_approx": 1.5,
        "support_a": "1",
        "support_b": "2",
        "gap_lower_bound": 1.0,
        "certified_by": "exact",
    }


@pytest.mark.parametrize(("b", "word"), [(circle(2), "tangent"), (circle(1), "overlap")])
def test_separating_plane_422(client, b, word):
    r = client.post("/api/separating-plane", json={"a": UNIT, "b": b})
    assert r.status_code == 422
    assert word in r.json()["detail"] and "no plane separates" in r.json()["detail"]


def test_contact_point_tangent(client):
    r = client.post("/api/contact-point", json={"a": UNIT, "b": circle(2), "digits": 5})
    assert r.status_code == 200
    one = {"value": "1", "approx": 1.0, "exact": "1", "isolating": ["1", "1"], "polynomial": None}
    zero = {"value": "0", "approx": 0.0, "exact": "0", "isolating": ["0", "0"], "polynomial": None}
    assert r.json() == {
        "relation": "tangent",
        "sentence": "tangent: they touch here",
        "point": [one, zero],
        "normal": [one, zero],
        "pencil_root": one,
        "certified_by": "exact",
    }


def test_contact_point_overlap_and_separate(client):
    r = client.post("/api/contact-point", json={"a": UNIT, "b": circle(1)}).json()
    assert r["relation"] == "overlap" and r["sentence"] == "overlap: this point is inside both"
    assert [c["exact"] for c in r["point"]] == ["1/2", "0"] and r["normal"] is None
    r = client.post("/api/contact-point", json={"a": UNIT, "b": circle(3)})
    assert r.status_code == 422 and "separate" in r.json()["detail"]


def test_witness(client):
    w = client.post("/api/witness", json={"a": UNIT, "b": circle(3)}).json()
    assert (w["relation"], w["sentence"], w["margin_text"]) == ("separate", "separate: this plane separates them", "50 % apart")
    assert w["plane"]["offset"] == "3/2" and w["point"] is None
    w = client.post("/api/witness", json={"a": UNIT, "b": circle(2)}).json()
    assert w["relation"] == "tangent" and [c["exact"] for c in w["point"]["point"]] == ["1", "0"]
    assert w["plane"] is None and w["contact_scale"]["lo"] == "1"
    w = client.post("/api/witness", json={"a": UNIT, "b": circle(1)}).json()
    assert w["sentence"] == "overlap: this point is inside both"


@pytest.mark.parametrize("path", ["/api/contact-scale", "/api/separating-plane", "/api/contact-point", "/api/witness"])
def test_bad_input(client, path):
    hyperbola = [[1, 0, 0], [0, -1, 0], [0, 0, -1]]
    r = client.post(path, json={"a": hyperbola, "b": UNIT})
    assert r.status_code == 422 and "a is not an ellipse" in r.json()["detail"]
    r = client.post(path, json={"a": UNIT, "b": [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, -1]]})
    assert r.status_code == 422 and "both must be ellipses" in r.json()["detail"]


def test_limits(client):
    r = client.post("/api/contact-scale", json={"a": UNIT, "b": circle(3), "digits": 61, "exact": True})
    assert r.status_code == 422 and "over the limit of 60" in r.json()["detail"]
    r = client.post("/api/contact-scale", json={"a": UNIT, "b": circle(3), "rtol": 0})
    assert (r.status_code, r.json()) == (422, {"detail": [{"loc": ["body", "rtol"], "msg": "Input should be greater than 0", "type": "greater_than"}]})


@pytest.mark.parametrize("route", ["/api/contact-scale", "/api/separating-plane", "/api/contact-point", "/api/witness"])
def test_witness_routes_refuse_json_edges_like_classify(client, route):
    """The same JSON edge as /api/classify: a number that underflows is refused, not changed."""
    text = '{"a": [[1, 0, 0], [0, 1, 0], [0, 0, -1]], "b": [[1, 0, -3], [0, 1, 0], [-3, 0, 1e-400]]}'
    r = client.post(route, content=text, headers={"content-type": "application/json"})
    assert r.status_code == 422 and "underflows to 0 as a float" in r.text


@pytest.mark.parametrize(
    "pair",
    [
        # issue 21: floats at 1e-300 (JSON numbers: the binary64 values they are)
        {"a": [[2.0**-1000, 0, 0], [0, 2.0**-1000, 0], [0, 0, -(2.0**-1000)]], "b": [[1e-300, 0, -3e-300], [0, 1e-300, 0], [-3e-300, 0, 8e-300]]},
        # exact decimal strings far outside the float range: unit circles 3 apart, matrices times 10^+-900
        {"a": [["1e900", "0", "0"], ["0", "1e900", "0"], ["0", "0", "-1e900"]], "b": [["1e-900", "0", "-3e-900"], ["0", "1e-900", "0"], ["-3e-900", "0", "8e-900"]]},
        # space scaled by 10^400: the circles' entries reach 10^800
        {"a": [[1, 0, 0], [0, 1, 0], [0, 0, "-1e800"]], "b": [[1, 0, "-3e400"], [0, 1, 0], ["-3e400", 0, "8e800"]]},
    ],
)
def test_every_route_answers_at_any_scale(client, pair):
    """explain and every witness route answer pairs that classify answers, with short texts."""
    r = client.post("/api/explain", json=pair)
    assert r.status_code == 200, r.text
    e = r.json()
    assert e["relation"] == "separate" and all(len(q["text"]) <= 16 for q in e["coefficients"])
    cs = client.post("/api/contact-scale", json=pair).json()
    lo, hi = Fraction(cs["lo"]), Fraction(cs["hi"])
    assert cs["relation"] == "separate" and lo <= Fraction(3, 2) <= hi and hi - lo <= Fraction(1, 10**12) * hi
    assert client.post("/api/separating-plane", json=pair).status_code == 200
    assert client.post("/api/witness", json=pair).json()["relation"] == "separate"
    assert client.post("/api/contact-point", json=pair).status_code == 422  # separate: no common point
