"""The HTTP API's jobs: what its worker processes run for a request (module-level, picklable by reference).

Their arguments and results are the request and response models (:mod:`app.api.schemas` and its
siblings); inside, a :class:`app.jobs.Budget` is checked between steps and a stop is reported as
:class:`app.workers.WorkerTimeout` saying where (:func:`app.jobs.budgeted`). Bad input is
:class:`core.InvalidInput` (a ValueError, with the pair and the matrix where known): it crosses
the process boundary as it is and the app's one exception handler answers it 422. No FastAPI here:
the worker processes never load it.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from core import InvalidInput, contacts, explain, sweep_contacts
from core.bodies.broadphase import TooManyPairs
from core.witness import contact_point, contact_scale, separating_plane, witness

from ..jobs import Budget, budgeted
from .contacts_schemas import ContactsIn, ContactsOut, PairOut
from .convert import Plain, bad_input, checked_pair, classify_items, contacts_matrices
from .limits import (
    contacts_answer_message,
    contacts_limit_message,
    sweep_answer_message,
    sweep_limit_message,
    sweep_times_message,
)
from .schemas import AlgebraicOut, ClassifyOut, ExplainOut, PairItem
from .sweep_schemas import SweepIn, SweepOut, SweepPairOut, in_api_words, sweep_arguments
from .witness_out import decided, kind_of, plane_out, point_out, scale_out
from .witness_schemas import (
    ContactPointOut,
    ContactScaleIn,
    ContactScaleOut,
    PlaneOut,
    WitnessIn,
    WitnessOut,
)

__all__ = [
    "classify_job",
    "explain_job",
    "contact_scale_job",
    "separating_plane_job",
    "contact_point_job",
    "witness_job",
    "contacts_job",
    "sweep_job",
]


def classify_job(
    pairs: Sequence[PairItem], method: str, seconds: float, batch: bool, plain: Sequence[Plain] | None = None
) -> list[ClassifyOut]:
    """:func:`app.api.convert.classify_items` under a budget of ``seconds`` (pairs with number strings).

    ``plain``: the route's :func:`app.api.convert.plain_shapes` of each pair (not decided again here).
    """
    with budgeted():
        return classify_items(pairs, method, Budget(seconds), batch=batch, plain=plain)


def explain_job(pair: PairItem, seconds: float) -> ExplainOut:
    """:func:`core.explain` of one pair: P(T), s0, s1, s1,0, their signs, Var and the rule."""
    with budgeted():
        a, b = checked_pair(pair)
        Budget(seconds).check("after reading the pair")
        with bad_input():
            return ExplainOut(**explain(a, b).to_dict())


def contact_scale_job(body: ContactScaleIn) -> ContactScaleOut:
    """Certified bracket of the contact scale (with ``exact``: mu* as an algebraic number)."""
    with budgeted():
        a, b = checked_pair(body)
        with bad_input():
            return scale_out(contact_scale(a, b, rtol=body.rtol), kind_of(a), body.digits if body.exact else None)


def separating_plane_job(body: WitnessIn) -> PlaneOut:
    """A separating plane, exact and verified (ValueError unless the pair is separate)."""
    with budgeted():
        a, b = checked_pair(body)
        with bad_input():
            return plane_out(separating_plane(a, b))


def contact_point_job(body: WitnessIn) -> ContactPointOut:
    """The contact point of a tangent pair, or a point inside both (ValueError if separate)."""
    with budgeted():
        a, b = checked_pair(body)
        with bad_input():
            return point_out(contact_point(a, b), body.digits)


def witness_job(body: WitnessIn) -> WitnessOut:
    """The relation, its sentence, the contact scale and the plane or the point."""
    with budgeted():
        a, b = checked_pair(body)
        with bad_input():
            w = witness(a, b)
            return WitnessOut(
                relation=decided(w.relation),
                sentence=w.sentence,
                margin_text=w.margin,
                contact_scale=scale_out(w.scale, kind_of(a), None),
                plane=None if w.plane is None else plane_out(w.plane),
                point=None if w.point is None else point_out(w.point, body.digits),
            )


def contacts_job(body: ContactsIn, seconds: float, max_candidates: int, max_pairs: int) -> bytes:
    """:func:`core.contacts` of the bodies under the request's limits; the answer as JSON bytes.

    The broad phase counts the pairs it would examine before building any (over
    ``max_candidates``: 422), the budget is checked between its chunks and the narrow phase's
    batches, and the number of pairs found is checked against ``max_pairs`` before the answer
    is built. The JSON is written here, so the server process only passes the bytes on.
    """
    budget = Budget(seconds)
    with budgeted():
        Q = contacts_matrices(body)
        n = int(Q.shape[0])

        def progress(done: int, total: int) -> None:
            budget.check(f"after {done:,} of {total:,} pairs to examine")

        with bad_input():
            try:
                res = contacts(
                    Q, box=body.box, method=body.method, on_invalid=body.on_invalid, progress=progress,
                    max_pairs=max_candidates,
                )
            except TooManyPairs as e:
                raise InvalidInput(contacts_limit_message(n, e.pairs, e.limit)) from None
        if len(res) > max_pairs:
            raise InvalidInput(contacts_answer_message(n, len(res), max_pairs))
        res.ids = _ids(body.ids, n)
        pairs = [PairOut(**_json_row(row)) for row in res.rows()]  # the columns of core.PairTable, as the CSV
        out = ContactsOut(bodies=res.n_bodies, pairs=pairs, counts=res.counts, invalid=res.invalid, summary=res.summary())
        return out.model_dump_json(exclude=None if res.ids is not None else _NO_IDS).encode()


_NO_IDS: Any = {"pairs": {"__all__": {"id_i", "id_j"}}}
"""Left out of an answer whose request gave no ids (its pairs are named by their rows alone)."""


def _ids(ids: list[int] | None, n: int) -> Any:
    """The request's ``ids`` as an array, checked against the number of bodies (None: no ids)."""
    if ids is None:
        return None
    if len(ids) != n:
        raise InvalidInput(f"ids: {len(ids)} ids for {n} bodies: give one id per body, in the order of the rows")
    return np.asarray(ids, dtype=np.int64)


