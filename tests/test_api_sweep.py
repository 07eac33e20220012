"""POST /api/sweep: moving bodies in, certified first contact times out (limits, budget, errors).

Golden values are independent of the code under test: motions solved by hand (two unit spheres
approaching head-on, |d(t)| = 4 - 6 t = 2 at t* = 1/3; a pair overlapping at t = 0; a sphere
passing another at 2 + 2^-40 (never meets) and at exactly 2 (grazes at t* = 1/2); across the face
of a periodic box), the full exact motion analysis :func:`core.analyse` of a rotating pair written
as motion text by hand, and the limits' combinatorics (n bodies at one point: n(n-1)/2 pairs).
Certified brackets are checked with exact rationals: t_lo <= t* <= t_hi, t_hi - t_lo <= 1e-9.
"""

from __future__ import annotations

import re
from fractions import Fraction
from typing import Any

import pytest
from fastapi.testclient import TestClient
from flint import fmpq, fmpq_poly

from app.api import ApiSettings, create_api
from core import Relation, analyse

UNIT = [1.0, 1.0, 1.0, 1.0, 0.0, 0.0, 0.0]
"""Semi-axes 1, 1, 1 and the identity quaternion: a unit sphere."""
NEAR = 2 + 2.0**-40
"""Two unit spheres whose centres pass this far apart never meet (2 is touching)."""


def sphere(x: float, y: float = 0.0, z: float = 0.0) -> list[float]:
    return [x, y, z, *UNIT]


@pytest.fixture(scope="module")
def client():
    with TestClient(create_api()) as c:
        yield c


def post(client: TestClient, body: dict[str, Any]) -> tuple[int, Any]:
    r = client.post("/api/sweep", json=body)
    return r.status_code, r.json()


def rational(text: str) -> Fraction:
    return Fraction(text)


def bracketed(pair: dict[str, Any], t: Fraction) -> dict[str, Any]:
    """``pair`` after checking that its floats bracket the exact t* within 1e-9 (floats are exact)."""
    lo, hi = Fraction(pair["t_lo"]), Fraction(pair["t_hi"])
    assert lo <= t <= hi and hi - lo <= Fraction(1, 10**9), (pair, t)
    return {"t_lo": pair["t_lo"], "t_hi": pair["t_hi"]}


def exact_time(t: Fraction, digits: int = 20) -> dict[str, Any]:
    """The JSON form of a rational t (``RealAlgebraic.to_dict``), written out by hand."""
    text = str(t)
    return {"value": _decimal(t, digits), "approx": float(t), "exact": text, "isolating": [text, text], "polynomial": None}


def _decimal(t: Fraction, digits: int) -> str:
    """t to ``digits`` significant digits, truncated, trailing zeros dropped (t in [0, 1))."""
    if t == 0:
        return "0"
    scaled = t * 10**digits // 1 if t >= Fraction(1, 10) else None
    assert scaled is not None  # the times of these tests are >= 0.1
    s = str(scaled).rjust(digits, "0")
    return ("0." + s).rstrip("0").rstrip(".")


def pair_out(i: int, j: int, relation: str, by: str, time: dict[str, Any] | None, **extra: Any) -> dict[str, Any]:
    return {"i": i, "j": j, "relation": relation, "certified_by": by, "time": time, "image": None,
            "image_x": 0, "image_y": 0, "image_z": 0, **extra}


# --- hand-solved motions ---------------------------------------------------------------------------

HAND_START = [sphere(0), sphere(4), sphere(20), sphere(21), sphere(40), sphere(45, NEAR), sphere(60), sphere(65, 2)]
HAND_END = [sphere(0), sphere(-2), sphere(20), sphere(23), sphere(40), sphere(35, NEAR), sphere(60), sphere(55, 2)]
"""Four pairs 20 apart (no pair across them can meet): 0-1 head-on, |d| = 4 - 6t = 2 at t = 1/3;
2-3 overlapping at t = 0 (centres 1 apart); 4-5 passing at 2 + 2^-40 (never meets); 6-7 passing at
exactly 2 (they graze at t = 1/2, the closest approach: the float filter cannot certify a touch
that does not cross, exact arithmetic does)."""


