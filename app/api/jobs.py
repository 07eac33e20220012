"""What the API runs in worker processes: work that grows with the user's numbers.

Module-level functions for :class:`app.workers.WorkerPool` (picklable by reference; their
arguments and results are the request and response models). Each runs under the request's time
budget in its own process, so a job can be killed when its client leaves, when its budget is
spent (:data:`app.api.budget.JOB_GRACE_S` after its own check had the chance to say where) or
when the server stops; its memory is capped. Inside, a :class:`~app.api.budget.Budget` is
checked between steps, and a stop is reported as :class:`app.workers.WorkerTimeout` saying
where; bad input is a ValueError with the message the route answers 422 with.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from typing import Any

from fastapi import HTTPException

from core.shapes.limits import Limits

from ..workers import WorkerTimeout
from .budget import Budget, BudgetExceeded
from .contacts_schemas import ContactsIn
from .schemas import ClassifyOut, ExplainOut, PairItem
from .witness_schemas import (
    ContactPointOut,
    ContactScaleIn,
    ContactScaleOut,
    PlaneOut,
    WitnessIn,
    WitnessOut,
)

__all__ = [
    "analyse_job",
    "classify_job",
    "explain_job",
    "contact_scale_job",
    "separating_plane_job",
    "contact_point_job",
    "witness_job",
    "contacts_job",
]


@contextmanager
def _as_job_errors() -> Iterator[None]:
    """The route's errors as the worker carries them: 422 -> ValueError, a budget stop -> WorkerTimeout."""
    try:
        yield
    except HTTPException as e:  # raised by app.api.convert for bad input (always 422), place named
        raise ValueError(str(e.detail)) from None
    except BudgetExceeded as e:
        raise WorkerTimeout(str(e)) from None


def analyse_job(a: Any, b: Any, interval: list[Any], digits: int, polynomials: bool, limits: Limits) -> dict[str, Any]:
    """Read both motions under ``limits``, then :func:`core.moving.analysis.analyse` as a JSON-ready dict.

    The request's text is parsed here, in the worker, never in the server process.
    """
    from core.moving.analysis import analyse

    from .motion_input import check_interval, check_motion

    ma, mb = check_motion(a, "a", limits), check_motion(b, "b", limits)
    check_interval(interval, limits)
    out = analyse(ma, mb, tuple(interval), digits=digits).to_dict(polynomials=polynomials)
    out["a"] = out.pop("A")
    out["b"] = out.pop("B")
    return out


def classify_job(pairs: Sequence[PairItem], method: str, seconds: float, batch: bool) -> list[ClassifyOut]:
    """:func:`app.api.convert.classify_items` under a budget of ``seconds`` (pairs with number strings)."""
    from .convert import classify_items

    with _as_job_errors():
        return classify_items(pairs, method, Budget(seconds), batch=batch)


def explain_job(pair: PairItem, seconds: float) -> ExplainOut:
    """:func:`core.explain` of one pair: P(T), s0, s1, s1,0, their signs, Var and the rule."""
    from core import explain

    from .convert import bad_input, checked_pair

    with _as_job_errors():
        a, b = checked_pair(pair)
        Budget(seconds).check("after reading the pair")
        with bad_input():
            return ExplainOut(**explain(a, b).to_dict())


def contact_scale_job(body: ContactScaleIn) -> ContactScaleOut:
    """Certified bracket of the contact scale (with ``exact``: mu* as an algebraic number)."""
    from core.witness import contact_scale

    from .convert import bad_input, checked_pair
    from .witness_out import kind_of, scale_out

    with _as_job_errors():
        a, b = checked_pair(body)
        with bad_input():
            return scale_out(contact_scale(a, b, rtol=body.rtol), kind_of(a), body.digits if body.exact else None)


def separating_plane_job(body: WitnessIn) -> PlaneOut:
    """A separating plane, exact and verified (ValueError unless the pair is separate)."""
    from core.witness import separating_plane

    from .convert import bad_input, checked_pair
    from .witness_out import plane_out

    with _as_job_errors():
        a, b = checked_pair(body)
        with bad_input():
            return plane_out(separating_plane(a, b))


def contact_point_job(body: WitnessIn) -> ContactPointOut:
    """The contact point of a tangent pair, or a point inside both (ValueError if separate)."""
    from core.witness import contact_point

    from .convert import bad_input, checked_pair
    from .witness_out import point_out

    with _as_job_errors():
        a, b = checked_pair(body)
        with bad_input():
            return point_out(contact_point(a, b), body.digits)


def witness_job(body: WitnessIn) -> WitnessOut:
    """The relation, its sentence, the contact scale and the plane or the point."""
    from core.witness import witness

    from .convert import bad_input, checked_pair
    from .witness_out import decided, kind_of, plane_out, point_out, scale_out

    with _as_job_errors():
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
    from typing import cast

    from core import Certifier, Relation, contacts
    from core.bodies.broadphase import TooManyPairs

    from .contacts_schemas import ContactsOut, PairOut, PairRelation
    from .convert import bad_input, contacts_matrices
    from .limits import contacts_answer_message, contacts_limit_message
    from .schemas import CertifiedBy

    budget = Budget(seconds)
    with _as_job_errors():
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
                raise ValueError(contacts_limit_message(n, e.pairs, e.limit)) from None
        if len(res) > max_pairs:
            raise ValueError(contacts_answer_message(n, len(res), max_pairs))
        names = {int(r): str(r) for r in Relation}  # core lists the non-separate pairs of valid bodies
        by_name: dict[int, CertifiedBy] = {int(Certifier.FLOAT): "float", int(Certifier.EXACT): "exact"}
        images = res.image.tolist() if res.image is not None else None
        pairs = [
            PairOut(i=a, j=b, relation=cast(PairRelation, names[r]), certified_by=by_name.get(c),
                    image=None if images is None else images[k])
            for k, (a, b, r, c) in enumerate(
                zip(res.i.tolist(), res.j.tolist(), res.relation.tolist(), res.certified_by.tolist(), strict=True)
            )
        ]
        out = ContactsOut(bodies=res.n_bodies, pairs=pairs, counts=res.counts, invalid=res.invalid, summary=res.summary())
        return out.model_dump_json().encode()
