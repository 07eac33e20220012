"""POST /api/contacts: many bodies in, the certified pairs out (limits, errors, periodic box)."""

from __future__ import annotations

import re

import numpy as np
import pytest
from fastapi.testclient import TestClient

from app.api import ApiSettings, create_api
from bench.bodies_data import random_bodies
from core import bodies_from_axes, contacts


@pytest.fixture(scope="module")
def client():
    with TestClient(create_api()) as c:
        yield c


def test_three_circles_exact_answer(client):
    r = client.post("/api/contacts", json={"bodies": [[0, 0, 0.5, 0.5, 0], [1, 0, 0.5, 0.5, 0], [1.5, 0, 0.5, 0.5, 0]]})
    assert r.status_code == 200
    out = r.json()
    assert out["pairs"] == [
        {"i": 0, "j": 1, "relation": "tangent", "certified_by": "exact", "image": None, "image_x": 0, "image_y": 0, "image_z": 0},
        {"i": 1, "j": 2, "relation": "overlap", "certified_by": "float", "image": None, "image_x": 0, "image_y": 0, "image_z": 0},
    ]
    assert out["bodies"] == 3 and out["invalid"] == {} and out["counts"]["candidates"] == 2
    assert out["summary"].startswith("3 bodies, 2 candidate pairs, 2 contacts (1 tangent, 1 overlap)")


def test_many_ellipsoids_equal_the_library(client):
    b = random_bodies(3000, dim=3, seed=2)
    rows = np.concatenate([b.centers, b.semi_axes, b.orientations], axis=1)
    r = client.post("/api/contacts", json={"bodies": rows.tolist(), "box": [b.side] * 3})
    assert r.status_code == 200, r.text
    want = contacts(bodies_from_axes(b.centers, b.semi_axes, b.orientations), box=(b.side,) * 3)
    got = r.json()["pairs"]
    assert [(p["i"], p["j"]) for p in got] == list(zip(want.i.tolist(), want.j.tolist(), strict=True))
    assert [p["image"] for p in got] == want.image.tolist()
    assert [[p["image_x"], p["image_y"], p["image_z"]] for p in got] == want.image.tolist()
    assert any(p["image_x"] or p["image_y"] or p["image_z"] for p in got)
    assert {p["relation"] for p in got} == {"overlap"}


def test_matrices_and_marked_invalid_bodies(client):
    unit = [[1, 0, 0], [0, 1, 0], [0, 0, -1]]
    moved = [[1, 0, -2], [0, 1, 0], [-2, 0, 3]]
    empty = [[1, 0, 0], [0, 1, 0], [0, 0, 1]]
    r = client.post("/api/contacts", json={"matrices": [unit, moved, empty]})
    assert r.status_code == 422 and r.json()["detail"].startswith("body 2 has an empty interior")
    r = client.post("/api/contacts", json={"matrices": [unit, moved, empty], "on_invalid": "mark"})
    assert r.status_code == 200
    assert r.json()["invalid"] == {"2": "body 2 has an empty interior: no real points (det > 0), not an ellipse"}
    assert [(p["i"], p["j"], p["relation"]) for p in r.json()["pairs"]] == [(0, 1, "tangent")]


@pytest.mark.parametrize(
    "body, message",
    [
        ({"bodies": [[0, 0, 0.5, -0.5, 0]]}, "bodies: row 0: semi-axes must be positive, got [0.5, -0.5]"),
        ({"bodies": [[0, 0, 0.5, 0.5, 0], [0, 0, 0, 1, 1, 1, 1, 0, 0, 0]]}, "bodies: every row must be"),
        ({}, "send either 'bodies' (rows of parameters) or 'matrices'"),
        ({"bodies": [[0, 0, 2, 2, 0], [1, 0, 0.5, 0.5, 0]], "box": [5, 5]}, "body 0 is too large for the periodic box"),
        ({"bodies": [[0, 0, 0.5, 0.5, 0]], "box": [5, 5, 5, 5]}, "box: expected 2 positive finite sides (Lx, Ly) or (Lx, Ly, xy)"),
        ({"bodies": [[0, 0, 0, 0.5, 0.5, 0.5, 1, 0, 0, 0]], "box": [5, 5, 5, 0.5, 0, 7e307]}, "box: the tilt factors"),
    ],
)
def test_bad_requests_say_what_is_wrong(client, body, message):
    r = client.post("/api/contacts", json=body)
    assert r.status_code == 422 and r.json()["detail"].startswith(message), r.text


