"""Pickling of the python-flint types the results hold (``fmpq_poly``, ``fmpz_poly``).

python-flint 0.9 pickles ``fmpz`` and ``fmpq`` but not its polynomials; a motion analysis
(:class:`core.moving.result.MotionAnalysis`) holds them, and it travels from a worker process to
the scene unchanged. Registering reducers with :mod:`copyreg` (coefficients in, the same
polynomial out, exactly) is enough; importing :mod:`core` does it.
"""

from __future__ import annotations

import copyreg
from typing import Any

from flint import fmpq_poly, fmpz_poly

__all__: list[str] = []


def _reduce_fmpq_poly(p: fmpq_poly) -> tuple[Any, tuple[Any, ...]]:
    return fmpq_poly, ([c for c in p.coeffs()],)


def _reduce_fmpz_poly(p: fmpz_poly) -> tuple[Any, tuple[Any, ...]]:
    return fmpz_poly, ([c for c in p.coeffs()],)


copyreg.pickle(fmpq_poly, _reduce_fmpq_poly)
copyreg.pickle(fmpz_poly, _reduce_fmpz_poly)
