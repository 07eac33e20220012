"""HTTP API (app.api): status codes and whole JSON bodies on hand-checkable exact cases.

Golden relations are checked by hand, not by the code under test: unit circles with centres 2
apart touch (P(T) = -(T + 1)(T - 1)^2), 2 + 1/10^9 apart they are separate, a circle of radius
1/2 inside the unit circle overlaps it; unit spheres 2 apart give P(T) = -(T + 1)^2 (T - 1)^2.
"""

from __future__ import annotations

import json
import math
import os
import re
import threading
import time
from fractions import Fraction

import pool_jobs
import pytest
from fastapi.testclient import TestClient

from app.api import ApiSettings, create_api
from app.api.deps import get_settings, get_workers
from app.workers import (
    WorkerBusy,
    WorkerCancelled,
    WorkerDied,
    WorkerFailed,
    WorkerPool,
    WorkerTimeout,
)
from core import InvalidInput
from core.formulae.decision import RULES


def circle(x, r=1):
    """Circle of radius r centred at (x, 0), exact entries as strings."""
    x, r = Fraction(x), Fraction(r)
    return [[1, 0, str(-x)], [0, 1, 0], [str(-x), 0, str(x * x - r * r)]]


def sphere(x, r=1):
    x, r = Fraction(x), Fraction(r)
    return [[1, 0, 0, str(-x)], [0, 1, 0, 0], [0, 0, 1, 0], [str(-x), 0, 0, str(x * x - r * r)]]


UNIT = [[1, 0, 0], [0, 1, 0], [0, 0, -1]]
UNIT_AT_2 = [[1, 0, -2], [0, 1, 0], [-2, 0, 3]]
SPHERE = [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, -1]]


def out(relation, certified_by="exact", kind="ellipse", method="adaptive"):
    return {"relation": relation, "certified_by": certified_by, "kind": kind, "method": method}


def assert_classified(body, expected):
    """Whole-body check; away from tangency either arithmetic may certify (a tangency is a
    zero, which only exact arithmetic certifies), so certified_by is pinned for tangent only."""
    if expected["relation"] != "tangent":
        assert body["certified_by"] in ("float", "exact")
        expected = {**expected, "certified_by": body["certified_by"]}
    assert body == expected


@pytest.fixture(scope="module")
def client():
    with TestClient(create_api(ApiSettings(scene_url="http://127.0.0.1:8080"))) as c:
        yield c


def post_raw(client, path, text):
    return client.post(path, content=text, headers={"content-type": "application/json"})


# --- /api/classify: golden relations -------------------------------------------------------

@pytest.mark.parametrize(
    "a, b, expected",
    [
        (UNIT, UNIT_AT_2, out("tangent")),  # integers: float filter cannot certify a zero
        (circle(0), circle(2), out("tangent")),
        (circle(0), circle(Fraction(2) + Fraction(1, 10**9)), out("separate")),
        (circle(0), circle(Fraction(2) - Fraction(1, 10**9)), out("overlap")),
        (circle(0), circle(0, Fraction(1, 2)), out("overlap")),  # nested
        (circle(0), circle(0), out("overlap")),  # identical
        ([[-v if isinstance(v, int) else v for v in row] for row in UNIT], UNIT_AT_2, out("tangent")),  # flipped signs
        (sphere(0), sphere(2), out("tangent", kind="ellipsoid")),
        (sphere(0), sphere(Fraction(2) + Fraction(1, 10**9)), out("separate", kind="ellipsoid")),
        (sphere(0), sphere(0, Fraction(1, 3)), out("overlap", kind="ellipsoid")),
    ],
)
def test_classify_golden(client, a, b, expected):
    r = client.post("/api/classify", json={"a": a, "b": b})
    assert r.status_code == 200, r.text
    assert_classified(r.json(), expected)


def test_classify_exact_method_and_float_method_on_tangency(client):
    r = client.post("/api/classify", json={"a": UNIT, "b": [[1, 0, -3], [0, 1, 0], [-3, 0, 8]], "method": "exact"})
    assert (r.status_code, r.json()) == (200, out("separate", method="exact"))
    # The float filter alone never certifies tangency: it abstains.
    r = client.post("/api/classify", json={"a": UNIT, "b": UNIT_AT_2, "method": "float"})
    assert (r.status_code, r.json()) == (200, out("undecided", None, method="float"))


def test_classify_far_apart_float_input_is_certified_by_the_filter(client):
    """Circles 10 apart (JSON ints and floats mixed): far from tangency, the float filter decides."""
    r = client.post("/api/classify", json={"a": UNIT, "b": [[1, 0, -10.0], [0, 1, 0], [-10.0, 0, 99]]})
    assert (r.status_code, r.json()) == (200, out("separate", "float"))
    r = client.post("/api/classify", json={"pairs": [{"a": UNIT, "b": [[1, 0, -3.5], [0, 1, 0], [-3.5, 0, 11.25]]}]})
    assert (r.status_code, r.json()) == (200, [out("separate", "float")])


def test_classify_batch_keeps_order(client):
    pairs = [
        {"a": circle(0), "b": circle(2)},
        {"a": circle(0), "b": circle(3)},
        {"a": sphere(0), "b": sphere("1/2")},
    ]
    r = client.post("/api/classify", json={"pairs": pairs, "method": "exact"})
    assert r.status_code == 200
    assert r.json() == [
        out("tangent", method="exact"),
        out("separate", method="exact"),
        out("overlap", kind="ellipsoid", method="exact"),
    ]


def test_classify_batch_error_names_the_pair(client):
    pairs = [{"a": circle(0), "b": circle(2)}, {"a": circle(0), "b": [[1, 0, 1], [0, 1, 0], [0, 0, -1]]}]
    r = client.post("/api/classify", json={"pairs": pairs})
    assert r.status_code == 422
    assert r.json()["detail"].startswith("pairs[1]: b is not symmetric: entry (0,2) = 1 but (2,0) = 0, a difference of 1 ")
    assert r.json()["detail"].endswith("pass (A + A.T) / 2")
    assert (r.json()["pair"], r.json()["matrix"]) == (1, "b")


def test_an_invalid_pair_is_validated_once_by_core_and_the_first_in_the_request_is_named(client, monkeypatch):
    """Core's on_invalid="raise" names the bad matrix; the API renames it to the request's names and
    does not validate again. Pairs of both sizes: the first bad one in request order is the answer."""
    import app.api.convert as convert

    calls = []
    monkeypatch.setattr(convert, "validate_quadric", lambda *a, **k: calls.append(a))
    not_an_ellipsoid = [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, -1, 0], [0, 0, 0, -1]]
    not_an_ellipse = [[1, 0, 0], [0, -1, 0], [0, 0, -1]]
    pairs = [{"a": circle(0), "b": circle(3)}, {"a": SPHERE, "b": not_an_ellipsoid}, {"a": not_an_ellipse, "b": circle(0)}]
    r = client.post("/api/classify", json={"pairs": pairs})
    assert r.status_code == 422 and (r.json()["pair"], r.json()["matrix"]) == (1, "b"), r.json()
    assert r.json()["detail"].startswith("pairs[1]: b is not an ellipsoid"), r.json()
    r = client.post("/api/classify", json={"pairs": pairs[:1] + pairs[2:] + pairs[1:2]})
    assert r.status_code == 422 and (r.json()["pair"], r.json()["matrix"]) == (1, "a"), r.json()
    assert r.json()["detail"].startswith("pairs[1]: a is not an ellipse"), r.json()
    assert calls == []  # validated once, by core


def test_batch_limit_from_overridden_settings():
    app = create_api()
    app.dependency_overrides[get_settings] = lambda: ApiSettings(max_batch=2)
    with TestClient(app) as c:
        pairs = [{"a": circle(0), "b": circle(3)}] * 3
        r = c.post("/api/classify", json={"pairs": pairs})
        assert (r.status_code, r.json()) == (422, {"detail": "batch of 3 pairs is over the limit of 2"})
        r = c.post("/api/classify", json={"pairs": pairs[:2], "method": "exact"})
        assert (r.status_code, r.json()) == (200, [out("separate", method="exact")] * 2)