def test_numbers_must_be_json_floats(client):
    r = client.post("/api/contacts", json={"bodies": [[0, 0, 0.5, 0.5, "0"]]})
    assert r.status_code == 422
    assert r.json()["detail"][0]["msg"].endswith("expected a JSON number (bodies are float64 numbers), got str")
    r = client.post("/api/contacts", content='{"bodies": [[0, 0, 0.5, 0.5, 1e999]]}', headers={"content-type": "application/json"})
    assert r.status_code == 422 and "overflows a float" in r.text


def test_integers_are_taken_when_they_are_float64_values(client):
    """2^55 + 2^37 is exactly a float64 (taken: the same answer as the float); 2^53 + 1 is not
    (refused, never rounded to a neighbour). Two circles of radius 2^36 whose centres, beyond
    2^53, are 2^37 apart: tangent."""
    x, r = 2**55, 2**36
    rows = [[x, 0, r, r, 0], [x + 2 * r, 0, r, r, 0]]
    as_int = client.post("/api/contacts", json={"bodies": rows})
    as_float = client.post("/api/contacts", json={"bodies": [[float(v) for v in row] for row in rows]})
    assert as_int.status_code == 200 and as_int.json() == as_float.json(), as_int.text
    assert [p["relation"] for p in as_int.json()["pairs"]] == ["tangent"], as_int.text
    r = client.post("/api/contacts", json={"bodies": [[2**53 + 1, 0, 1, 1, 0]]})
    assert r.status_code == 422
    assert r.json()["detail"][0]["msg"].endswith("an integer of 16 digits that is not exactly a float64: bodies are float64 numbers")


def test_body_count_and_size_limits():
    with TestClient(create_api(ApiSettings(max_contacts_bodies=3, max_contacts_body_bytes=2000))) as c:
        r = c.post("/api/contacts", json={"bodies": [[k, 0, 0.5, 0.5, 0] for k in range(4)]})
        assert (r.status_code, r.json()) == (422, {"detail": "4 bodies is over the limit of 3 per request"})
        r = c.post("/api/contacts", json={"bodies": [[k + 0.123456789, 0, 0.5, 0.5, 0] for k in range(200)]})
        assert (r.status_code, r.json()) == (413, {"detail": "request body too large: the limit is 2000 bytes"})
        # the other routes keep the general limit
        r = c.post("/api/classify", json={"a": [[1, 0, 0], [0, 1, 0], [0, 0, -1]], "b": [[1, 0, -2], [0, 1, 0], [-2, 0, 3]]})
        assert (r.status_code, r.json()["relation"]) == (200, "tangent")


def test_the_default_limit_takes_ten_thousand_bodies(client):
    b = random_bodies(10_000, dim=3, seed=5)
    rows = np.concatenate([b.centers, b.semi_axes, b.orientations], axis=1)
    r = client.post("/api/contacts", json={"bodies": rows.tolist()})
    assert r.status_code == 200 and r.json()["bodies"] == 10_000


