"""Float filter placeholder (replaced by the certified float64 filter in the next commit)."""
from __future__ import annotations

import numpy as np

from .relation import Relation

_last = 0


def classify_float(a: np.ndarray, b: np.ndarray, *, scalar: bool = False) -> np.ndarray:
    """Abstain on every pair (exact path decides)."""
    global _last
    _last = a.shape[0]
    return np.full(a.shape[0], Relation.UNDECIDED, dtype=np.int8)


def last_escalations() -> int:
    """Pairs left undecided by the last call."""
    return _last


def explain_float(A, B):  # noqa: ANN001, ANN201
    """No float explanation yet."""
    return None
