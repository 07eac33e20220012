"""Request-level guards: the messages of the contact search's per-request limits.

Body sizes are limited where bodies arrive (:mod:`app.api.line`).

The library has no limits (``core.contacts`` answers any input it can hold); the server's
limits are applied here, at the edge, with messages that say what was asked, the limit and what
to do instead: :func:`contacts_limit_message` (the pairs the broad phase would examine, counted
before any is built: :class:`core.bodies.broadphase.TooManyPairs`) and
:func:`contacts_answer_message` (the pairs an answer would list, checked before it is built);
the same for ``/api/sweep`` (:func:`sweep_limit_message`, :func:`sweep_answer_message`) and its
exact times (:func:`sweep_times_message`).

No FastAPI here: the jobs that raise these run in the worker processes. The answers to errors are
:mod:`app.api.errors`.
"""

from __future__ import annotations

__all__ = [
    "contacts_limit_message",
    "contacts_answer_message",
    "sweep_limit_message",
    "sweep_answer_message",
    "sweep_times_message",
]

_ELSEWHERE = "or search them with `python -m app contacts` or `core.contacts`, which have no such limit"
_SWEEP_ELSEWHERE = "or sweep them with `python -m app sweep` or `core.sweep_contacts`, which have no such limit"


def contacts_limit_message(bodies: int, pairs: int, limit: int) -> str:
    """422 detail: the broad phase would examine ``pairs`` pairs, over ``limit``.

    Examples:
        >>> contacts_limit_message(10_000, 49_995_000, 2_000_000)[:95]
        '10,000 bodies give 49,995,000 pairs to examine (bodies close enough that their bounding spheres'
    """
    return (
        f"{bodies:,} bodies give {pairs:,} pairs to examine (bodies close enough that their bounding spheres "
        f"may meet), over the limit of {limit:,} per request: send fewer or less crowded bodies, {_ELSEWHERE}"
    )


def contacts_answer_message(bodies: int, pairs: int, limit: int) -> str:
    """422 detail: the answer would list ``pairs`` pairs, over ``limit``."""
    return (
        f"the answer would list {pairs:,} pairs of the {bodies:,} bodies that touch or overlap, over the limit "
        f"of {limit:,} pairs per answer: send fewer bodies per request, {_ELSEWHERE}"
    )


def sweep_limit_message(bodies: int, pairs: int, limit: int) -> str:
    """422 detail of ``/api/sweep``: the swept broad phase would examine ``pairs`` pairs, over ``limit``.

    Examples:
        >>> sweep_limit_message(10_000, 49_995_000, 2_000_000)[:98]
        '10,000 moving bodies give 49,995,000 pairs to examine (bodies whose swept volumes may meet during '
    """
    return (
        f"{bodies:,} moving bodies give {pairs:,} pairs to examine (bodies whose swept volumes may meet during the "
        f"step), over the limit of {limit:,} per request: send fewer or less crowded bodies, {_SWEEP_ELSEWHERE}"
    )


def sweep_answer_message(bodies: int, pairs: int, limit: int) -> str:
    """422 detail of ``/api/sweep``: the answer would list ``pairs`` pairs, over ``limit``."""
    return (
        f"the answer would list {pairs:,} pairs of the {bodies:,} moving bodies that touch or overlap during the step, "
        f"over the limit of {limit:,} pairs per answer: send fewer bodies per request, {_SWEEP_ELSEWHERE}"
    )


def sweep_times_message(pairs: int, limit: int) -> str:
    """422 detail of ``/api/sweep``: ``exact_times`` for ``pairs`` pairs, over ``limit``."""
    return (
        f"exact_times: the answer lists {pairs:,} pairs, over the limit of {limit:,} exact times per answer (exact "
        "arithmetic per pair): ask without exact_times (t_lo, t_hi are certified brackets), send fewer bodies, or ask "
        "/api/analyse about one pair; `core.sweep_contacts(...).time(k)` has no such limit"
    )