def test_pairs_to_examine_and_answer_size_limits_say_how_many_and_the_limit():
    """Counted before any pair is built (candidates) / before the answer is built (pairs)."""
    at_one_point = [[0.0, 0.0, 1.0, 1.0, 0.0]] * 30  # 435 pairs, every one overlapping
    with TestClient(create_api(ApiSettings(max_contacts_candidates=434))) as c:
        r = c.post("/api/contacts", json={"bodies": at_one_point})
        assert (r.status_code, r.json()) == (422, {"detail": (
            "30 bodies give 435 pairs to examine (bodies close enough that their bounding spheres may meet), over the "
            "limit of 434 per request: send fewer or less crowded bodies, or search them with `python -m app contacts` "
            "or `core.contacts`, which have no such limit"
        )})
        assert c.post("/api/contacts", json={"bodies": at_one_point[:29]}).status_code == 200  # 406 pairs
    with TestClient(create_api(ApiSettings(max_contacts_pairs=434))) as c:
        r = c.post("/api/contacts", json={"bodies": at_one_point})
        assert (r.status_code, r.json()) == (422, {"detail": (
            "the answer would list 435 pairs of the 30 bodies that touch or overlap, over the limit of 434 pairs per "
            "answer: send fewer bodies per request, or search them with `python -m app contacts` or `core.contacts`, "
            "which have no such limit"
        )})
        r = c.post("/api/contacts", json={"bodies": at_one_point[:29]})
        assert r.status_code == 200 and len(r.json()["pairs"]) == 406


def test_contacts_over_the_time_budget_is_503_saying_where():
    """A lattice of touching spheres (every pair needs exact arithmetic) under a 20 ms budget."""
    c = np.array(np.meshgrid(*(np.arange(8.0),) * 3, indexing="ij")).reshape(3, -1).T  # 1,344 tangent pairs
    rows = [[*p, 0.5, 0.5, 0.5, 1.0, 0.0, 0.0, 0.0] for p in c.tolist()]
    with TestClient(create_api(ApiSettings(request_budget_s=0.02))) as client:
        r = client.post("/api/contacts", json={"bodies": rows})
    assert (r.status_code, r.headers["retry-after"]) == (503, "2")
    detail = r.json()["detail"]
    killed = "stopped: the job exceeded its time budget of 0.02 s and was stopped; send fewer bodies per request"
    assert re.fullmatch(
        r"stopped after [\d,]+ of [\d,]+ pairs to examine: over the time budget of 0\.02 s per request; "
        r"send fewer bodies per request", detail
    ) or detail == killed, detail


def test_a_body_too_far_from_the_origin_for_its_size_is_refused_not_mislabelled(client):
    """Unit circles 2 apart are tangent wherever they are; at x = 1e12 their float64 matrices were
    overlapping shapes (reported "overlap", certified for those matrices) and at x = 1e8 a
    "degenerate ellipse". Now: tangent up to 2^26 times the semi-axis, a clear refusal beyond."""
    for x in (1e6, 2.0**26 - 2):
        r = client.post("/api/contacts", json={"bodies": [[x, 0, 1, 1, 0], [x + 2, 0, 1, 1, 0]]})
        assert r.status_code == 200 and [p["relation"] for p in r.json()["pairs"]] == ["tangent"], (x, r.text)
    for x in (2.0**26 + 1, 1e8, 1e12):
        r = client.post("/api/contacts", json={"bodies": [[x, 0, 1, 1, 0], [x + 2, 0, 1, 1, 0]]})
        assert r.status_code == 422, (x, r.text)
        assert "is more than 2^26 times the smallest semi-axis (1.0) from the origin" in r.text, r.text


def test_ids_name_the_pairs_as_the_command_line_does(client):
    """Issue 54.3: a request's ids come back as id_i, id_j (and only then); a wrong count is a 422."""
    bodies = [[0, 0, 0.5, 0.5, 0], [1, 0, 0.5, 0.5, 0], [9, 0, 0.5, 0.5, 0]]
    r = client.post("/api/contacts", json={"bodies": bodies, "box": [10, 10], "ids": [70, 80, 90]})
    assert r.status_code == 200, r.text
    pairs = r.json()["pairs"]
    assert [(p["i"], p["j"], p["id_i"], p["id_j"], p["relation"], p["image"]) for p in pairs] == [
        (0, 1, 70, 80, "tangent", [0, 0]), (0, 2, 70, 90, "tangent", [-1, 0])]
    plain = client.post("/api/contacts", json={"bodies": bodies, "box": [10, 10]}).json()["pairs"]
    assert "id_i" not in plain[0] and [p["j"] for p in plain] == [1, 2]
    r = client.post("/api/contacts", json={"bodies": bodies, "ids": [1, 2]})
    assert r.status_code == 422 and "ids: 2 ids for 3 bodies" in r.json()["detail"]