# --- shapes given by centre / semi-axes / orientation -------------------------------------

@pytest.mark.parametrize(
    "a, b, expected",
    [
        ({"center": [0, 0], "semi_axes": [1, 1]}, {"center": ["2", 0], "semi_axes": [1, 1]}, out("tangent")),
        ({"center": [0, 0], "semi_axes": [1, 1]}, {"center": ["2.000000001", 0], "semi_axes": [1, 1]}, out("separate")),
        # ellipse 2 x 1 turned a quarter turn by the exact quaternion (1, 0, 0, 1): x-extent 1, touches x = 1
        ({"center": [0, 0], "semi_axes": [2, 1], "orientation": [1, 0, 0, 1]}, {"center": [2, 0], "semi_axes": [1, 1]}, out("tangent")),
        ({"center": [0, 0], "semi_axes": [2, 1]}, {"center": [2, 0], "semi_axes": [1, 1]}, out("overlap")),
        # quarter turn about x: body y (semi-axis 2) -> world z, so the z-extent is 2: touches z = 2
        ({"center": [0, 0, 0], "semi_axes": [1, 2, 3], "orientation": [1, 1, 0, 0]}, {"center": [0, 0, 3], "semi_axes": [1, 1, 1]}, out("tangent", kind="ellipsoid")),
        ({"center": [0, 0, 0], "semi_axes": [1, 2, 3], "orientation": [1, 1, 0, 0]}, {"center": [0, 0, 4], "semi_axes": [1, 1, 1]}, out("separate", kind="ellipsoid")),
        ({"center": [0, 0], "semi_axes": [1, 1]}, UNIT_AT_2, out("tangent")),  # a shape against a matrix
    ],
)
def test_classify_shapes_exact(client, a, b, expected):
    r = client.post("/api/classify", json={"a": a, "b": b})
    assert r.status_code == 200, r.text
    assert_classified(r.json(), expected)


def test_classify_shape_with_float_angle(client):
    # 2 x 1 ellipse turned by 0.5 rad (float path) against a unit circle 10 away: separate.
    a = {"center": [0.0, 0.0], "semi_axes": [2, 1], "orientation": 0.5}
    r = client.post("/api/classify", json={"a": a, "b": {"center": [10, 0], "semi_axes": [1, 1]}, "method": "exact"})
    assert (r.status_code, r.json()) == (200, out("separate", method="exact"))


# --- /api/explain ---------------------------------------------------------------------------

def q(name, v, sign):
    text = "0" if v == 0 else f"{v:.5e}"  # six significant digits, as explain writes them at any size
    return {"name": name, "approx": float(v), "exact": str(v), "bound": None, "sign": sign, "text": text}


def test_explain_tangent_circles(client):
    # P(T) = det(T A + B) = -(T + 1)(T - 1)^2 = -T^3 + T^2 + T - 1; double root at T = 1 > 0.
    r = client.post("/api/explain", json={"a": UNIT, "b": UNIT_AT_2})
    assert r.status_code == 200
    assert r.json() == {
        "n": 3,
        "relation": "tangent",
        "certified_by": "exact",
        "rule": "2d-s0=0",
        "rule_text": RULES["2d-s0=0"],
        "var": 2,
        "coefficients": [q("a0", -1, -1), q("a1", 1, 1), q("a2", 1, 1), q("a3", -1, -1)],
        "s0": q("s0", 0, 0),
        "s1": None,
        "s10": None,
        "subresultants_needed": ["s0"],
    }


def test_explain_tangent_spheres(client):
    # P(T) = -(T + 1)^2 (T - 1)^2 = -T^4 + 2T^2 - 1: s0 = s1 = 0 (gcd(P, P') has degree 2), Th. 24.1.
    r = client.post("/api/explain", json={"a": SPHERE, "b": sphere(2)})
    assert r.status_code == 200
    assert r.json() == {
        "n": 4,
        "relation": "tangent",
        "certified_by": "exact",
        "rule": "3d-s1=0",
        "rule_text": RULES["3d-s1=0"],
        "var": 2,
        "coefficients": [q("a0", -1, -1), q("a1", 0, 0), q("a2", 2, 1), q("a3", 0, 0), q("a4", -1, -1)],
        "s0": q("s0", 0, 0),
        "s1": q("s1", 0, 0),
        "s10": None,
        "subresultants_needed": ["s0", "s1"],
    }


def test_explain_rejects_batch_and_bad_matrix(client):
    r = client.post("/api/explain", json={"a": UNIT, "b": [[1, 0, 0], [0, -1, 0], [0, 0, -1]]})
    assert (r.status_code, r.json()) == (422, {"detail": "b is not an ellipse: its quadratic part is indefinite or semidefinite (a hyperbola, parabola or degenerate conic)", "matrix": "b"})
    r = client.post("/api/explain", json={"pairs": [{"a": UNIT, "b": UNIT_AT_2}]})
    assert r.status_code == 422
    assert [e["loc"] for e in r.json()["detail"]] == [["body", "a"], ["body", "b"], ["body", "pairs"]]


# --- malformed requests: 4xx with a message, never 500 ------------------------------------

@pytest.mark.parametrize(
    "b, detail",
    [
        ([[1, 0, 1], [0, 1, 0], [0, 0, -1]], "b is not symmetric: entry (0,2) = 1 but (2,0) = 0, a difference of 1 relative to the scale of rows 0 and 2 (rounding is accepted up to 9.5e-07); if this is rounding, pass (A + A.T) / 2"),
        ([[1, 0, 0], [0, -1, 0], [0, 0, -1]], "b is not an ellipse: its quadratic part is indefinite or semidefinite (a hyperbola, parabola or degenerate conic)"),
        ([[1, 0, 0], [0, 1, 0], [0, 0, 1]], "b has an empty interior: no real points (det > 0), not an ellipse"),
        ([[1, 0, 0], [0, 1, 0], [0, 0, 0]], "b is a degenerate ellipse (det = 0: a single point)"),
        ([[1, 0, 0], [0, 1, 0, 0], [0, 0, -1]], "b must be a 3x3 (ellipse) or 4x4 (ellipsoid) matrix, got 3x3/4"),
        (SPHERE, "a is 3x3 and b is 4x4: both must be ellipses (3x3) or both ellipsoids (4x4)"),
        ({"center": [0, 0], "semi_axes": [-1, 1]}, "b: semi-axes must be positive, got ['-1', '1']"),
        ({"center": [0, 0, 0], "semi_axes": [1, 1, 1], "orientation": 0.5}, "b: a 3D orientation is a quaternion [w, x, y, z], not an angle"),
        ({"center": [0, 0], "semi_axes": [1, 1, 1]}, "b: need 2 or 3 centre coordinates and as many semi-axes, got 2 and 3"),
        ({"center": [0, 0], "semi_axes": [1, 1], "orientation": [1, 1, 0, 0]}, "b: a 2D quaternion must rotate about z: (w, 0, 0, z)"),
        ({"center": [0, 0], "semi_axes": [1, 1], "orientation": [0, 0, 0, 0]}, "b: orientation quaternion is zero"),
        ({"center": [0.5, 0], "semi_axes": ["1e400", 1]}, "b: '1e400' is too large for a float (this shape is built in floats)"),
        # was "b is a degenerate ellipse (det = 0: a single point)": the float matrix of a unit circle
        # 1e8 from the origin rounds to a point; the builder says so and what to do
        ({"center": [1e8, 0], "semi_axes": [1, 1]}, "b: centre [100000000.0, 0.0] is more than 2^26 times the smallest "
         "semi-axis (1.0) from the origin: the float64 matrix would not be this shape (its constant term rounds by as "
         "much as the shape's own size); place the origin nearer the bodies"),
    ],
)
def test_core_rejections_are_422_with_message(client, b, detail):
    """core.InvalidInput answered once, 422: the message, and the matrix it names (the request's "b")."""
    r = client.post("/api/classify", json={"a": UNIT, "b": b})
    named = {"matrix": "b"} if detail.startswith("b") else {}  # "a is 3x3 and b is 4x4" is about the pair
    assert (r.status_code, r.json()) == (422, {"detail": detail, **named})


