"""Settings of the HTTP API: limits, time budget and where the landing page lives.

One frozen dataclass, built by the command line (``python -m app serve``) and injected into routes
with ``Depends(get_settings)`` (:mod:`app.api.deps`), so tests can swap it through
``app.dependency_overrides``.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path

from core.shapes.limits import SERVER, Limits

__all__ = ["ApiSettings", "default_static_dir", "default_bench_dir"]


def default_static_dir() -> Path | None:
    """The landing page's folder, or None.

    Looked for in ``app/static`` (an installed wheel), ``static/`` of the checkout (an editable
    install), then ``./static`` (a working directory that holds one).

    Examples:
        >>> default_static_dir() is None or (default_static_dir() / "index.html").is_file()
        True
    """
    here = Path(__file__).resolve()
    for candidate in (here.parents[1] / "static", here.parents[2] / "static", Path.cwd() / "static"):
        if (candidate / "index.html").is_file():
            return candidate
    return None


def default_bench_dir() -> Path | None:
    """``bench/figures`` of the repository (written by ``python -m bench.report``), if bench/ exists."""
    bench = Path(__file__).resolve().parents[2] / "bench"
    return bench / "figures" if bench.is_dir() else None


@dataclass(frozen=True)
class ApiSettings:
    """Limits and links of one API instance (all limits are per request)."""

    scene_url: str | None = None
    """Link to the 3D scene shown on the landing page; None when serving ``--api-only``."""
    cors_origins: tuple[str, ...] = ()
    """Web origins (``https://example.org``) whose pages may call the API from a browser (CORS,
    ``--cors-origin``); empty: none (the default: no CORS headers at all)."""
    max_body_bytes: int = 1_000_000
    """Largest accepted request body (413 above)."""
    max_batch: int = 1000
    """Most pairs in one ``{"pairs": [...]}`` classify request."""
    max_contacts_bodies: int = 10_000
    """Most bodies in one ``/api/contacts`` request (a search over 10,000 bodies takes ~20 ms;
    larger sets: ``python -m app contacts`` or the library)."""
    max_contacts_body_bytes: int = 4_000_000
    """Largest ``/api/contacts`` body (10,000 rows of 10 JSON numbers are about 2 MB)."""
    max_contacts_candidates: int = 2_000_000
    """Most pairs the broad phase of one ``/api/contacts`` request may examine (counted before
    any is built; 10,000 bodies at random in a box give ~50,000, 10,000 at one point 49,995,000)."""
    max_contacts_pairs: int = 100_000
    """Most pairs listed in one ``/api/contacts`` answer (checked before the answer is built).
    ``/api/sweep`` has the same three limits (bodies, pairs to examine, pairs listed) and twice
    the body size (its start and end rows)."""
    max_sweep_exact_times: int = 100
    """Most exact first contact times (``exact_times``) in one ``/api/sweep`` answer (each is
    exact arithmetic on the pair's motion: ~1-40 ms)."""
    max_expression_chars: int = SERVER.expression_chars or 2000
    """Longest expression string in a motion (all other size limits of user text:
    :data:`core.shapes.limits.SERVER`, e.g. number strings up to 400 characters)."""
    max_degree: int = SERVER.degree
    """Highest degree in t of a numerator or denominator of one motion entry after
    simplification."""
    time_budget_s: float = 20.0
    """Wall-clock budget of one motion analysis; the worker process is killed when exceeded."""
    request_budget_s: float = 5.0
    """Wall-clock budget of one classify/explain/witness/contacts request: the work is stopped
    (between pairs, or its worker process killed) and answered with 503."""
    max_digits: int = 200
    """Largest ``digits`` accepted by /api/analyse."""
    max_concurrent_analyses: int = 2
    """Worker processes running at once (analyses, explanations, witnesses, contacts, exact
    classifications: each job in its own process); more wait in the queue."""
    max_queued_analyses: int = 16
    """Requests that may wait for a worker (first come, first served); beyond them, 503 with
    Retry-After at once."""
    queue_wait_s: float = 10.0
    """Longest wait of a request, from when its body has arrived to when its work starts (for the
    reader of large bodies, then in the queue for a worker); then 503 with Retry-After."""
    max_large_bodies: int = 16
    """Requests with a body over 64 kB the server holds at once (from their first byte over 64 kB
    to their answer: received, read, waiting for a worker, running); one more is answered 503
    with Retry-After at once, its body unread. Their memory is bounded by this times the body
    limit (:mod:`app.api.line`)."""
    body_stall_s: float = 10.0
    """Longest pause while a request body arrives; then 408 and the connection closed."""
    body_read_s: float = 60.0
    """Longest time for a whole request body to arrive; then 408 and the connection closed."""
    memory_limit_mb: int | None = 2048
    """Address-space cap of an analysis worker process (None: no cap)."""
    static_dir: Path | None = field(default_factory=default_static_dir)
    """Folder with ``index.html``, ``style.css`` and ``img/`` served at ``/`` and ``/static``."""
    bench_dir: Path | None = field(default_factory=default_bench_dir)
    """Benchmark figures (PNG) shown on the landing page and served at ``/bench/figures``."""

    def __post_init__(self) -> None:
        """Reject limits that make no sense (a ValueError naming the field)."""
        for name in ("max_body_bytes", "max_batch", "max_expression_chars", "max_degree",
                     "max_digits", "max_concurrent_analyses", "max_contacts_bodies", "max_contacts_body_bytes",
                     "max_contacts_candidates", "max_contacts_pairs", "max_sweep_exact_times", "max_large_bodies"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise ValueError(f"ApiSettings.{name} must be a positive integer, got {value!r}")
        q = self.max_queued_analyses
        if isinstance(q, bool) or not isinstance(q, int) or q < 0:
            raise ValueError(f"ApiSettings.max_queued_analyses must be a non-negative integer, got {q!r}")
        for name in ("time_budget_s", "request_budget_s", "queue_wait_s", "body_stall_s", "body_read_s"):
            if not (getattr(self, name) > 0):
                raise ValueError(f"ApiSettings.{name} must be > 0, got {getattr(self, name)!r}")

    def text_limits(self) -> Limits:
        """Size limits of user text in this API.

        :data:`core.shapes.limits.SERVER` with this instance's expression length and degree.
        """
        return replace(SERVER, expression_chars=self.max_expression_chars, degree=self.max_degree)