def hand_answer(out: dict[str, Any], times: bool) -> dict[str, Any]:
    pairs = out["pairs"]
    assert [(p["i"], p["j"]) for p in pairs] == [(0, 1), (2, 3), (6, 7)]
    return {
        "bodies": 8,
        "pairs": [
            pair_out(0, 1, "tangent", "float", exact_time(Fraction(1, 3)) if times else None, **bracketed(pairs[0], Fraction(1, 3))),
            pair_out(2, 3, "overlap", "float", exact_time(Fraction(0)) if times else None, t_lo=0.0, t_hi=0.0),
            pair_out(6, 7, "tangent", "exact", exact_time(Fraction(1, 2)) if times else None, t_lo=0.5, t_hi=0.5),
        ],
        # broad: the 4 pairs whose swept balls meet; every one passes the relative-motion test (the
        # near miss is within its margin); certified: 3 by the float filter, the graze exactly
        "counts": {"bodies": 8, "invalid": 0, "broad": 4, "candidates": 4, "float": 3, "exact": 1, "contacts": 3,
                   "tangent": 2, "overlap": 1, "at_start": 1},
        "invalid": {},
        "summary": "8 moving bodies, 4 candidate pairs, 3 meet (1 at t = 0); certified by the float filter 3, by exact arithmetic 1",
    }


def test_hand_solved_motions_with_exact_times(client):
    status, out = post(client, {"start": HAND_START, "end": HAND_END, "exact_times": True})
    assert status == 200, out
    assert out == hand_answer(out, times=True)
    assert out["pairs"][0]["time"]["value"] == "0.33333333333333333333"  # the hand decimal, spelled out


def test_hand_solved_motions_without_exact_times_and_fewer_digits(client):
    status, out = post(client, {"start": HAND_START, "end": HAND_END})
    assert status == 200, out
    assert out == hand_answer(out, times=False)
    status, out = post(client, {"start": HAND_START, "end": HAND_END, "exact_times": True, "digits": 5})
    assert status == 200 and out["pairs"][0]["time"] == exact_time(Fraction(1, 3), 5) == {
        "value": "0.33333", "approx": 1 / 3, "exact": "1/3", "isolating": ["1/3", "1/3"], "polynomial": None}


def test_the_exact_method_certifies_every_pair_exactly(client):
    status, out = post(client, {"start": HAND_START, "end": HAND_END, "method": "exact"})
    assert status == 200, out
    want = hand_answer(out, times=False)
    for p in want["pairs"]:
        p["certified_by"] = "exact"
    want["counts"].update(float=0, exact=4)
    want["summary"] = want["summary"].replace("float filter 3, by exact arithmetic 1", "float filter 0, by exact arithmetic 4")
    # exactly: the bracket of a rational t* is the floats around it (1/3 is not a float)
    assert out == want and out["pairs"][0]["t_hi"] == out["pairs"][0]["t_lo"] + 2.0**-54


def test_two_dimensional_bodies_with_and_without_end_angles(client):
    """Circles: 1 moves from x = 3 to x = 1 and meets 0 at t = 1/2; 2 turns in place (an ellipse)."""
    body = {"start": [[0, 0, 1, 1, 0], [3, 0, 1, 1, 0], [0, 5, 2, 1, 0]],
            "end": [[0, 0, 1, 1], [1, 0, 1, 1, 0], [0, 5, 2, 1, 1.5]], "exact_times": True}
    status, out = post(client, body)
    assert status == 200, out
    assert out == {
        "bodies": 3,
        "pairs": [pair_out(0, 1, "tangent", "float", exact_time(Fraction(1, 2)), **bracketed(out["pairs"][0], Fraction(1, 2)))],
        "counts": {"bodies": 3, "invalid": 0, "broad": 1, "candidates": 1, "float": 1, "exact": 0, "contacts": 1,
                   "tangent": 1, "overlap": 0, "at_start": 0},
        "invalid": {},
        "summary": "3 moving bodies, 1 candidate pairs, 1 meet (0 at t = 0); certified by the float filter 1, by exact arithmetic 0",
    }