def err(loc, msg, type_="value_error"):
    return {"loc": loc, "msg": msg, "type": type_}


@pytest.mark.parametrize(
    "text, detail",
    [
        ('{"a": [[1,0,0],[0,1,0],[0,0,-1]], "b": [[1,0,NaN],[0,1,0],[0,0,-1]]}',
         [err(["body", "pair", "b", "matrix", 0, 2], "Value error, not a finite number: nan (NaN and infinity are not accepted)")]),
        ('{"a": [[1,0,0],[0,1,0],[0,0,-Infinity]], "b": [[1,0,0],[0,1,0],[0,0,-1]]}',
         [err(["body", "pair", "a", "matrix", 2, 2], "Value error, not a finite number: -inf (NaN and infinity are not accepted)")]),
        ('{"a": [[1,0,0],[0,1,0],[0,0,true]], "b": [[1,0,0],[0,1,0],[0,0,-1]]}',
         [err(["body", "pair", "a", "matrix", 2, 2], "Value error, a boolean is not a number: True")]),
        ('{"a": [[1,0,0],[0,1,0],[0,0,"-1/0"]], "b": [[1,0,0],[0,1,0],[0,0,"abc"]]}',
         [err(["body", "pair", "a", "matrix", 2, 2], "Value error, zero denominator in '-1/0'"),
          err(["body", "pair", "b", "matrix", 2, 2], "Value error, not a number: 'abc' (expected e.g. '3', '-0.25', '1e-3' or '3/7')")]),
        ('{"a": [[1,0],[0,1]], "b": [[1,0,0],[0,1,0],[0,0,-1]]}',
         [err(["body", "pair", "a", "matrix", 0], "List should have at least 3 items after validation, not 2", "too_short"),
          err(["body", "pair", "a", "matrix", 1], "List should have at least 3 items after validation, not 2", "too_short")]),
        ('{"a": [[1,0,0],[0,1,0],[0,0,-1]], "b": [[1,0,0],[0,1,0],[0,0,-1]], "method": "fast"}',
         [err(["body", "pair", "method"], "Input should be 'adaptive', 'float' or 'exact'", "literal_error")]),
        ('{"a": [[1,0,0],[0,1,0],[0,0,-1]]}', [err(["body", "pair", "b"], "Field required", "missing")]),
        ('{"pairs": []}', [err(["body", "batch", "pairs"], "List should have at least 1 item after validation, not 0", "too_short")]),
        ('[1, 2]', [err(["body", "pair"], "Input should be a valid dictionary or object to extract fields from", "model_attributes_type")]),
    ],
)
def test_malformed_bodies_are_422(client, text, detail):
    r = post_raw(client, "/api/classify", text)
    assert (r.status_code, r.json()) == (422, {"detail": detail})


@pytest.mark.parametrize(
    "text, detail",
    [
        ('{"a": [[1,0,0],[0,1,0],[0,0,-1]], "b": ', [err(["body", 39], "JSON decode error: Expecting value", "json_invalid")]),
        ('{"a": 1,}', [err(["body", 8], "JSON decode error: Expecting property name enclosed in double quotes", "json_invalid")]),
        ("", [err(["body"], "Field required", "missing")]),
    ],
)
def test_unreadable_bodies_are_400_as_the_schema_declares(client, text, detail):
    """400 "Unreadable body": no JSON to validate; 422 is for JSON that does not fit (above)."""
    r = post_raw(client, "/api/classify", text)
    assert (r.status_code, r.json()) == (400, {"detail": detail})
    assert "400" in client.get("/openapi.json").json()["paths"]["/api/classify"]["post"]["responses"]


def test_body_without_json_content_type_is_415(client):
    text = json.dumps({"a": UNIT, "b": UNIT_AT_2})
    r = client.post("/api/classify", content=text, headers={"content-type": "application/x-www-form-urlencoded"})
    assert (r.status_code, r.json()) == (415, {"detail": "send the body as JSON with the header 'content-type: application/json' (got 'application/x-www-form-urlencoded')"})
    r = client.post("/api/analyse", content=text)
    assert (r.status_code, r.json()) == (415, {"detail": "send the body as JSON with the header 'content-type: application/json' (no content-type header)"})
    r = client.post("/api/explain", content=text, headers={"content-type": "application/json; charset=utf-8"})
    assert (r.status_code, r.json()["relation"]) == (200, "tangent")  # read as JSON: the unit circles 2 apart


def test_huge_integer_and_long_string(client):
    big = 10**401
    r = client.post("/api/classify", json={"a": UNIT, "b": [[1, 0, 0], [0, 1, 0], [0, 0, big]]})
    assert (r.status_code, r.json()) == (422, {"detail": [err(["body", "pair", "b", "matrix", 2, 2], "Value error, integer too large (more than 400 digits); send it as a string fraction")]})
    r = client.post("/api/classify", json={"a": UNIT, "b": [[1, 0, 0], [0, 1, 0], [0, 0, "1" * 401]]})
    assert (r.status_code, r.json()) == (422, {"detail": [err(["body", "pair", "b", "matrix", 2, 2], "Value error, number string too long (401 > 400 characters)")]})


def test_deeply_nested_json_is_400_that_says_so(client):
    nested = "JSON nested too deeply: the body has more levels of [ and { than the JSON reader allows (about 1000); the inputs of this API need at most 5"
    for path in ("/api/classify", "/api/explain", "/api/analyse"):
        r = post_raw(client, path, "[" * 100_000 + "]" * 100_000)
        assert (r.status_code, r.json()) == (400, {"detail": nested})
    r = post_raw(client, "/api/classify", '{"pairs": ' + "[" * 50 + "]" * 50 + "}")  # deep but readable
    assert r.status_code == 422 and "nested" not in r.text


def test_large_bodies_are_read_off_the_event_loop(client, monkeypatch):
    """A body over ``INLINE_BYTES`` is read in a worker thread, so the server answers other
    requests meanwhile (10,000 moving bodies take ~0.2 s to read; a loaded run saw /healthz wait
    1.6 s behind one); a small body is read where it arrives. Same answers either way."""
    import asyncio

    import app.api.json_body as jb

    where: list[bool] = []
    real = jb.read_json

    def spy(body):
        try:
            asyncio.get_running_loop()
            where.append(True)  # on the event loop
        except RuntimeError:
            where.append(False)  # in a worker thread
        return real(body)

    monkeypatch.setattr(jb, "read_json", spy)
    small = {"a": UNIT, "b": UNIT_AT_2}
    big = {"pairs": [small] * 1000}  # the most one request may hold (ApiSettings.max_batch), ~85 KB
    assert len(json.dumps(small)) <= jb.INLINE_BYTES < len(json.dumps(big))
    r1, r2 = post_raw(client, "/api/classify", json.dumps(small)), post_raw(client, "/api/classify", json.dumps(big))
    assert where == [True, False]
    assert r1.status_code == r2.status_code == 200
    assert r2.json() == [r1.json()] * 1000


def test_body_size_limit_declared_and_streamed():
    with TestClient(create_api(ApiSettings(max_body_bytes=200))) as c:
        body = json.dumps({"a": UNIT, "b": circle("1/3", "1/7") + [] , "method": "exact"})
        assert len(body) < 200
        r = post_raw(c, "/api/classify", body)
        assert (r.status_code, r.json()) == (200, out("overlap", method="exact"))
        big = json.dumps({"pairs": [{"a": UNIT, "b": UNIT_AT_2}] * 10})
        r = post_raw(c, "/api/classify", big)
        assert (r.status_code, r.json()) == (413, {"detail": "request body too large: the limit is 200 bytes"})

        def chunks():  # no content-length: chunked upload
            for i in range(0, len(big), 50):
                yield big[i:i + 50].encode()

        r = c.post("/api/classify", content=chunks(), headers={"content-type": "application/json"})
        assert (r.status_code, r.json()) == (413, {"detail": "request body too large: the limit is 200 bytes"})