def _json_row(row: dict[str, Any]) -> dict[str, Any]:
    """A row of :meth:`core.PairTable.rows` as the API's pair: "none" (not certified) is null."""
    if row.get("certified_by") == "none":
        row["certified_by"] = None
    return row


def sweep_job(body: SweepIn, seconds: float, max_candidates: int, max_pairs: int, max_times: int) -> bytes:
    """:func:`core.sweep_contacts` of the moving bodies under the request's limits; the answer as JSON bytes.

    As :func:`contacts_job`: the swept broad phase counts the pairs it would examine before
    building any (over ``max_candidates``: 422), the budget is checked between its chunks and
    the narrow phase's batches, the pairs found are checked against ``max_pairs`` before the
    answer is built; with ``exact_times``, their number against ``max_times`` before any is
    computed, and the budget between them.
    """
    budget = Budget(seconds)
    with budgeted():
        c0, c1, r, o0, o1, box = sweep_arguments(body)
        n = int(c0.shape[0])

        def progress(done: int, total: int) -> None:
            budget.check(f"after {done:,} of {total:,} pairs to examine")

        try:
            res = sweep_contacts(
                c0, c1, r, o0, o1, box=box, on_invalid=body.on_invalid, method=body.method, progress=progress,
                max_pairs=max_candidates,
            )
        except TooManyPairs as e:
            raise InvalidInput(sweep_limit_message(n, e.pairs, e.limit)) from None
        except ValueError as e:
            raise InvalidInput(in_api_words(e)) from None
        m = len(res)
        if m > max_pairs:
            raise InvalidInput(sweep_answer_message(n, m, max_pairs))
        times: list[AlgebraicOut | None] = [None] * m
        if body.exact_times:
            if m > max_times:
                raise InvalidInput(sweep_times_message(m, max_times))
            for k in range(m):
                budget.check(f"after {k:,} of {m:,} exact times")
                times[k] = AlgebraicOut(**res.time(k).to_dict(body.digits))
        res.ids = _ids(body.ids, n)
        pairs = [SweepPairOut(**_json_row(row), time=times[k]) for k, row in enumerate(res.rows())]
        invalid = {k: in_api_words(why) for k, why in res.invalid.items()}
        out = SweepOut(bodies=res.n_bodies, pairs=pairs, counts=res.counts, invalid=invalid, summary=res.summary())
        return out.model_dump_json(exclude=None if res.ids is not None else _NO_IDS).encode()
