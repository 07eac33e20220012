"""Scene configuration and per-tab state: the single mutable object of one browser tab.

A :class:`SceneConfig` is what a user can write down (``--config file.json``, the defaults, a
preset); :class:`AppState` is what one tab is looking at right now (the shapes, the motion, t,
the last explanation). Numbers entered by hand stay exact: a shape parameter is a float (the
exact binary rational it is, e.g. after a drag) or an ``fmpq`` (typed text such as "3/7").
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from flint import fmpq

from core.shapes.numbers import to_float

from .texts import APPROX, Number, exact_text, parse_matrix, parse_vector, read_time, round_decimal

__all__ = ["ShapeState", "SceneConfig", "AppState", "StatusError", "DEFAULT_PRESET", "PALETTES", "RELATION_HEX"]

RELATION_HEX: dict[str, str] = {
    "separate": "#2ca02c",
    "tangent": "#ffbf00",
    "overlap": "#d62728",
}
"""Relation -> colour of the default palette (shapes, bars, the readout, the legend)."""

PALETTES: dict[str, dict[str, str]] = {
    "green / amber / red": RELATION_HEX,
    # Okabe & Ito's colour-blind safe set: blue, orange, vermillion differ in lightness and
    # hue for deuteranopes, protanopes and tritanopes alike
    "colour-blind safe": {"separate": "#0072b2", "tangent": "#e69f00", "overlap": "#d55e00"},
}
"""Named palettes (View -> Palette); the first is the default."""

if TYPE_CHECKING:
    from ..pair.analysis import AnalysisView
    from ..pair.contact import WitnessView
    from ..pair.motion import MotionModel


DEFAULT_PRESET = "example-29"
"""Preset loaded when the scene opens with no configuration (two ellipsoids about to touch)."""


@dataclass
class ShapeState:
    """One shape: centre, semi-axes, orientation, as the user entered or dragged them."""

    center: tuple[Number, ...]
    """(x, y) or (x, y, z)."""
    semi_axes: tuple[Number, ...]
    """Positive semi-axis lengths along the body axes."""
    orientation: tuple[Number, ...]
    """2D: (angle,) in radians or a quaternion (w, 0, 0, z); 3D: quaternion (w, x, y, z)."""
    matrix: tuple[tuple[fmpq, ...], ...] | None = None
    """The exact matrix when the shape was typed as one (then centre, semi-axes and orientation
    are its float decomposition, for drawing and for the fields)."""
    typed: dict[str, str] = field(default_factory=dict, compare=False)
    """Field ("center", "semi_axes", "orientation", "matrix") -> the text the user typed there,
    shown back verbatim: the exact value certified is what that text says."""

    FIELDS = ("center", "semi_axes", "orientation")

    def field_texts(self) -> dict[str, str]:
        """What each Shape field shows: exactly the value the shape holds.

        Typed text verbatim; an exact rational as its decimal or "p/q"; a computed float (a pose
        drawn at t, the float decomposition of a typed matrix) rounded to
        :data:`~app.scene.common.texts.SHOWN_DIGITS` and marked "≈ " (never a rounded number that looks
        exact); the matrix field: the typed matrix, or empty.

        Examples:
            >>> s = ShapeState((fmpq(1, 10), 2.0000000000000004), (fmpq(1), fmpq(3, 7)), (0.0,))
            >>> s.field_texts()["center"], s.field_texts()["semi_axes"]
            ('≈ 0.1, 2', '1, 3/7')
        """
        out: dict[str, str] = {}
        for key in self.FIELDS:
            values = getattr(self, key)
            if key in self.typed:
                out[key] = self.typed[key]
            elif all(isinstance(v, fmpq) for v in values):
                out[key] = ", ".join(exact_text(v) for v in values)
            else:
                out[key] = APPROX + ", ".join(exact_text(v) for v in self._rounded(key))
        if "matrix" in self.typed:
            out["matrix"] = self.typed["matrix"]
        else:
            out["matrix"] = "" if self.matrix is None else "; ".join(", ".join(exact_text(v) for v in row) for row in self.matrix)
        return out

    def _scale(self) -> float:
        """Size of the shape (largest |centre coordinate| or semi-axis): where float noise ends."""
        return max([abs(float(v)) for v in self.center] + [float(v) for v in self.semi_axes])

    def _rounded(self, key: str) -> tuple[fmpq, ...]:
        """The values of one field rounded to SHOWN_DIGITS significant digits.

        The centre against the size of the shape (noise such as 1e-17 becomes 0), each semi-axis
        against itself, the orientation (angle or quaternion components, of order 1) against 1.
        """
        values = getattr(self, key)
        if key == "center":
            scale = self._scale()
            return tuple(round_decimal(v, scale) for v in values)
        if key == "semi_axes":
            return tuple(round_decimal(v) for v in values)
        return tuple(round_decimal(v, 1) for v in values)

    def rationalised(self) -> ShapeState:
        """The shape made exactly the decimals its fields show (floats rounded to SHOWN_DIGITS).

        What a drag and leaving a motion do: from then on the shape certified is the one whose
        numbers are on screen. Exact parameters stay as they are; a typed matrix stays.

        Examples:
            >>> s = ShapeState((2.0000000000000004, -2.7e-17), (0.9999999999999998, 1.0), (0.0,))
            >>> r = s.rationalised(); r.center, r.semi_axes, r.field_texts()["center"]
            ((2, 0), (1, 1), '2, 0')
        """
        if self.matrix is not None or not any(isinstance(v, float) for k in self.FIELDS for v in getattr(self, k)):
            return self
        center, axes, orient = (self._rounded(k) for k in self.FIELDS)
        if any(v <= 0 for v in axes) or (len(orient) == 4 and not any(orient)):
            raise ValueError("the shape is too thin to be written with the digits shown")
        return ShapeState(center, axes, orient)

    @classmethod
    def from_matrix(cls, M: Any, name: str = "matrix") -> ShapeState:
        """A shape typed as its matrix, checked and normalised exactly.

        The symmetric part, with the interior X^T M X < 0; drawn from its float decomposition.

        Raises:
            ValueError: not an ellipse/ellipsoid, or unreadable (the message names ``name``).

        Examples:
            >>> s = ShapeState.from_matrix([["1", "0", "-2"], ["0", "1", "0"], ["-2", "0", "3"]])
            >>> s.center, s.semi_axes, str(s.matrix[0][2])
            ((2, 0), (1.0, 1.0), '-2')
        """
        import numpy as np
        from flint import fmpq_mat

        from core.shapes.quadrics import axes_from_quadric, validate_quadric

        E = validate_quadric(M, name=name)
        exact = tuple(tuple(fmpq(v) for v in row) for row in E)
        p = axes_from_quadric(np.array([[to_float(v) for v in row] for row in exact]), validate=False)
        # the centre is rational (Q c = -m, Q positive definite): exact; axes and orientation are
        # eigen-data (irrational in general): their float decomposition, shown as "≈"
        d = len(exact) - 1
        Q = fmpq_mat([list(row[:d]) for row in exact[:d]])
        c = Q.solve(fmpq_mat([[-row[d]] for row in exact[:d]]))
        center = tuple(c[i, 0] for i in range(d))
        return cls(center, tuple(p.semi_axes), tuple(p.orientation), matrix=exact)

    @property
    def dim(self) -> int:
        """2 or 3."""
        return len(self.center)

    @property
    def is_exact(self) -> bool:
        """True when any parameter is an exact rational (typed text)."""
        return any(isinstance(v, fmpq) for v in (*self.center, *self.semi_axes, *self.orientation))

    def quadric(self) -> Any:
        """Matrix of the shape (exact ``fmpq`` lists when any entry is exact, else floats)."""
        from core import quadric_from_axes

        if self.matrix is not None:
            return [list(row) for row in self.matrix]

        o: Any = self.orientation
        exact = all(isinstance(v, fmpq) for v in (*self.center, *self.semi_axes))
        if len(o) == 1:
            angle = o[0]
            if angle == 0:
                o = None
            elif exact:
                o = angle_quaternion(angle)
            else:  # float parameters (a configuration's JSON floats, many bodies): the float64 matrix
                return quadric_from_axes(
                    [float(v) for v in self.center], [float(v) for v in self.semi_axes], float(angle)
                )
        if exact and o is not None and any(isinstance(v, float) for v in o):
            o = [fmpq(*v.as_integer_ratio()) if isinstance(v, float) else v for v in o]
        return quadric_from_axes(self.center, self.semi_axes, o, exact=exact)

    def float_pose(self) -> tuple[tuple[float, float, float], tuple[float, float, float, float], tuple[float, float, float]]:
        """(position, wxyz, scale) for drawing, in 3D (2D shapes live in z = 0, rotate about z)."""
        c = [float(v) for v in self.center]
        r = [float(v) for v in self.semi_axes]
        if self.dim == 2:
            pos = (c[0], c[1], 0.0)
            scale = (r[0], r[1], 1.0)
            if len(self.orientation) == 1:
                h = float(self.orientation[0]) / 2
                wxyz = (math.cos(h), 0.0, 0.0, math.sin(h))
            else:
                wxyz = _unit(tuple(float(v) for v in self.orientation))
            return pos, wxyz, scale
        return (c[0], c[1], c[2]), _unit(tuple(float(v) for v in self.orientation)), (r[0], r[1], r[2])

    def to_dict(self) -> dict[str, Any]:
        """JSON form (numbers as exact strings; floats as their shortest round-trip repr).

        A shape typed as a matrix is written as its exact matrix.
        """
        if self.matrix is not None:
            return {"matrix": [[str(v) for v in row] for row in self.matrix]}
        return self.params_dict()

    def params_dict(self) -> dict[str, list[str]]:
        """Centre, semi-axes and orientation as JSON (also of a shape typed as a matrix)."""
        return {
            "center": [_num_text(v) for v in self.center],
            "semi_axes": [_num_text(v) for v in self.semi_axes],
            "orientation": [_num_text(v) for v in self.orientation],
        }

    @classmethod
    def from_dict(cls, d: Any, dim: int, name: str) -> ShapeState:
        """Read and check a shape from its JSON form (see :meth:`to_dict`)."""
        if not isinstance(d, dict):
            raise ValueError(f"shape {name}: expected an object with center, semi_axes, orientation (or matrix)")
        unknown = set(d) - {"center", "semi_axes", "orientation", "matrix"}
        if unknown:
            raise ValueError(f"shape {name}: unknown keys {sorted(unknown)}")
        if d.get("matrix") is not None:
            shape = cls.from_matrix(parse_matrix(d["matrix"], dim, f"{name}.matrix"), f"{name}.matrix")
            return shape
        center = parse_vector(d.get("center", [0] * dim), dim, f"{name}.center")
        axes = parse_vector(d.get("semi_axes", [1] * dim), dim, f"{name}.semi_axes")
        if any(v <= 0 for v in axes):
            raise ValueError(f"{name}.semi_axes: must be positive")
        default_o = [0] if dim == 2 else [1, 0, 0, 0]
        orient = parse_vector(d.get("orientation", default_o), (1, 4) if dim == 2 else 4, f"{name}.orientation")
        if len(orient) == 4 and all(v == 0 for v in orient):
            raise ValueError(f"{name}.orientation: the quaternion is zero")
        if dim == 2 and len(orient) == 4 and (orient[1] != 0 or orient[2] != 0):
            raise ValueError(f"{name}.orientation: a 2D quaternion must rotate about z: (w, 0, 0, z)")
        return cls(center, axes, orient)


def angle_quaternion(angle: Any) -> list[fmpq]:
    """The exact rotation the scene means by a 2D angle θ (radians).

    The quaternion (cos θ/2, 0, 0, sin θ/2) with its two components computed in float64 and then
    taken as the exact binary rationals they are (θ itself is the float nearest to the typed value).

    The rotation is then exact (a rational quaternion gives a rational rotation matrix), so the
    centre and semi-axes stay exact too; cos and sin of a rational angle are not rational.

    Examples:
        >>> angle_quaternion(fmpq(0))
        [1, 0, 0, 0]
    """
    h = float(angle) / 2
    return [fmpq(*math.cos(h).as_integer_ratio()), fmpq(0), fmpq(0), fmpq(*math.sin(h).as_integer_ratio())]


def _unit(q: tuple[float, ...]) -> tuple[float, float, float, float]:
    n = math.sqrt(sum(v * v for v in q)) or 1.0
    return (q[0] / n, q[1] / n, q[2] / n, q[3] / n)


def _num_text(v: Number) -> str:
    return repr(v) if isinstance(v, float) else exact_text(v)


def _default_shapes(dim: int) -> tuple[ShapeState, ShapeState]:
    if dim == 2:
        return (
            ShapeState((fmpq(0), fmpq(0)), (fmpq(2), fmpq(1)), (fmpq(0),)),
            ShapeState((fmpq(3), fmpq(3, 2)), (fmpq(3, 2), fmpq(1, 2)), (fmpq(3, 5),)),
        )
    one, zero = fmpq(1), fmpq(0)
    return (
        ShapeState((zero, zero, zero), (fmpq(2), one, one), (one, zero, zero, zero)),
        ShapeState((fmpq(3), fmpq(3, 2), zero), (fmpq(3, 2), one, fmpq(1, 2)), (one, zero, zero, fmpq(1, 3))),
    )


@dataclass
class SceneConfig:
    """What a tab opens on: static shapes and/or a preset/motion, t, and display options."""

    dim: int = 3
    """2 (ellipses in the z = 0 plane, camera from above) or 3."""
    A: ShapeState | None = None
    """Static shape A (None: the default for ``dim``)."""
    B: ShapeState | None = None
    preset: str | None = DEFAULT_PRESET
    """Name of a motion preset (``core.moving.presets``); None for a static scene."""
    motion: dict[str, Any] | None = None
    """Typed motion (expression strings per shape and the interval), overrides ``preset``."""
    t: float | str | None = None
    """Time to show: a number, or exact text ("2/3", "(12-2*sqrt(2))/17"); None: the motion's default."""
    event: int | None = None
    """Show the k-th event (1-based) exactly instead of ``t``."""
    show_plots: bool = True
    """Live uPlot plots (skipped entirely when False)."""
    separating_plane: bool = False
    """Draw a separating plane when the shapes are separate."""
    gizmos: bool = False
    """Show the transform gizmos ("Move the shapes"; off by default: they covered the shapes)."""
    palette: str | None = None
    """Relation palette name (:data:`PALETTES`; None: the default)."""

    def shapes(self) -> tuple[ShapeState, ShapeState]:
        """The static shapes, defaults filled in."""
        da, db = _default_shapes(self.dim)
        return (self.A or da, self.B or db)

    @classmethod
    def from_dict(cls, d: Any) -> SceneConfig:
        """Read and check a configuration (the JSON accepted by ``--config``).

        Raises:
            ValueError: unknown keys, wrong types or bad numbers (the message names the field).

        Examples:
            >>> SceneConfig.from_dict({"dim": 2, "preset": None}).dim
            2
            >>> SceneConfig.from_dict({"dimension": 2})
            Traceback (most recent call last):
            ...
            ValueError: config: unknown keys ['dimension']; allowed: A, B, dim, event, gizmos, motion, palette, preset, separating_plane, show_plots, t
        """
        if not isinstance(d, dict):
            raise ValueError("config: expected a JSON object")
        allowed = {f for f in cls.__dataclass_fields__}
        unknown = set(d) - allowed
        if unknown:
            raise ValueError(f"config: unknown keys {sorted(unknown)}; allowed: {', '.join(sorted(allowed))}")
        dim = d.get("dim", 3)
        if dim not in (2, 3) or isinstance(dim, bool):
            raise ValueError(f"config: dim must be 2 or 3, got {dim!r}")
        cfg = cls(dim=dim)
        for key in ("A", "B"):
            if d.get(key) is not None:
                setattr(cfg, key, ShapeState.from_dict(d[key], dim, key))
        preset = d.get("preset", DEFAULT_PRESET if "A" not in d and "B" not in d else None)
        if preset is not None and not isinstance(preset, str):
            raise ValueError("config: preset must be a name (string) or null")
        cfg.preset = preset
        motion = d.get("motion")
        if motion is not None and not isinstance(motion, dict):
            raise ValueError("config: motion must be an object")
        cfg.motion = motion
        if d.get("t") is not None:
            t = d["t"]
            if isinstance(t, str):
                try:
                    read_time(t)
                except ValueError as e:
                    raise ValueError(f"config: t: {e}") from None
                cfg.t = t
            else:
                try:
                    t = float(t)
                except (TypeError, ValueError):
                    raise ValueError(f"config: t must be a number or exact text, got {d['t']!r}") from None
                if not math.isfinite(t):
                    raise ValueError("config: t must be finite")
                cfg.t = t
        if d.get("event") is not None:
            ev = d["event"]
            if not isinstance(ev, int) or isinstance(ev, bool) or ev < 1:
                raise ValueError(f"config: event must be a positive integer (1-based), got {ev!r}")
            cfg.event = ev
        if d.get("palette") is not None:
            if d["palette"] not in PALETTES:
                raise ValueError(f"config: palette must be one of {', '.join(PALETTES)}")
            cfg.palette = d["palette"]
        for key in ("show_plots", "separating_plane", "gizmos"):
            if key in d:
                if not isinstance(d[key], bool):
                    raise ValueError(f"config: {key} must be true or false")
                setattr(cfg, key, d[key])
        return cfg

    @classmethod
    def from_json_file(cls, path: str | Path) -> SceneConfig:
        """Read a configuration file (see :meth:`from_dict`)."""
        try:
            data = json.loads(Path(path).read_text())
        except OSError as e:
            raise ValueError(f"cannot read config file {path}: {e.strerror}") from None
        except json.JSONDecodeError as e:
            raise ValueError(f"config file {path} is not valid JSON: {e}") from None
        return cls.from_dict(data)

    def to_dict(self) -> dict[str, Any]:
        """JSON form (round-trips through :meth:`from_dict`)."""
        a, b = self.shapes()
        return {
            "dim": self.dim,
            "A": a.to_dict(),
            "B": b.to_dict(),
            "preset": self.preset,
            "motion": self.motion,
            "t": self.t,
            "event": self.event,
            "show_plots": self.show_plots,
            "separating_plane": self.separating_plane,
            "gizmos": self.gizmos,
            "palette": self.palette,
        }