# --- health, docs, settings ------------------------------------------------------------------

def test_healthz_and_docs(client):
    r = client.get("/healthz")
    assert (r.status_code, r.json()) == (200, {"status": "ok", "analyses_running": 0, "max_concurrent_analyses": 2,
                                              "analyses_waiting": 0, "max_queued_analyses": 16,
                                              "large_bodies": 0, "max_large_bodies": 16})
    assert client.get("/docs").status_code == 200
    spec = client.get("/openapi.json").json()
    for path in ("/api/classify", "/api/explain", "/healthz"):
        assert path in spec["paths"]
    for path, ops in spec["paths"].items():
        for op in ops.values():
            assert "200" in op["responses"], (path, op)


@pytest.mark.parametrize("field, value", [("max_batch", 0), ("max_digits", -1), ("time_budget_s", 0.0), ("max_body_bytes", True)])
def test_settings_reject_nonsense(field, value):
    with pytest.raises(ValueError, match=field):
        ApiSettings(**{field: value})


# --- worker pool: time budget, busy, crashes ------------------------------------------------

def test_worker_pool_results_errors_and_timeout():
    pool = WorkerPool(1)
    assert pool.run(math.sqrt, 16.0, timeout=30) == 4.0
    with pytest.raises(ValueError, match="math domain error"):
        pool.run(math.sqrt, -1.0, timeout=30)
    t0 = time.monotonic()
    with pytest.raises(WorkerTimeout, match="time budget of 0.5 s"):
        pool.run(time.sleep, 30, timeout=0.5)
    assert time.monotonic() - t0 < 5
    assert pool.running == 0
    with pytest.raises(WorkerDied, match="exit code 3"):
        pool.run(os._exit, 3, timeout=30)
    with pytest.raises(WorkerFailed, match="TypeError"):
        pool.run(math.sqrt, "x", timeout=30)


def test_worker_pool_memory_cap():
    pool = WorkerPool(1, memory_mb=1024)
    with pytest.raises(WorkerDied, match=r"ran out of memory \(limit 1024 MB\)"):
        pool.run(bytearray, 3 * 1024**3, timeout=60)
    assert len(pool.run(bytearray, 1024, timeout=60)) == 1024


def test_worker_pool_refuses_when_busy():
    pool = WorkerPool(1)
    started = threading.Event()

    def slow():
        started.set()
        try:
            pool.run(time.sleep, 30, timeout=1.5)
        except WorkerTimeout:
            pass

    th = threading.Thread(target=slow)
    th.start()
    started.wait()
    deadline = time.monotonic() + 5
    while pool.running == 0 and time.monotonic() < deadline:
        time.sleep(0.01)
    with pytest.raises(WorkerBusy, match=r"^all 1 workers are busy$"):
        pool.run(math.sqrt, 4.0, timeout=5)
    th.join()
    assert pool.run(math.sqrt, 4.0, timeout=30) == 2.0


def _hold_the_slot(pool, release):
    """Start a job that holds the pool's only slot until ``release`` exists; its thread."""
    def hold():
        try:
            pool.run(pool_jobs.wait_for, str(release), timeout=120)
        except WorkerBusy:  # the test shut the pool down
            pass

    th = threading.Thread(target=hold, daemon=True)
    th.start()
    while pool.running == 0:  # the job has started
        time.sleep(0.01)
    return th


def test_worker_pool_queue_serves_callers_in_order_and_refuses_beyond_it(tmp_path):
    """Callers wait in turn (first come, first served); one more than the queue holds is refused."""
    pool = WorkerPool(1, max_waiting=3, max_wait_s=120)
    release, order = tmp_path / "release", tmp_path / "order"
    holder = _hold_the_slot(pool, release)
    waiters = []
    for k, name in enumerate("BCD"):
        th = threading.Thread(target=lambda name=name: pool.run(pool_jobs.log, str(order), name, timeout=60))
        th.start()
        waiters.append(th)
        while pool.waiting < k + 1:  # queued before the next one comes
            time.sleep(0.01)
    with pytest.raises(WorkerBusy, match=r"^all 1 workers are busy and 3 requests are waiting$"):
        pool.run(math.sqrt, 4.0, timeout=5)
    release.touch()
    for th in [holder, *waiters]:
        th.join()
    assert order.read_text().split() == ["B", "C", "D"]
    assert (pool.running, pool.waiting) == (0, 0)


def test_worker_pool_queue_wait_cancel_and_shutdown(tmp_path):
    """A caller leaves the queue when its wait runs out, when it is cancelled, or at shutdown."""
    pool = WorkerPool(1, max_waiting=2, max_wait_s=0.3)
    release = tmp_path / "release"
    holder = _hold_the_slot(pool, release)
    with pytest.raises(WorkerBusy, match=r"^waited 0.3 s in the queue for one of the 1 workers$"):
        pool.run(math.sqrt, 4.0, timeout=5)
    assert pool.waiting == 0
    pool.max_wait_s = 120
    cancel = threading.Event()
    errors = []

    def wait(**kw):
        try:
            pool.run(math.sqrt, 4.0, timeout=5, **kw)
        except (WorkerBusy, WorkerCancelled) as e:
            errors.append(e)

    th = threading.Thread(target=wait, kwargs={"cancel": cancel})
    th.start()
    while pool.waiting == 0:
        time.sleep(0.01)
    cancel.set()
    th.join()
    assert [type(e) for e in errors] == [WorkerCancelled] and pool.waiting == 0
    th = threading.Thread(target=wait)
    th.start()
    while pool.waiting == 0:
        time.sleep(0.01)
    pool.shutdown()
    th.join()
    holder.join()
    assert [str(e) for e in errors[1:]] == ["the server is shutting down"]
    assert (pool.running, pool.waiting) == (0, 0)


# --- /api/analyse and /api/presets ------------------------------------------------------

def unit_circle_moving(x):
    return {"shape": {"center": [0, 0], "semi_axes": [1, 1]}, "translation": [x, "0"]}


def alg(v):
    return {"value": str(v), "approx": float(v), "exact": str(v), "isolating": [str(v), str(v)], "polynomial": None}


def row(where, t, a, s0, s1, s10, var, relation, rule):
    return {"where": where, "t": t, "a": list(a), "s0": s0, "s1": s1, "s10": s10, "var": var, "relation": relation, "rule": rule}