def test_across_the_face_of_a_periodic_box(client):
    """Box 10: body 1 moves from x = 7 to 9.5; its image at x - 10 comes to |1 - (-3 + 2.5 t)| = 2 at t = 4/5."""
    body = {"start": [sphere(1, 5, 5), sphere(7, 5, 5)], "end": [sphere(1, 5, 5), sphere(9.5, 5, 5)], "box": [10, 10, 10]}
    status, out = post(client, body)
    assert status == 200, out
    assert out["pairs"] == [pair_out(0, 1, "tangent", "float", None, image=[-1, 0, 0], image_x=-1,
                                     **bracketed(out["pairs"][0], Fraction(4, 5)))]
    status, open_space = post(client, {**body, "box": None})
    assert status == 200 and open_space["pairs"] == []


def test_across_the_face_of_a_tilted_box(client):
    """Box (10, 10, 10, xy = 0.5): a2 = (5, 10, 0). Body 1 moves from (6, 7) to (6, 9.5); its image -a2
    comes from (1, -3) to (1, -0.5), |1 - (-3 + 2.5 t)| = 2 at t = 4/5. The same bodies in the
    orthogonal box (10, 10, 10) or in open space never meet (the tilt decides)."""
    body = {"start": [sphere(1, 1, 5), sphere(6, 7, 5)], "end": [sphere(1, 1, 5), sphere(6, 9.5, 5)], "box": [10, 10, 10, 0.5, 0, 0]}
    status, out = post(client, body)
    assert status == 200, out
    assert out["pairs"] == [pair_out(0, 1, "tangent", "float", None, image=[0, -1, 0], image_y=-1,
                                     **bracketed(out["pairs"][0], Fraction(4, 5)))]
    for other in ([10, 10, 10], None):
        status, moved = post(client, {**body, "box": other})
        assert status == 200 and moved["pairs"] == []


def same_root(out: dict[str, Any], alpha: Any) -> bool:
    """The answer's algebraic number is alpha: a common factor of both polynomials changes sign
    on an interval inside both isolating intervals (so its root there is both numbers)."""
    lo, hi = fmpq(*map(int, rational(out["isolating"][0]).as_integer_ratio())), fmpq(*map(int, rational(out["isolating"][1]).as_integer_ratio()))
    assert out["exact"] is None and lo < hi
    p = fmpq_poly([int(c) for c in out["polynomial"]])
    g = p.gcd(alpha.poly)
    alpha.refine_to((hi - lo) / 4)
    a, b = max(lo, alpha.lo), min(hi, alpha.hi)
    return bool(a < b and g.degree() >= 1 and g(a) * g(b) < 0)


def test_a_rotating_body_against_the_exact_motion_analysis(client):
    """An ellipsoid (2, 1, 1) moving from x = 4 to 1 while turning about z (q = (1 - t, 0, 0, t)) hits a
    unit sphere at rest; t* from :func:`core.analyse` of the same motion written by hand."""
    moving = {"shape": {"center": ["0", "0", "0"], "semi_axes": ["2", "1", "1"]},
              "translation": ["4 - 3*t", "0", "0"], "rotation": {"quaternion": ["1 - t", "0", "0", "t"]}}
    still = {"shape": {"center": ["0", "0", "0"], "semi_axes": ["1", "1", "1"]}}
    ref = analyse(still, moving, (0, 1))
    assert ref.relation_at(0) == Relation.SEPARATE and ref.events
    alpha = ref.events[0].time
    body = {"start": [sphere(0), [4, 0, 0, 2, 1, 1, 1, 0, 0, 0]], "end": [sphere(0), [1, 0, 0, 2, 1, 1, 0, 0, 0, 1]],
            "exact_times": True}
    status, out = post(client, body)
    assert status == 200, out
    [p] = out["pairs"]
    assert (p["i"], p["j"], p["relation"]) == (0, 1, "tangent")
    assert alpha.compare(fmpq(*Fraction(p["t_lo"]).as_integer_ratio())) >= 0
    assert alpha.compare(fmpq(*Fraction(p["t_hi"]).as_integer_ratio())) <= 0
    assert p["t_hi"] - p["t_lo"] <= 1e-9
    assert p["time"]["value"] == alpha.decimal(20) and p["time"]["approx"] == float(alpha)
    assert same_root(p["time"], alpha)


