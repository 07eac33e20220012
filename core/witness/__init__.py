"""Contact geometry: the certified witnesses behind each answer (issue 15).

How far from touching, where they touch, and which plane separates them, for two ellipses or
ellipsoids, certified like the relation itself::

    from core.witness import contact_scale, separating_plane, contact_point, witness

* :func:`contact_scale`: the Perram-Wertheim contact scale mu* (scale both shapes about their
  centres by mu*: they touch), a certified rational bracket, exact on request; vectorised for
  stacks of float pairs.
* :func:`separating_plane`: n.x = d with exact rationals, A strictly on one side, B on the other,
  verified exactly (float stacks: float planes with a certified flag).
* :func:`contact_point`: the exact contact point and normal of a tangent pair, or a rational
  point inside both shapes of an overlapping pair.
* :func:`witness`: the one that proves the relation, with a sentence.
* :func:`distance`: a certified bracket of the Euclidean distance (an empty slab below, two
  points of the shapes above).
* :func:`contact_scale_batch`, :func:`separating_plane_batch`: the float forms, for stacks or
  for one float pair (0-d results); :func:`float_witness`: all of them for one float pair from
  one float preparation (the scene's drag path).

Modules: :mod:`~core.witness.centred` (centre, size, inverse shape matrix),
:mod:`~core.witness.contact_function` (the contact function, exact), :mod:`~core.witness.floats`
(float estimates), :mod:`~core.witness.scale`, :mod:`~core.witness.plane`,
:mod:`~core.witness.point`, :mod:`~core.witness.distance`, :mod:`~core.witness.batch` (vectorised forms),
:mod:`~core.witness.floatdet` (certified float determinants), :mod:`~core.witness.numbers`
(exact algebraic values), :mod:`~core.witness.witness`.
"""

from .api import contact_scale as contact_scale
from .api import separating_plane as separating_plane
from .batch import ContactScaleBatch as ContactScaleBatch
from .batch import FloatWitness as FloatWitness
from .batch import PlaneBatch as PlaneBatch
from .batch import contact_scale_batch as contact_scale_batch
from .batch import float_witness as float_witness
from .batch import separating_plane_batch as separating_plane_batch
from .distance import DistanceBracket as DistanceBracket
from .distance import distance as distance
from .plane import SeparatingPlane as SeparatingPlane
from .point import ContactPoint as ContactPoint
from .point import contact_point as contact_point
from .scale import ContactScale as ContactScale
from .witness import SENTENCES as SENTENCES
from .witness import Witness as Witness
from .witness import margin_text as margin_text
from .witness import witness as witness

__all__ = [
    "SENTENCES",
    "ContactPoint",
    "ContactScale",
    "ContactScaleBatch",
    "DistanceBracket",
    "FloatWitness",
    "PlaneBatch",
    "SeparatingPlane",
    "Witness",
    "contact_point",
    "contact_scale",
    "contact_scale_batch",
    "distance",
    "float_witness",
    "margin_text",
    "separating_plane",
    "separating_plane_batch",
    "witness",
]