def test_analyse_crossing_circles_whole_body(client):
    """Unit circles at (t, 0) and (-t, 0) on [-2, 2].

    By hand: P(T) = (T + 1)(-T^2 + (4t^2 - 2) T - 1) = -T^3 + (4t^2 - 3) T^2 + (4t^2 - 3) T - 1,
    s1 = -2 a2 (a2 + 3) = -8 t^2 (4t^2 - 3), s1,0 = 9 - a2^2. Centre distance 2|t|: tangent at
    t = -+1, overlap between (identical circles at t = 0: a root of s0, not an event).
    """
    body = {"a": unit_circle_moving("t"), "b": unit_circle_moving("-t"), "interval": ["-2", "2"], "polynomials": False}
    r = client.post("/api/analyse", json=body)
    assert r.status_code == 200, r.text
    got = r.json()
    # the sample point of each interval is the implementation's choice: check it lies inside
    samples = [Fraction(iv.pop("sample")) for iv in got["intervals"]]
    assert [-2 < samples[0] < -1, -1 < samples[1] < 1, 1 < samples[2] < 2] == [True] * 3
    interval_rows = [rw for rw in got["sign_table"] if rw["where"] == "interval"]
    assert [Fraction(rw.pop("t")) for rw in interval_rows[:2]] == samples[:2]
    # the overlap interval is split at the root t = 0 in the sign table: one sample each side
    assert -1 < Fraction(interval_rows[2]["t"]) < 1 and Fraction(interval_rows[3].pop("t")) == samples[2]
    interval_rows[2].pop("t")
    sep, tan, ovl = "separate", "tangent", "overlap"
    outer = ("-", "+", "+", "-")  # 4t^2 - 3 > 0
    inner = ("-", "-", "-", "-")
    assert got == {
        "dimension": 2,
        "interval": ["-2", "2"],
        "case": "s0",
        "sqrt_d": 1,
        "digits": 20,
        "events": [
            {**alg(-1), "relation": tan, "kind": "change", "before": sep, "after": ovl, "rule": "2d-s0=0"},
            {**alg(1), "relation": tan, "kind": "change", "before": ovl, "after": sep, "rule": "2d-s0=0"},
        ],
        "roots": [{**alg(0), "relation": ovl, "kind": "root", "before": ovl, "after": ovl, "rule": "var"}],
        "intervals": [
            {"lo": alg(-2), "hi": alg(-1), "relation": sep},
            {"lo": alg(-1), "hi": alg(1), "relation": ovl},
            {"lo": alg(1), "hi": alg(2), "relation": sep},
        ],
        "sign_table": [
            {k: v for k, v in row("interval", None, outer, "+", "-", "-", 2, sep, "2d-s0>0").items() if k != "t"},
            row("point", "-1", outer, "0", "-", "+", 2, tan, "2d-s0=0"),
            {k: v for k, v in row("interval", None, inner, "-", "+", "+", 0, ovl, "var").items() if k != "t"},
            row("point", "0", inner, "0", "0", "0", 0, ovl, "var"),
            {k: v for k, v in row("interval", None, inner, "-", "+", "+", 0, ovl, "var").items() if k != "t"},
            row("point", "1", outer, "0", "-", "+", 2, tan, "2d-s0=0"),
            {k: v for k, v in row("interval", None, outer, "+", "-", "-", 2, sep, "2d-s0>0").items() if k != "t"},
        ],
        "rules": {k: RULES[k] for k in ("2d-s0>0", "2d-s0=0", "var")},
        "a": {"shape": {"center": ["0", "0"], "semi_axes": ["1", "1"], "orientation": None}, "translation": ["t", "0"], "rotation": None, "scale": None},
        "b": {"shape": {"center": ["0", "0"], "semi_axes": ["1", "1"], "orientation": None}, "translation": ["-t", "0"], "rotation": None, "scale": None},
        "polynomials": None,
    }


def _isolates(lo, hi, sign):
    """Exactly: lo <= (12 + sign 2 sqrt 2)/17 <= hi (rational lo, hi; sign = -1 or +1).

    x <= root  iff  y(x) = sign (17x - 12)/2  is <= sqrt 2 (sign +1) or >= sqrt 2 (sign -1).
    """
    def y(x):
        return sign * (17 * x - 12) / 2

    def le_sqrt2(v):
        return v <= 0 or v * v <= 2

    def ge_sqrt2(v):
        return v >= 0 and v * v >= 2

    if sign > 0:
        return le_sqrt2(y(lo)) and ge_sqrt2(y(hi))
    return ge_sqrt2(y(lo)) and le_sqrt2(y(hi))


def test_isolates_helper_can_fail():
    assert _isolates(Fraction(53, 100), Fraction(54, 100), -1)  # 0.5395...
    assert not _isolates(Fraction(54, 100), Fraction(55, 100), -1)
    assert _isolates(Fraction(87, 100), Fraction(88, 100), 1)  # 0.8722...
    assert not _isolates(Fraction(53, 100), Fraction(54, 100), 1)


def test_analyse_example_29_events_from_the_paper(client):
    """Paper Example 29: tangent at t = (12 -+ 2 sqrt 2)/17, overlap between, separate outside, t in [0, 1]."""
    p = client.get("/api/presets/example-29").json()
    r = client.post("/api/analyse", json=p)
    assert r.status_code == 200, r.text
    got = r.json()
    assert got["case"] == "s1"  # s0 vanishes identically (paper)
    assert [(e["relation"], e["kind"], e["before"], e["after"]) for e in got["events"]] == [
        ("tangent", "change", "separate", "overlap"),
        ("tangent", "change", "overlap", "separate"),
    ]
    assert [iv["relation"] for iv in got["intervals"]] == ["separate", "overlap", "separate"]
    from decimal import Decimal, getcontext

    getcontext().prec = 60
    root2 = Decimal(2).sqrt()
    for e, sign in zip(got["events"], (-1, 1), strict=False):
        lo, hi = (Fraction(x) for x in e["isolating"])
        assert lo < hi and _isolates(lo, hi, sign)
        true = (12 + sign * 2 * root2) / 17
        assert len(e["value"].replace("0.", "", 1)) == 20  # 20 significant digits (first digit nonzero)
        assert abs(Decimal(e["value"]) - true) <= Decimal("1e-20")
        # the one JSON form of an algebraic number (as witnesses): (17 t - 12)^2 = 8, i.e. 17 t^2 - 24 t + 8 = 0
        coeffs = [int(c) for c in e["polynomial"]]
        assert coeffs[0] * 17 == coeffs[2] * 8 and coeffs[1] * 17 == coeffs[2] * -24 and len(coeffs) == 3, coeffs
        assert e["exact"] is None and abs(e["approx"] - float(true)) <= 1e-15
    assert got["polynomials"]["a"][1] == "17*t^2 - 24*t + 8"  # a3 = a1 (paper)
    assert got["polynomials"]["s0"] == "0"


def test_presets_list_and_one(client):
    r = client.get("/api/presets")
    assert r.status_code == 200
    names = [p["name"] for p in r.json()]
    assert names[:5] == ["example-29", "example-30", "example-31", "example-32", "example-33"]
    r = client.get("/api/presets/example-31")
    assert (r.status_code, r.json()) == (200, {
        "name": "example-31",
        "description": r.json()["description"],
        "a": {"shape": {"center": [0, 0, 0], "semi_axes": [2, 3, 4]}, "translation": ["0", "7", "0"]},
        "b": {"shape": {"center": [0, 0, 0], "semi_axes": [2, 4, 2]}, "translation": ["0", "0", "(t - 4)/2"]},
        "interval": [None, None],
    })
    r = client.get("/api/presets/nope")
    assert r.status_code == 404
    assert r.json()["detail"].startswith("unknown preset 'nope'; available: example-29, ")


@pytest.mark.parametrize(
    "change, status, detail",
    [
        ({"a": unit_circle_moving("3*t + x")}, 422, "a.translation[0]: unexpected 'x' at position 6: 3*t + x (allowed: numbers, t, + - * / ^, parentheses, sqrt(n))"),
        ({"b": unit_circle_moving("t^17")}, 422, None),
        ({"digits": 201}, 422, "digits = 201 is over the limit of 200"),
        ({"interval": ["1", "1"]}, 422, "empty interval: need lo < hi, got [1, 1]"),
        ({"b": {"matrix": [["1", "0", "t"], ["0", "1", "0"], ["0", "0", "-1"]]}}, 422, "b: matrix is not symmetric: entry (0,2) = t but (2,0) = 0"),
        ({"b": {"shape": {"center": [0, 0, 0], "semi_axes": [1, 1, 1]}}}, 422, None),
        ({"a": unit_circle_moving("t" * 1)}, 200, None),
    ],
)
def test_analyse_bad_input(client, change, status, detail):
    body = {"a": unit_circle_moving("t"), "b": unit_circle_moving("-t"), "interval": ["-2", "2"], "polynomials": False}
    body.update(change)
    r = client.post("/api/analyse", json=body)
    assert r.status_code == status, r.text
    if detail is not None:
        assert r.json() == {"detail": detail}
    elif status == 422:
        assert isinstance(r.json()["detail"], str) and r.json()["detail"]


def test_analyse_expression_length_limit():
    with TestClient(create_api(ApiSettings(max_expression_chars=10))) as c:
        body = {"a": unit_circle_moving("t + 0 + 0 + 0"), "b": unit_circle_moving("-t")}
        r = c.post("/api/analyse", json=body)
        assert (r.status_code, r.json()) == (422, {"detail": "a.translation[0]: expression too long (13 > 10 characters)"})


