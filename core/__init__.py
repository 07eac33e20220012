"""Certified interference of two ellipses or ellipsoids, fixed or moving.

Implements Caravantes, Diaz-Toca, Fioravanti, Gonzalez-Vega, "Solving the interference problem
for ellipses and ellipsoids: new formulae". Conventions are documented once, in
:mod:`core.shapes.quadrics`. Public API::

    from core import classify, Relation, explain          # static pairs (certified)
    from core import classify_detailed                    # + which arithmetic certified each pair
    from core import analyse                              # moving pairs: events and intervals
    from core import read_motion, read_interval           # user text, under limits (one grammar)
    from core import quadric_from_axes, axes_from_quadric, validate_quadric
    from core import warm_up, set_threads, get_threads, threads   # start the filter's threads; how many
    from core import filter_stats, Stats                  # how often each float stage fails (core.filtered)
    from core import contact_scale, separating_plane, contact_point, distance   # witnesses (core.witness)
    from core import contacts, Contacts, bodies_from_axes  # N bodies (core.bodies)
    from core import Box, Bodies, PairTable               # a periodic box; bodies with ids and box
    from core import BodyIndex                            # an index asked about new bodies
    from core import sweep_contacts, SweepContacts, first_contact   # N moving bodies: first contacts

``core`` imports only numpy, python-flint and the standard library (the float filter's C kernels
are the extension built when the package is installed, :mod:`core.fixed.compiled`); the Dask
path (:mod:`core.fixed.lazy`, :mod:`core.bodies.distributed`) imports dask only when it is used.
"""

from . import pickling as _pickling  # noqa: F401  (flint polynomials pickle: results travel between processes
from .bodies.bodies import Bodies as Bodies
from .bodies.box import Box as Box
from .bodies.broadphase import TooManyPairs as TooManyPairs
from .bodies.build import bodies_from_axes as bodies_from_axes
from .bodies.contacts import contacts as contacts
from .bodies.index import BodyIndex as BodyIndex
from .bodies.index import IndexPairs as IndexPairs
from .bodies.pairs import PairTable as PairTable
from .bodies.result import Contacts as Contacts
from .bodies.sweep import sweep_contacts as sweep_contacts
from .bodies.sweep_result import SweepContacts as SweepContacts
from .errors import InvalidInput as InvalidInput
from .filtered import Certifier as Certifier
from .filtered import FilterCounts as FilterCounts
from .filtered import Stats as Stats
from .filtered import filter_stats as filter_stats
from .fixed.classify import Classification as Classification
from .fixed.classify import classify as classify
from .fixed.classify import classify_detailed as classify_detailed
from .fixed.compiled import get_threads as get_threads
from .fixed.compiled import set_threads as set_threads
from .fixed.compiled import threads as threads
from .fixed.compiled import warm_up as warm_up
from .fixed.explain import explain as explain
from .fixed.explanation import Explanation as Explanation
from .fixed.explanation import Quantity as Quantity
from .moving.analysis import MotionAnalysis as MotionAnalysis
from .moving.analysis import analyse as analyse
from .moving.expressions import parse_expression as parse_expression
from .moving.first_contact import first_contact as first_contact
from .moving.motions import Motion as Motion
from .moving.motions import motion_from_dict as motion_from_dict
from .moving.motions import motion_to_dict as motion_to_dict
from .moving.motions import read_interval as read_interval
from .moving.motions import read_motion as read_motion
from .moving.presets import preset as preset
from .moving.presets import preset_names as preset_names
from .options import METHODS as METHODS
from .options import ON_INVALID as ON_INVALID
from .options import Method as Method
from .relation import Relation as Relation
from .shapes.quadrics import ShapeParams as ShapeParams
from .shapes.quadrics import axes_from_quadric as axes_from_quadric
from .shapes.quadrics import quadric_from_axes as quadric_from_axes
from .shapes.quadrics import rotation_from_quaternion as rotation_from_quaternion
from .shapes.quadrics import validate_quadric as validate_quadric
from .witness import ContactPoint as ContactPoint
from .witness import ContactScale as ContactScale
from .witness import DistanceBracket as DistanceBracket
from .witness import NoWitness as NoWitness
from .witness import SeparatingPlane as SeparatingPlane
from .witness import Witness as Witness
from .witness import WitnessArray as WitnessArray
from .witness import contact_point as contact_point
from .witness import contact_scale as contact_scale
from .witness import distance as distance
from .witness import separating_plane as separating_plane

__all__ = [
    "Bodies",
    "BodyIndex",
    "Box",
    "IndexPairs",
    "InvalidInput",
    "PairTable",
    "METHODS",
    "ON_INVALID",
    "Certifier",
    "Classification",
    "ContactPoint",
    "ContactScale",
    "Contacts",
    "classify_detailed",
    "Explanation",
    "FilterCounts",
    "Method",
    "Motion",
    "MotionAnalysis",
    "Quantity",
    "Relation",
    "SeparatingPlane",
    "TooManyPairs",
    "ShapeParams",
    "Stats",
    "NoWitness",
    "SweepContacts",
    "Witness",
    "analyse",
    "axes_from_quadric",
    "bodies_from_axes",
    "classify",
    "contact_point",
    "contact_scale",
    "contacts",
    "distance",
    "explain",
    "filter_stats",
    "first_contact",
    "motion_from_dict",
    "motion_to_dict",
    "parse_expression",
    "preset",
    "preset_names",
    "quadric_from_axes",
    "read_interval",
    "read_motion",
    "rotation_from_quaternion",
    "separating_plane",
    "set_threads",
    "get_threads",
    "threads",
    "DistanceBracket",
    "WitnessArray",
    "sweep_contacts",
    "validate_quadric",
    "warm_up",
]