# --- bad input -------------------------------------------------------------------------------------

@pytest.mark.parametrize(
    "body, message",
    [
        ({"start": [sphere(0), sphere(3)], "end": [sphere(0)]},
         "start has 2 rows but end has 1: end holds the same bodies at t = 1, row by row"),
        ({"start": [sphere(0), [0, 0, 1, 1, 0]], "end": [sphere(0), [0, 0, 1, 1, 0]]},
         "start: every row must be [x, y, z, a, b, c, qw, qx, qy, qz] (3D) or every row [x, y, a, b, angle] (2D)"),
        ({"start": [sphere(0)], "end": [[0, 0, 1, 1, 0]]},
         "end row 0: expected [x, y, z, a, b, c, qw, qx, qy, qz] or [x, y, z, a, b, c] (the start rows are 3D), got 5 numbers"),
        ({"start": [sphere(0), sphere(3)], "end": [sphere(0), [3, 0, 0, 1, 1, 2]]},
         "end row 1: semi-axes [1.0, 1.0, 2.0] differ from start's [1.0, 1.0, 1.0]: a body keeps its shape during the step"),
        ({"start": [[0, 0, 1, 1, 0]], "end": [[0, 0, 1, 1, 0]], "box": [5, 5, 5, 5]}, "box: expected 2 positive finite sides (Lx, Ly) or (Lx, Ly, xy)"),
        ({"start": [[0, 0, 1, -1, 0]], "end": [[0, 0, 1, -1, 0]]}, "row 0: semi-axes must be positive, got [1.0, -1.0]"),
        ({"start": [[0, 0, 0, 1, 1, 1, 0, 0, 0, 0]], "end": [[0, 0, 0, 1, 1, 1]]},
         "row 0: start's orientation: the quaternion is zero"),
        ({"start": [sphere(0)], "end": [[0, 0, 0, 1, 1, 1, -2, 0, 0, 0]]},
         "row 0: the orientation passes through zero: end's = -lambda start's (lambda > 0); flip the sign of end's quaternion"),
        ({"start": [sphere(0), sphere(3)], "end": [sphere(9), sphere(3)], "box": [10, 10, 10]},
         "row 0 moves 9 in one step, more than half the smallest height of the periodic cell"),
        ({"start": [[0, 0, 0, 2, 2, 2, 1, 0, 0, 0], sphere(3)], "end": [[4, 0, 0, 2, 2, 2, 1, 0, 0, 0], sphere(3)], "box": [10, 10, 10]},
         "body 0 is too large for the periodic box"),
        ({"start": [sphere(0)], "end": [sphere(0)], "digits": 201}, "digits = 201 is over the limit of 200"),
    ],
)
def test_bad_requests_say_what_is_wrong(client, body, message):
    status, out = post(client, body)
    assert status == 422 and isinstance(out["detail"], str) and out["detail"].startswith(message), out


def test_marked_rows_are_listed_and_the_rest_swept(client):
    start = [sphere(0), sphere(4), [10, 0, 0, 1, 0, 1, 1, 0, 0, 0]]
    end = [sphere(0), sphere(-2), [10, 0, 0, 1, 0, 1]]
    status, out = post(client, {"start": start, "end": end, "on_invalid": "mark"})
    assert status == 200, out
    assert out["invalid"] == {"2": "row 2: semi-axes must be positive, got [1.0, 0.0, 1.0]"}
    assert [(p["i"], p["j"], p["relation"]) for p in out["pairs"]] == [(0, 1, "tangent")]
    assert out["counts"]["invalid"] == 1 and out["summary"].endswith("; 1 invalid bodies")