class SleepyPool(WorkerPool):
    """The real pool, but every job is a 30 s sleep: a deterministic slow analysis."""

    def run(self, fn, /, *args, timeout, **kwargs):
        return super().run(time.sleep, 30, timeout=timeout)


def sleepy_app(**settings):
    """An app with one analysis slot whose jobs all sleep 30 s, and that pool."""
    app = create_api(ApiSettings(max_concurrent_analyses=1, **settings))
    pool = SleepyPool(1)
    app.dependency_overrides[get_workers] = lambda: pool
    return app, pool


def test_slow_analysis_is_stopped_and_healthz_stays_responsive():
    """A 30 s job under a 1 s budget is killed at 1 s; /healthz answers at once meanwhile."""
    app, pool = sleepy_app(time_budget_s=1.0)
    body = {"a": unit_circle_moving("t"), "b": unit_circle_moving("-t")}
    with TestClient(app) as c:
        result = {}

        def fire():
            t0 = time.monotonic()
            result["r"] = c.post("/api/analyse", json=body)
            result["seconds"] = time.monotonic() - t0

        th = threading.Thread(target=fire)
        th.start()
        latencies, seen_running, answered_while_running, refused = [], 0, 0, None
        while th.is_alive():
            t0 = time.monotonic()
            h = c.get("/healthz")
            latencies.append(time.monotonic() - t0)
            running = h.json()["analyses_running"]
            seen_running = max(seen_running, running)
            answered_while_running += running == 1
            if seen_running and refused is None:  # a second analysis is refused while the slot is taken
                refused = c.post("/api/analyse", json=body)
            time.sleep(0.05)
        th.join()
        assert seen_running == 1
        # never blocked by the job: a /healthz that waited for it would take the whole 1 s budget and
        # be answered at most once while it runs; a loaded machine may delay one answer, not the median
        assert answered_while_running >= 3, latencies
        assert sorted(latencies)[len(latencies) // 2] < 0.25 and max(latencies) < 1.0, latencies
        assert refused is not None and refused.status_code == 503
        assert refused.headers["retry-after"] == "2"
        assert refused.json() == {"detail": "all 1 workers are busy; retry in a moment"}
        r = result["r"]
        assert (r.status_code, r.json()) == (503, {"detail": "analysis stopped: the job exceeded its time budget of 1 s and was stopped; narrow the interval or simplify the motion"})
        assert 1.0 <= result["seconds"] < 5.0
        assert c.get("/healthz").json()["analyses_running"] == 0


# --- edges: numbers a float cannot hold, non-ASCII digits, budgets, busy before parsing ----------

@pytest.mark.parametrize(
    "token, msg",
    [
        ("1e-400", 'JSON number 1e-400 underflows to 0 as a float; send it as a string ("1e-400") for its exact value'),
        ("-2.5E-999", 'JSON number -2.5E-999 underflows to 0 as a float; send it as a string ("-2.5E-999") for its exact value'),
        ("1e400", 'JSON number 1e400 overflows a float (|x| > 1.8e308); send it as a string ("1e400") for its exact value'),
        ("9" * 401, "integer too large (more than 400 digits); send it as a string fraction"),
    ],
)
def test_json_numbers_that_a_float_cannot_hold_are_refused(client, token, msg):
    text = '{"a": [[1,0,0],[0,1,0],[0,0,-1]], "b": [[1,0,0],[0,1,0],[0,0,' + token + "]]}"
    r = post_raw(client, "/api/classify", text)
    assert (r.status_code, r.json()) == (422, {"detail": [err(["body", "pair", "b", "matrix", 2, 2], f"Value error, {msg}")]})


def test_json_zero_and_tiny_subnormal_are_numbers(client):
    """0.0, -0e5 and 5e-324 (the smallest subnormal) are exactly what they say: accepted."""
    text = '{"a": [[1,0,0],[0,1,0],[0,0,-1]], "b": [[1,0,-0e5],[0,1,5e-324],[0.0,5e-324,-1]]}'
    r = post_raw(client, "/api/classify", text)
    assert r.status_code == 200 and r.json()["relation"] == "overlap"


def test_json_number_limits_in_motions_too(client):
    text = json.dumps({"a": unit_circle_moving("t"), "b": unit_circle_moving("-t")}).replace('"t"', "1e-400", 1)
    r = post_raw(client, "/api/analyse", text)
    assert r.status_code == 422
    assert "underflows to 0 as a float" in r.text


@pytest.mark.parametrize("text", ["\uff11", "\u0661/3", "1e\u0663", "\u0967.5"])
def test_only_ascii_digits_are_numbers_at_the_api(client, text):
    r = client.post("/api/classify", json={"a": UNIT, "b": [[1, 0, 0], [0, 1, 0], [0, 0, text]]})
    assert r.status_code == 422
    assert r.json()["detail"][0]["msg"] == f"Value error, not a number: {text!r} (expected e.g. '3', '-0.25', '1e-3' or '3/7')"


def test_exponent_limit_at_the_edge_states_the_real_limit(client):
    ok = client.post("/api/classify", json={"a": UNIT, "b": [[1, 0, 0], [0, 1, 0], [0, 0, "-1e1000"]]})
    assert (ok.status_code, ok.json()["relation"]) == (200, "overlap")  # a disc of radius 10^500 around the unit circle
    r = client.post("/api/classify", json={"a": UNIT, "b": [[1, 0, 0], [0, 1, 0], [0, 0, "-1e1001"]]})
    assert r.status_code == 422
    assert r.json()["detail"][0]["msg"] == "Value error, exponent out of range in '-1e1001': |e| <= 1000 after 'e'"


def _classified_one_by_one(pairs, method):
    """Reference for the batch: core.classify per pair, certified_by from method="float" first
    (JSON numbers as a stack of one, like the batch's stacked call; strings as they are)."""
    import numpy as np

    from core import Relation, classify

    out_ = []
    for p in pairs:
        a, b = p["a"], p["b"]
        kind = "ellipse" if len(a) == 3 else "ellipsoid"
        plain = all(isinstance(v, int | float) for m in (a, b) for row in m for v in row)
        if method != "exact":
            if plain:
                rel = classify(np.array(a, dtype=float)[None], np.array(b, dtype=float)[None], method="float")[0]
            else:
                rel = classify(a, b, method="float")
            if rel != Relation.UNDECIDED:
                out_.append(out(str(Relation(rel)), "float", kind, method))
                continue
        if method == "float":
            out_.append(out("undecided", None, kind, method))
        else:
            out_.append(out(str(classify(a, b, method="exact")), "exact", kind, method))
    return out_


@pytest.mark.parametrize("method", ["adaptive", "float", "exact"])
def test_batch_mixes_sizes_and_arithmetic(client, method):
    """Ellipses and ellipsoids, floats and exact strings, tangent and not, in one batch: each pair
    gets the relation and certifier it gets alone."""
    rng = __import__("random").Random(5)
    pairs = []
    for k in range(40):
        x = rng.choice([0.5, 1.0, 2.0, 3.0, 5.0])
        if k % 4 == 0:
            pairs.append({"a": circle(0), "b": circle(Fraction(x).limit_denominator())})
        elif k % 4 == 1:
            pairs.append({"a": sphere(0), "b": sphere(Fraction(x).limit_denominator())})
        elif k % 4 == 2:
            pairs.append({"a": [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, -1.0]], "b": [[1.0, 0.0, -x], [0.0, 1.0, 0.0], [-x, 0.0, x * x - 1]]})
        else:
            pairs.append({"a": [[1.0, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, -1]], "b": [[1.0, 0, 0, -x], [0, 1, 0, 0], [0, 0, 1, 0], [-x, 0, 0, x * x - 1]]})
    r = client.post("/api/classify", json={"pairs": pairs, "method": method})
    assert r.status_code == 200
    got = r.json()
    assert got == _classified_one_by_one(pairs, method)
    assert {g["certified_by"] for g in got} >= ({"exact"} if method != "float" else {None})


