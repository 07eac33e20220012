"""The one error of bad input: :class:`InvalidInput`, a ValueError that says which pair and matrix.

Core raises it wherever input is not what it must be (a matrix that is no ellipse or ellipsoid,
an unreadable entry, a non-symmetric matrix); the message says what is wrong, and the attributes
say where, so that a caller (the HTTP API's one exception handler, the command line) can name
the field without parsing the text. It is a ValueError: code that caught ValueError still does.
"""

from __future__ import annotations

__all__ = ["InvalidInput"]


class InvalidInput(ValueError):
    """Bad input, with where it is: ``pair`` (index in a batch, or None) and ``matrix`` ("A", "B", ...).

    Examples:
        >>> e = InvalidInput("pair 3: B is not an ellipse", pair=3, matrix="B", reason="B is not an ellipse")
        >>> isinstance(e, ValueError), e.pair, e.matrix, e.reason
        (True, 3, 'B', 'B is not an ellipse')
    """

    def __init__(self, message: str, *, pair: int | None = None, matrix: str | None = None, reason: str | None = None) -> None:
        super().__init__(message)
        self.pair = pair
        """Index of the pair in the batch (flat), or None (one pair, or not about a pair)."""
        self.matrix = matrix
        """Which matrix: the name the caller gave ("A", "B", "matrix"), or None."""
        self.reason = reason if reason is not None else message
        """The message without the pair's prefix (what is wrong with the matrix)."""

    def at_pair(self, pair: int | None, prefix: str) -> InvalidInput:
        """The same error placed at ``pair`` of a batch, its message prefixed (e.g. "pair 3: ")."""
        return InvalidInput(prefix + self.reason, pair=pair, matrix=self.matrix, reason=self.reason)

    @classmethod
    def of(cls, error: ValueError, *, matrix: str | None = None) -> InvalidInput:
        """``error`` as an InvalidInput (kept as it is if it already is one)."""
        if isinstance(error, InvalidInput):
            return error
        return cls(str(error), matrix=matrix)