def test_numbers_must_be_json_floats(client):
    r = client.post("/api/sweep", json={"start": [[0, 0, 1, 1, "0"]], "end": [[0, 0, 1, 1]]})
    assert r.status_code == 422
    assert r.json()["detail"][0]["msg"].endswith("expected a JSON number (bodies are float64 numbers), got str")
    r = client.post("/api/sweep", content='{"start": [[0, 0, 1, 1, 1e999]], "end": [[0, 0, 1, 1]]}',
                    headers={"content-type": "application/json"})
    assert r.status_code == 422 and "overflows a float" in r.text


# --- limits ----------------------------------------------------------------------------------------

def crowd(n: int) -> list[list[float]]:
    """n unit spheres at one point (every pair overlaps at t = 0)."""
    return [sphere(0)] * n


def test_body_count_and_size_limits():
    with TestClient(create_api(ApiSettings(max_contacts_bodies=3, max_contacts_body_bytes=2000))) as c:
        r = c.post("/api/sweep", json={"start": crowd(4), "end": crowd(4)})
        assert (r.status_code, r.json()) == (422, {"detail": "4 bodies is over the limit of 3 per request"})
        rows = [[k + 0.123456789, 0, 1, 1, 0] for k in range(100)]  # ~2,900 bytes each: over 2 x 2000
        r = c.post("/api/sweep", json={"start": rows, "end": rows})
        assert (r.status_code, r.json()) == (413, {"detail": "request body too large: the limit is 4000 bytes"})
        r = c.post("/api/sweep", json={"start": crowd(3), "end": crowd(3)})  # 3 rows, under both limits
        assert r.status_code == 200 and len(r.json()["pairs"]) == 3


def test_pairs_to_examine_answer_size_and_exact_times_limits_say_how_many_and_the_limit():
    """Counted before any pair is built / before the answer is built / before any exact time."""
    with TestClient(create_api(ApiSettings(max_contacts_candidates=434))) as c:
        status, out = post(c, {"start": crowd(30), "end": crowd(30)})  # 435 pairs
        assert (status, out) == (422, {"detail": (
            "30 moving bodies give 435 pairs to examine (bodies whose swept volumes may meet during the step), over the "
            "limit of 434 per request: send fewer or less crowded bodies, or sweep them with `python -m app sweep` or "
            "`core.sweep_contacts`, which have no such limit"
        )})
        status, out = post(c, {"start": crowd(29), "end": crowd(29)})  # 406 pairs
        assert status == 200 and len(out["pairs"]) == 406
    with TestClient(create_api(ApiSettings(max_contacts_pairs=434))) as c:
        status, out = post(c, {"start": crowd(30), "end": crowd(30)})
        assert (status, out) == (422, {"detail": (
            "the answer would list 435 pairs of the 30 moving bodies that touch or overlap during the step, over the "
            "limit of 434 pairs per answer: send fewer bodies per request, or sweep them with `python -m app sweep` or "
            "`core.sweep_contacts`, which have no such limit"
        )})
    with TestClient(create_api(ApiSettings(max_sweep_exact_times=9))) as c:
        status, out = post(c, {"start": crowd(5), "end": crowd(5), "exact_times": True})  # 10 pairs
        assert (status, out) == (422, {"detail": (
            "exact_times: the answer lists 10 pairs, over the limit of 9 exact times per answer (exact arithmetic per "
            "pair): ask without exact_times (t_lo, t_hi are certified brackets), send fewer bodies, or ask /api/analyse "
            "about one pair; `core.sweep_contacts(...).time(k)` has no such limit"
        )})
        status, out = post(c, {"start": crowd(5), "end": crowd(5)})
        assert status == 200 and len(out["pairs"]) == 10 and all(p["time"] is None for p in out["pairs"])


# --- the time budget -------------------------------------------------------------------------------

BUDGET_STOP = (
    r"stopped after [\d,]+ of [\d,]+ (pairs to examine|exact times): over the time budget of {s} s per request; "
    r"send fewer bodies per request"
)