BUDGET_STOP = re.compile(
    r"^stopped (while reading pair \d+ of 399|before the 399 pairs of 4x4 matrices"
    r"|after \d+ of the 399 pairs needing exact arithmetic \(399 pairs in the request\))"
    r": over the time budget of 0\.01 s per request; send fewer pairs per request$"
)
"""Every place a batch can be stopped by its own budget checks (app.api.convert.classify_items)."""


@pytest.mark.parametrize("numbers", ["strings", "json"])
def test_batch_over_the_request_budget_is_503(numbers):
    """399 pairs needing exact arithmetic (~40 ms of work) under a 10 ms budget: 503 saying where.

    Where it stops depends on the machine's load, so the detail must be one of the messages of
    the places the budget is checked (or, for the worker process, the kill at the budget when
    the job could not even report in time); nothing else.
    """
    if numbers == "strings":  # exact values: classified in a worker process
        pairs = [{"a": sphere(0), "b": sphere(f"{k}/7")} for k in range(1, 400)]
        killed = "stopped: the job exceeded its time budget of 0.01 s and was stopped; send fewer pairs per request"
    else:  # JSON numbers: in a server thread; tangent pairs, so each needs exact arithmetic
        unit = [[1.0, 0, 0, 0], [0, 1.0, 0, 0], [0, 0, 1.0, 0], [0, 0, 0, -1.0]]
        pairs = [{"a": unit, "b": [[1.0, 0, 0, -2.0], [0, 1.0, 0, 0], [0, 0, 1.0, 0], [-2.0, 0, 0, 3.0]]}] * 399
        killed = None
    with TestClient(create_api(ApiSettings(request_budget_s=0.01))) as c:
        r = c.post("/api/classify", json={"pairs": pairs, "method": "exact"})
    assert r.status_code == 503 and r.headers["retry-after"] == "2"
    detail = r.json()["detail"]
    assert BUDGET_STOP.match(detail) or detail == killed, detail


def test_busy_is_answered_before_the_motion_is_read():
    """With the only slot taken, even a hostile motion gets 503 at once (nothing is parsed)."""
    app, pool = sleepy_app(time_budget_s=5.0)
    hostile = {"a": unit_circle_moving("(t+1e999)^64*(t+2e999)^64/(t+1e999)^63"), "b": unit_circle_moving("-t")}
    with TestClient(app) as c:
        th = threading.Thread(target=lambda: c.post("/api/analyse", json={"a": unit_circle_moving("t"), "b": unit_circle_moving("-t")}))
        th.start()
        try:
            while pool.running == 0:
                time.sleep(0.01)
            r = c.post("/api/analyse", json=hostile)
            assert (r.status_code, r.json()) == (503, {"detail": "all 1 workers are busy; retry in a moment"})
            assert r.headers["retry-after"] == "2"
        finally:
            pool.shutdown()
            th.join()


def test_hostile_motion_is_refused_in_the_worker_with_its_place():
    with TestClient(create_api(ApiSettings(time_budget_s=20.0))) as c:
        body = {"a": unit_circle_moving("(t+1e999)^64*(t+2e999)^64/(t+1e999)^63"), "b": unit_circle_moving("-t")}
        t0 = time.monotonic()
        r = c.post("/api/analyse", json=body)
        assert time.monotonic() - t0 < 10
        assert r.status_code == 422
        assert r.json()["detail"].startswith("a.translation[0]: constant too large: about 2^")
        assert "limit 20000 bits at position 9" in r.json()["detail"]
        body = {"a": unit_circle_moving("t"), "b": unit_circle_moving("-t"), "interval": ["1e1001", None]}
        r = c.post("/api/analyse", json=body)
        assert (r.status_code, r.json()) == (422, {"detail": "interval lo: exponent out of range in '1e1001': |e| <= 1000 after 'e'"})


def test_shutdown_pool_refuses_and_releases_waiters():
    pool = WorkerPool(1)
    result = {}

    def wait():
        try:
            pool.run(time.sleep, 30, timeout=60)
        except WorkerBusy as e:
            result["e"] = str(e)

    th = threading.Thread(target=wait)
    th.start()
    while pool.running == 0:
        time.sleep(0.01)
    t0 = time.monotonic()
    pool.shutdown()
    th.join(5)
    assert not th.is_alive() and time.monotonic() - t0 < 2
    assert result["e"] == "the server is shutting down"
    with pytest.raises(WorkerBusy, match="shutting down"):
        pool.run(math.sqrt, 4.0, timeout=10)


def test_cancelled_job_is_killed():
    from app.workers import WorkerCancelled

    pool = WorkerPool(1)
    cancel = threading.Event()
    threading.Timer(0.5, cancel.set).start()
    t0 = time.monotonic()
    with pytest.raises(WorkerCancelled):
        pool.run(time.sleep, 30, timeout=60, cancel=cancel)
    assert time.monotonic() - t0 < 5 and pool.running == 0


def test_an_app_serves_analyses_again_after_its_lifespan_restarts():
    """Shutdown refuses jobs (the server is stopping); a new lifespan of the same app takes them again."""
    app = create_api(ApiSettings())
    body = {"a": unit_circle_moving("t"), "b": unit_circle_moving("-t"), "interval": ["-2", "2"]}
    for _ in range(2):
        with TestClient(app) as c:
            r = c.post("/api/analyse", json=body)
            assert r.status_code == 200 and [e["value"] for e in r.json()["events"]] == ["-1", "1"]
    assert app.state.workers.closed


# --- where the work runs: never on the event loop; work that grows with the numbers in a worker -----

def test_no_pair_is_decided_on_the_event_loop(monkeypatch):
    """Was: a single pair of JSON numbers was classified on the event loop (p99 2.7 s under load)."""
    import asyncio

    import app.api.batching as batching
    import app.api.routes.classify as route

    where = []
    real = route.classify_items

    def spy(*args, **kwargs):
        try:
            asyncio.get_running_loop()
            where.append("event loop")
        except RuntimeError:
            where.append("thread")
        return real(*args, **kwargs)

    monkeypatch.setattr(route, "classify_items", spy)
    monkeypatch.setattr(batching, "classify_items", spy)
    with TestClient(create_api()) as c:
        r = c.post("/api/classify", json={"a": UNIT, "b": [[1, 0, -2], [0, 1, 0], [-2, 0, 3]]})
        assert (r.status_code, r.json()["relation"]) == (200, "tangent")
        r = c.post("/api/classify", json={"pairs": [{"a": UNIT, "b": [[1, 0, -2], [0, 1, 0], [-2, 0, 3]]}] * 3})
        assert [p["relation"] for p in r.json()] == ["tangent"] * 3
    assert where == ["thread", "thread"]


