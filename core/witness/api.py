"""The public witnesses of one pair or of stacks.

Each dispatches to the exact one-pair form or to the vectorised float form (:mod:`.batch`), so
that neither of those imports the other.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from flint import fmpq  # noqa: F401  (used in the doctests)

from .batch import contact_scale_batch, separating_plane_batch
from .plane import separating_plane_pair
from .scale import contact_scale_pair

__all__ = ["contact_scale", "separating_plane", "is_stack"]


def is_stack(M: Any) -> bool:
    """True for a stack (..., n, n) of matrices rather than one matrix."""
    if isinstance(M, np.ndarray):
        return M.ndim > 2
    try:
        return isinstance(M[0][0], list | tuple | np.ndarray)
    except (TypeError, IndexError, KeyError):
        return False



def contact_scale(A: Any, B: Any, *, rtol: float = 1e-12) -> Any:
    """Certified contact scale mu* of a pair: > 1 separate, = 1 tangent, < 1 overlap.

    Args:
        A: one matrix (any input form of :func:`core.classify`), or a stack (..., n, n) of
            float matrices (then the vectorised batch form is used).
        B: the same for B (stacks broadcast against A).
        rtol: relative width asked of the bracket, > 0: hi - lo <= rtol * hi (one pair: met,
            usually far better; batch: see :func:`core.witness.batch.contact_scale_batch`). The
            exact value is :meth:`ContactScale.algebraic`.

    Returns:
        One pair: a :class:`ContactScale` (exact rational ``lo``, ``hi``; ``approx``;
        ``relation``; ``algebraic()`` for the exact value). Stacks: a
        :class:`core.witness.batch.ContactScaleBatch` of float arrays ``lo <= mu* <= hi``.

    Raises:
        ValueError: a matrix is not an ellipse/ellipsoid, or the sizes differ.

    Examples:
        >>> sphere = lambda x, r: [[1, 0, 0, -x], [0, 1, 0, 0], [0, 0, 1, 0], [-x, 0, 0, x * x - r * r]]
        >>> cs = contact_scale(sphere(0, 1), sphere(5, 1.5))      # mu = 5 / 2.5
        >>> cs.lo, cs.hi, str(cs.relation)
        (2, 2, 'separate')
        >>> contact_scale(sphere(0, 1), sphere(2, 1)).relation
        <Relation.TANGENT: 1>
        >>> cs = contact_scale(sphere(0, 1), sphere(1, fmpq(1, 3)))    # mu = 1 / (4/3)
        >>> cs.approx, str(cs.relation)
        (0.75, 'overlap')
    """
    if is_stack(A) or is_stack(B):
        return contact_scale_batch(A, B, rtol=rtol)
    return contact_scale_pair(A, B, rtol=rtol)


def separating_plane(A: Any, B: Any) -> Any:
    """A plane n.x = d with exact rational n, d: A strictly in n.x < d, B strictly in n.x > d.

    Args:
        A: one matrix (any input form of :func:`core.classify`), or a float stack (..., n, n)
            (then :func:`core.witness.batch.separating_plane_batch`: float planes with a
            certified flag).
        B: the same for B.

    Returns:
        A :class:`SeparatingPlane`, verified exactly (dual quadric) before it is returned.

    Raises:
        ValueError: the pair is not separate (tangent or overlapping: no plane separates it
            strictly), or a matrix is invalid.

    Examples:
        >>> circle = lambda x: [[1, 0, -x], [0, 1, 0], [-x, 0, x * x - 1]]
        >>> p = separating_plane(circle(0), circle(3))
        >>> p.normal, p.offset
        ((1, 0), 3/2)
        >>> separating_plane(circle(0), circle(2))
        Traceback (most recent call last):
        ...
        ValueError: A and B are tangent: they touch, so no plane separates them strictly (contact_point gives where)
    """
    if is_stack(A) or is_stack(B):
        return separating_plane_batch(A, B)
    return separating_plane_pair(A, B)