def grazing_rows(n: int) -> tuple[list[list[float]], list[list[float]]]:
    """n pairs of unit spheres, each passing the other at exactly 2 (every one needs exact arithmetic)."""
    start, end = [], []
    for k in range(n):
        x = 20.0 * k
        start += [sphere(x), sphere(x + 5, 2)]
        end += [sphere(x), sphere(x - 5, 2)]
    return start, end


def test_sweep_over_the_time_budget_is_503_saying_where():
    start, end = grazing_rows(400)  # 400 exact first contacts: seconds of work
    with TestClient(create_api(ApiSettings(request_budget_s=0.02))) as c:
        r = c.post("/api/sweep", json={"start": start, "end": end})
    assert (r.status_code, r.headers["retry-after"]) == (503, "2")
    detail = r.json()["detail"]
    killed = "stopped: the job exceeded its time budget of 0.02 s and was stopped; send fewer bodies per request"
    assert re.fullmatch(BUDGET_STOP.format(s=r"0\.02"), detail) or detail == killed, detail


def test_exact_times_over_the_time_budget_is_503_saying_where():
    """3,000 head-on pairs of a turning ellipsoid and a sphere: the float filter brackets them in
    milliseconds; their exact times are exact arithmetic on degree-23 polynomials (~3 ms each, ~9 s
    in all): a budget of 2 s takes the first request (~0.3 s) with room on a loaded machine, never
    the second."""
    start, end = [], []
    for k in range(3000):
        x = 20.0 * k
        start += [sphere(x), [x + 4, 0, 0, 2, 1, 1, 1, 0, 0, 0]]
        end += [sphere(x), [x + 1, 0, 0, 2, 1, 1, 0, 0, 0, 1]]
    with TestClient(create_api(ApiSettings(request_budget_s=2.0, max_sweep_exact_times=10_000))) as c:
        r = c.post("/api/sweep", json={"start": start, "end": end})
        assert r.status_code == 200 and len(r.json()["pairs"]) == 3000  # without exact times
        r = c.post("/api/sweep", json={"start": start, "end": end, "exact_times": True})
    assert (r.status_code, r.headers["retry-after"]) == (503, "2")
    detail = r.json()["detail"]
    killed = "stopped: the job exceeded its time budget of 2 s and was stopped; send fewer bodies per request"
    assert re.fullmatch(
        # where it stopped: in the exact times, or (a loaded machine) still examining the pairs
        r"stopped after [\d,]+ of 3,000 (exact times|pairs to examine): over the time budget of 2 s per request; send fewer bodies per request",
        detail,
    ) or detail == killed, detail


def test_the_sweep_runs_in_a_worker_process():
    """The event loop only passes the bytes on: the sweep and its JSON are made in sweep_job."""
    from app.api.deps import get_workers
    from app.workers import WorkerPool

    jobs: list[str] = []

    class Recording(WorkerPool):
        def run(self, fn, /, *args, **kwargs):
            jobs.append(fn.__name__)
            return super().run(fn, *args, **kwargs)

    app = create_api()
    pool = Recording(1)
    app.dependency_overrides[get_workers] = lambda: pool
    with TestClient(app) as c:
        status, out = post(c, {"start": HAND_START, "end": HAND_END})
    assert status == 200 and out == hand_answer(out, times=False)
    assert jobs == ["sweep_job"]


def test_ids_name_the_pairs(client):
    """Issue 54.3: ids in, id_i and id_j out, with the image and the certifier."""
    body = {"start": [sphere(1, 5, 5), sphere(7, 5, 5)], "end": [sphere(1, 5, 5), sphere(9.5, 5, 5)], "box": [10, 10, 10],
            "ids": [41, 42]}
    status, out = post(client, body)
    assert status == 200, out
    (pair,) = out["pairs"]
    assert (pair["id_i"], pair["id_j"], pair["image"], pair["certified_by"]) == (41, 42, [-1, 0, 0], "float")
    assert Fraction(pair["t_lo"]) <= Fraction(4, 5) <= Fraction(pair["t_hi"])