class RecordingPool(WorkerPool):
    """The real pool, recording the name of every job it runs."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self.jobs = []

    def run(self, fn, /, *args, **kwargs):
        self.jobs.append(fn.__name__)
        return super().run(fn, *args, **kwargs)


def test_work_that_grows_with_the_numbers_runs_in_the_worker_processes():
    app = create_api()
    pool = RecordingPool(1)
    app.dependency_overrides[get_workers] = lambda: pool
    tangent = [[1, 0, -2], [0, 1, 0], [-2, 0, 3]]
    exact = [[1, 0, "-2"], [0, 1, 0], ["-2", 0, "3"]]
    shape = {"center": ["2", "0"], "semi_axes": ["1", "1"]}
    with TestClient(app) as c:
        posts = [
            ("/api/classify", {"a": UNIT, "b": tangent}, []),
            ("/api/classify", {"a": {"center": [0.0, 0.0], "semi_axes": [1, 1]}, "b": tangent}, []),
            ("/api/classify", {"a": UNIT, "b": exact}, ["classify_job"]),
            ("/api/classify", {"pairs": [{"a": UNIT, "b": tangent}, {"a": UNIT, "b": shape}]}, ["classify_job"]),
            ("/api/explain", {"a": UNIT, "b": tangent}, ["explain_job"]),
            ("/api/contact-scale", {"a": UNIT, "b": tangent}, ["contact_scale_job"]),
            ("/api/separating-plane", {"a": UNIT, "b": [[1, 0, -3], [0, 1, 0], [-3, 0, 8]]}, ["separating_plane_job"]),
            ("/api/contact-point", {"a": UNIT, "b": tangent}, ["contact_point_job"]),
            ("/api/witness", {"a": UNIT, "b": tangent}, ["witness_job"]),
            ("/api/contacts", {"bodies": [[0, 0, 1, 1, 0], [2, 0, 1, 1, 0]]}, ["contacts_job"]),
            ("/api/analyse", {"a": unit_circle_moving("t"), "b": unit_circle_moving("-t")}, ["analyse_job"]),
        ]
        for path, body, jobs in posts:
            pool.jobs.clear()
            r = c.post(path, json=body)
            assert r.status_code == 200, (path, r.text)
            assert pool.jobs == jobs, (path, body)
        assert c.post("/api/contacts", json={"bodies": [[0, 0, 1, 1, 0], [2, 0, 1, 1, 0]]}).json()["pairs"][0]["relation"] == "tangent"


def test_pair_batcher_gives_each_request_its_own_answer():
    """Single pairs classified together; a bad pair among them gets its 422, the others their relation."""
    import asyncio

    from app.api.batching import PairBatcher
    from app.api.convert import plain_shapes
    from app.api.schemas import PairItem

    sep = [[1, 0, -3], [0, 1, 0], [-3, 0, 8]]
    bad = [[1, 0, 0], [0, -1, 0], [0, 0, -1]]  # indefinite: not an ellipse
    pairs = [PairItem(a=UNIT, b=b) for b in ([[1, 0, -2], [0, 1, 0], [-2, 0, 3]], bad, sep, UNIT)]
    batcher = PairBatcher(5.0)

    async def burst():
        return await asyncio.gather(*(batcher.classify(p, "adaptive", plain_shapes(p)) for p in pairs * 5), return_exceptions=True)

    try:
        answers = asyncio.run(burst())
    finally:
        batcher.stop()
    for k, answer in enumerate(answers):
        if k % 4 == 1:
            assert isinstance(answer, InvalidInput) and answer.matrix == "b", answer
            assert str(answer).startswith("b is not an ellipse: "), answer
        else:
            assert answer.relation == ["tangent", None, "separate", "overlap"][k % 4], answer


class InlinePool(WorkerPool):
    """The pool's interface, every job run in the calling thread (so a monkeypatch reaches it)."""

    def run(self, fn, /, *args, timeout, cancel=None, grace=0.0, wait_until=None, **kwargs):
        return fn(*args, **kwargs)


def count_binary64_tests(monkeypatch):
    """Count the calls of core's binary64 tests by calling module, wherever they were imported by name.

    Returns {"binary64": {module: calls}, "binary64_array": {module: calls}}; the scalar test's
    calls from inside binary64_array are counted as core.shapes.numbers'.
    """
    import sys as _sys

    import core.shapes.numbers as numbers

    calls = {"binary64": {}, "binary64_array": {}}
    for name in calls:
        real = getattr(numbers, name)

        def counted(*args, _name=name, _real=real, **kwargs):
            caller = _sys._getframe(1).f_globals.get("__name__", "?")
            calls[_name][caller] = calls[_name].get(caller, 0) + 1
            return _real(*args, **kwargs)

        for module in list(_sys.modules.values()):
            if getattr(module, name, None) is real and (getattr(module, "__name__", "").startswith(("core", "app"))):
                monkeypatch.setattr(module, name, counted)
    return calls


def test_binary64_is_decided_once_per_classify_request(monkeypatch):
    """Issue 53: each number of a /api/classify request is tested once (the route's plain_shapes), then passed down.

    Was: the route tested every number (is_plain_pair), classify_items tested each matrix again
    (binary64_array), and a pair with number strings was tested twice by the route.
    """
    app = create_api()
    app.dependency_overrides[get_workers] = lambda: InlinePool(1)
    floats = {"center": [0.0, 0.5], "semi_axes": [1.0, 1.5], "orientation": 0.25}  # 5 numbers, built in floats
    with TestClient(app) as c:
        for body, numbers in (
            ({"a": UNIT, "b": UNIT_AT_2}, 18),  # integers: no all-floats shortcut could hide a second test
            ({"a": [[1.0, 0, 0.0], [0, 1.0, 0], [0.0, 0, -1.0]], "b": floats}, 14),
            ({"pairs": [{"a": UNIT, "b": UNIT_AT_2}] * 3}, 54),
        ):
            calls = count_binary64_tests(monkeypatch)
            r = c.post("/api/classify", json=body)
            assert r.status_code == 200, r.text
            assert calls == {"binary64": {"app.api.convert": numbers}, "binary64_array": {}}, (body, calls)
            monkeypatch.undo()
        # number strings: the route stops testing a shape at its first string; classify_items tests nothing
        # again; core.classify reads its two object stacks (A, B) of the exact group once each, as it reads any object input
        calls = count_binary64_tests(monkeypatch)
        r = c.post("/api/classify", json={"a": UNIT, "b": circle(2)})
        assert (r.status_code, r.json()["relation"]) == (200, "tangent"), r.text
        assert calls["binary64"].get("app.api.convert", 0) == 9 + 3  # UNIT's 9, then circle(2)'s 1, 0 and its string "-2"
        assert set(calls["binary64_array"]) == {"core.fixed.classify"} and calls["binary64_array"]["core.fixed.classify"] == 2  # A, B
        assert set(calls["binary64"]) <= {"app.api.convert", "core.shapes.numbers"}


# --- HTTP conventions (issue 26, item 7): HEAD /healthz, opt-in CORS ------------------------------

def test_head_healthz_is_the_status_alone(client):
    r = client.head("/healthz")
    assert (r.status_code, r.content, r.headers["content-type"]) == (200, b"", "application/json")


def test_cors_is_off_unless_asked(client):
    preflight = {"origin": "https://example.org", "access-control-request-method": "POST", "access-control-request-headers": "content-type"}
    assert client.options("/api/classify", headers=preflight).status_code == 405
    r = client.get("/healthz", headers={"origin": "https://example.org"})
    assert not [h for h in r.headers if h.startswith("access-control-")]


def test_cors_for_the_listed_origins_only():
    preflight = {"access-control-request-method": "POST", "access-control-request-headers": "content-type"}
    with TestClient(create_api(ApiSettings(cors_origins=("https://example.org",)))) as c:
        r = c.options("/api/classify", headers={**preflight, "origin": "https://example.org"})
        assert r.status_code == 200 and r.headers["access-control-allow-origin"] == "https://example.org"
        assert set(r.headers["access-control-allow-methods"].split(", ")) == {"GET", "HEAD", "POST"}
        r = c.post("/api/classify", json={"a": UNIT, "b": UNIT_AT_2}, headers={"origin": "https://example.org"})
        assert r.status_code == 200 and r.headers["access-control-allow-origin"] == "https://example.org"
        assert r.headers["access-control-expose-headers"] == "retry-after"  # a page can honour Retry-After
        r = c.options("/api/classify", headers={**preflight, "origin": "https://evil.example"})
        assert r.status_code == 400 and "access-control-allow-origin" not in r.headers
        r = c.post("/api/classify", json={"a": UNIT, "b": UNIT_AT_2}, headers={"origin": "https://evil.example"})
        assert r.status_code == 200 and "access-control-allow-origin" not in r.headers


def test_cors_origin_option_of_serve():
    from app.cli import build_parser

    args = build_parser().parse_args(["serve", "--cors-origin", "HTTPS://Example.org:443/", "--cors-origin", "*"])
    assert args.cors_origin == ["https://example.org", "*"]
    assert build_parser().parse_args(["serve"]).cors_origin == []
    with pytest.raises(SystemExit) as e:
        build_parser().parse_args(["serve", "--cors-origin", "example.org/path"])
    assert e.value.code == 2
