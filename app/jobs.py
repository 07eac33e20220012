"""What the worker processes run: the one module of jobs for the scene and the HTTP API.

Module-level functions for :class:`app.workers.WorkerPool` (picklable by reference). Each runs
in its own process under a time budget and a memory cap, so a job can be killed when its client
leaves, when its budget is spent or when the server stops. Every text a user typed is read here,
in the worker, by core's readers (:func:`core.moving.motions.read_motion`,
:func:`core.moving.motions.read_interval`: one grammar, each expression parsed once), never in
the process serving the tabs and the requests.

* :func:`analyse_job`: read two motions and I under the server's limits, analyse; the
  :class:`core.moving.result.MotionAnalysis` pickles back as it is (the scene keeps it, the API
  writes its JSON). :func:`read_motion_job`: the scene's typed motion, read and built.
* The API's request jobs (``classify_job`` with number strings, ``explain_job``, the witness
  jobs, ``contacts_job``, ``sweep_job``): their arguments and results are the request and response models;
  inside, a budget (:class:`app.api.budget.Budget`) is checked between steps and a stop is
  reported as :class:`app.workers.WorkerTimeout` saying where; bad input is a ValueError with
  the message the route answers 422 with. They import the API's modules when called, so the
  scene's workers never load FastAPI.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from typing import TYPE_CHECKING, Any

from core.moving.analysis import analyse
from core.moving.motions import read_interval, read_motion
from core.moving.result import MotionAnalysis
from core.shapes.limits import SERVER, Limits

from .workers import WorkerTimeout

if TYPE_CHECKING:
    from .api.budget import Budget
    from .api.contacts_schemas import ContactsIn
    from .api.schemas import ClassifyOut, ExplainOut, PairItem
    from .api.sweep_schemas import SweepIn
    from .api.witness_schemas import (
        ContactPointOut,
        ContactScaleIn,
        ContactScaleOut,
        PlaneOut,
        WitnessIn,
        WitnessOut,
    )
    from .scene.motion import MotionModel

__all__ = [
    "analyse_job",
    "read_motion_job",
    "classify_job",
    "explain_job",
    "contact_scale_job",
    "separating_plane_job",
    "contact_point_job",
    "witness_job",
    "contacts_job",
    "sweep_job",
]


def analyse_job(
    a: Any,
    b: Any,
    interval: Any,
    digits: int = 20,
    limits: Limits = SERVER,
    names: tuple[str, str] = ("a", "b"),
) -> MotionAnalysis:
    """Read both motions and I under ``limits``, then :func:`core.moving.analysis.analyse` them.

    The same contract for the scene and the HTTP API.

    Args:
        a: the first motion: a motion dict, an n x n nested list of expressions, or a
            :class:`core.moving.motions.Motion` already read (the scene's).
        b: the second, likewise.
        interval: I as a pair (lo, hi) or the text "lo, hi" (:func:`core.moving.motions.read_interval`).
        digits: significant digits of the event values.
        limits: size limits of the text (:data:`core.shapes.limits.SERVER`, or the API's
            :meth:`app.api.settings.ApiSettings.text_limits`).
        names: the motions' names in error messages ("a.translation[0]: ...").

    Raises:
        ValueError: unreadable text (its place named), or a motion that cannot be analysed on I
            (core's message).
    """
    ma, mb = read_motion(a, limits=limits, name=names[0]), read_motion(b, limits=limits, name=names[1])
    return analyse(ma, mb, read_interval(interval, limits), digits=digits)


def read_motion_job(motion: dict[str, Any]) -> MotionModel | tuple[str, str]:
    """Read a scene's typed motion under :data:`core.shapes.limits.SERVER` and build its exact matrices.

    Returns:
        The loaded model (it pickles with its exact matrices), or (message, field) for a
        :class:`app.scene.motion.MotionError` (an exception would lose its field on the way back).
    """
    from .scene.motion import MotionError, load_motion

    try:
        return load_motion(preset=None, motion=motion, limits=SERVER)
    except MotionError as e:
        return str(e), e.field


def _budget(seconds: float) -> Budget:
    from .api.budget import Budget

    return Budget(seconds)


@contextmanager
def _as_job_errors() -> Iterator[None]:
    """The route's errors as the worker carries them: 422 -> ValueError, a budget stop -> WorkerTimeout."""
    from fastapi import HTTPException

    from .api.budget import BudgetExceeded

    try:
        yield
    except HTTPException as e:  # raised by app.api.convert for bad input (always 422), place named
        raise ValueError(str(e.detail)) from None
    except BudgetExceeded as e:
        raise WorkerTimeout(str(e)) from None


def classify_job(pairs: Sequence[PairItem], method: str, seconds: float, batch: bool) -> list[ClassifyOut]:
    """:func:`app.api.convert.classify_items` under a budget of ``seconds`` (pairs with number strings)."""
    from .api.convert import classify_items

    with _as_job_errors():
        return classify_items(pairs, method, _budget(seconds), batch=batch)


def explain_job(pair: PairItem, seconds: float) -> ExplainOut:
    """:func:`core.explain` of one pair: P(T), s0, s1, s1,0, their signs, Var and the rule."""
    from core import explain

    from .api.convert import bad_input, checked_pair

    with _as_job_errors():
        a, b = checked_pair(pair)
        _budget(seconds).check("after reading the pair")
        with bad_input():
            from .api.schemas import ExplainOut

            return ExplainOut(**explain(a, b).to_dict())


def contact_scale_job(body: ContactScaleIn) -> ContactScaleOut:
    """Certified bracket of the contact scale (with ``exact``: mu* as an algebraic number)."""
    from core.witness import contact_scale

    from .api.convert import bad_input, checked_pair
    from .api.witness_out import kind_of, scale_out

    with _as_job_errors():
        a, b = checked_pair(body)
        with bad_input():
            return scale_out(contact_scale(a, b, rtol=body.rtol), kind_of(a), body.digits if body.exact else None)


def separating_plane_job(body: WitnessIn) -> PlaneOut:
    """A separating plane, exact and verified (ValueError unless the pair is separate)."""
    from core.witness import separating_plane

    from .api.convert import bad_input, checked_pair
    from .api.witness_out import plane_out

    with _as_job_errors():
        a, b = checked_pair(body)
        with bad_input():
            return plane_out(separating_plane(a, b))


def contact_point_job(body: WitnessIn) -> ContactPointOut:
    """The contact point of a tangent pair, or a point inside both (ValueError if separate)."""
    from core.witness import contact_point

    from .api.convert import bad_input, checked_pair
    from .api.witness_out import point_out

    with _as_job_errors():
        a, b = checked_pair(body)
        with bad_input():
            return point_out(contact_point(a, b), body.digits)


def witness_job(body: WitnessIn) -> WitnessOut:
    """The relation, its sentence, the contact scale and the plane or the point."""
    from core.witness import witness

    from .api.convert import bad_input, checked_pair
    from .api.witness_out import decided, kind_of, plane_out, point_out, scale_out

    with _as_job_errors():
        a, b = checked_pair(body)
        with bad_input():
            w = witness(a, b)
            from .api.witness_schemas import WitnessOut

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
    from core import contacts
    from core.bodies.broadphase import TooManyPairs

    from .api.contacts_schemas import ContactsOut, PairOut
    from .api.convert import bad_input, contacts_matrices
    from .api.limits import contacts_answer_message, contacts_limit_message

    budget = _budget(seconds)
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
        res.ids = _ids(body.ids, n)
        pairs = [PairOut(**_json_row(row)) for row in res.rows()]  # the columns of core.PairTable, as the CSV
        out = ContactsOut(bodies=res.n_bodies, pairs=pairs, counts=res.counts, invalid=res.invalid, summary=res.summary())
        return out.model_dump_json(exclude=None if res.ids is not None else _NO_IDS).encode()


_NO_IDS: Any = {"pairs": {"__all__": {"id_i", "id_j"}}}
"""Left out of an answer whose request gave no ids (its pairs are named by their rows alone)."""


def _ids(ids: list[int] | None, n: int) -> Any:
    """The request's ``ids`` as an array, checked against the number of bodies (None: no ids)."""
    import numpy as np

    if ids is None:
        return None
    if len(ids) != n:
        raise ValueError(f"ids: {len(ids)} ids for {n} bodies: give one id per body, in the order of the rows")
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
    from core import sweep_contacts
    from core.bodies.broadphase import TooManyPairs

    from .api.limits import sweep_answer_message, sweep_limit_message, sweep_times_message
    from .api.schemas import AlgebraicOut
    from .api.sweep_schemas import (
        SweepOut,
        SweepPairOut,
        in_api_words,
        sweep_arguments,
    )

    budget = _budget(seconds)
    with _as_job_errors():
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
            raise ValueError(sweep_limit_message(n, e.pairs, e.limit)) from None
        except ValueError as e:
            raise ValueError(in_api_words(e)) from None
        m = len(res)
        if m > max_pairs:
            raise ValueError(sweep_answer_message(n, m, max_pairs))
        times: list[AlgebraicOut | None] = [None] * m
        if body.exact_times:
            if m > max_times:
                raise ValueError(sweep_times_message(m, max_times))
            for k in range(m):
                budget.check(f"after {k:,} of {m:,} exact times")
                times[k] = AlgebraicOut(**res.time(k).to_dict(body.digits))
        res.ids = _ids(body.ids, n)
        pairs = [SweepPairOut(**_json_row(row), time=times[k]) for k, row in enumerate(res.rows())]
        invalid = {k: in_api_words(why) for k, why in res.invalid.items()}
        out = SweepOut(bodies=res.n_bodies, pairs=pairs, counts=res.counts, invalid=invalid, summary=res.summary())
        return out.model_dump_json(exclude=None if res.ids is not None else _NO_IDS).encode()