class StatusError(str):
    """A status line that reports a failure, as plain text.

    Each view renders it as it shows errors (the motion panel in red, the readout after a warning
    sign); the text never carries HTML.
    """


@dataclass
class AppState:
    """Everything one tab shows: controllers change it, ``Session.refresh`` draws it."""

    dim: int
    """2 or 3."""
    shapes: dict[str, ShapeState]
    """"A" and "B": the static shapes, or during a motion the shapes drawn at t (floats)."""
    motion: MotionModel | None = None
    """The loaded motion, or None (static shapes)."""
    analysis: AnalysisView | None = None
    """Its analysis once done (None while it runs)."""
    t: float = 0.0
    """Current time (when a motion is loaded), as drawn."""
    t_exact: Any = None
    """The exact time typed in the t box (a rational such as 1/3, or an algebraic number such as
    (12 - 2 sqrt 2)/17), or None: the relation and the readout are certified at this value; the
    shapes are drawn at its float ``t``."""
    t_text: str | None = None
    """How the t box shows t: the text the user typed ("3/4" stays "3/4"), or None (the number)."""
    event: int | None = None
    """1-based index of the event shown exactly, or None when showing ``t``."""
    auto_t: bool = False
    """The start time is the analysis' default (just before the first event) until the user moves t."""
    relation: str | None = None
    """Relation currently drawn ("separate", "tangent", "overlap"), None when unknown."""
    explanation: dict[str, Any] | None = None
    """Last ``core.explain(A, B).to_dict()`` of the static shapes (None during a motion)."""
    witness: WitnessView | None = None
    """Last witness of the static shapes (margin, sentence, plane or point)."""
    status: str = ""
    """Status line of the motion panel (plain text; a :class:`StatusError` for a failure)."""
    analysing: bool = False
    """An analysis of ``motion`` is running."""
    errors: dict[str, str] = field(default_factory=dict)
    """Field -> message shown next to it: "A", "B", "interval" (motion editor), "shape A",
    "shape B" (shape folders), "t" (t box)."""
    show_plots: bool = True
    separating_plane: bool = False
    gizmos: bool = False
    palette: str = "green / amber / red"
    """Name of the relation palette (:data:`PALETTES`)."""
    follow: bool = False
    """The camera follows the moving shapes."""
    plot_scale: str = "asinh"
    """Scale of the plots' y axis (:data:`app.scene.pair.plots.SCALES`)."""
    answer_hidden: bool = False
    """A lesson step's question is open: the picture and the panel keep the relation to themselves
    (neutral colours, no relation words) until "Reveal the answer" or an edit (:mod:`app.scene.pair.lesson_view`)."""
