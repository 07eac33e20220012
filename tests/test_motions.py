"""Motions (core.moving.motions): JSON form, exact A(t) = M^-T A0 M^-1, evaluation for drawing."""

import math
from fractions import Fraction

import numpy as np
import pytest
from flint import fmpq

from core.moving.motions import (
    as_motion,
    matrix_at,
    matrix_at_exact,
    motion_from_dict,
    motion_to_dict,
    shape_at,
)
from core.moving.presets import preset
from core.shapes.quadrics import quadric_from_axes


def F(x):
    return fmpq(x.numerator, x.denominator) if isinstance(x, Fraction) else fmpq(x)


def test_translation_matches_quadric_from_axes():
    m = motion_from_dict({"shape": {"center": ["1/2", 0], "semi_axes": [2, 1]}, "translation": ["t", "t^2"]})
    for t in (Fraction(0), Fraction(3, 2), Fraction(-2)):
        expected = quadric_from_axes([Fraction(1, 2) + t, t * t], [2, 1], exact=True)
        assert matrix_at_exact(m, F(t)) == expected


def test_rotation_quaternion_matches_quadric_from_axes_3d():
    # quaternion (1, t, 0, 0): rotation about x; compare with the lead's exact quadric_from_axes
    m = motion_from_dict({
        "shape": {"center": [0, 0, 0], "semi_axes": [3, 2, 1]},
        "rotation": {"quaternion": ["1", "t", "0", "0"]},
        "translation": ["1", "2*t", "-t"],
    })
    for t in (Fraction(0), Fraction(1, 3), Fraction(2)):
        expected = quadric_from_axes([1, 2 * t, -t], [3, 2, 1], [1, t, 0, 0], exact=True)
        assert matrix_at_exact(m, F(t)) == expected


def test_body_offset_is_moved_with_the_body():
    # body centre (1, 0) rotated by 90 degrees (quaternion [1, 1] = (1, 0, 0, 1)) lands at (0, 1)
    m = motion_from_dict({"shape": {"center": [1, 0], "semi_axes": [2, 1]}, "rotation": {"quaternion": ["1", "1"]}})
    p = shape_at(m, 0.0)
    assert np.allclose(p.center, [0, 1]) and np.allclose(sorted(p.semi_axes), [1, 2])
    assert math.isclose(abs(p.orientation[0]), math.pi / 2, abs_tol=1e-12)


def test_scale_and_rotation_matrix():
    # L = R diag(s): a unit circle scaled by (2, 1) then rotated 90 degrees: semi-axes (1, 2) along x, y
    m = motion_from_dict({
        "shape": {"center": [0, 0], "semi_axes": [1, 1]},
        "rotation": {"matrix": [["0", "-1"], ["1", "0"]]},
        "scale": ["2", "1"],
    })
    M = matrix_at(m, 0.0)
    assert np.allclose(M, [[1, 0, 0], [0, 0.25, 0], [0, 0, -1]])


def test_example30_rotations_are_orthogonal_and_denominators_positive():
    for key in "AB":
        M = as_motion(preset("example-30")[key]).matrix()
        # symmetric, and the constant determinant of the body (rigid motion keeps det A0)
        for i in range(4):
            for j in range(4):
                assert M[i][j] == M[j][i]
        t = fmpq(3, 7)
        # float evaluation agrees with the exact matrix at a rational point (drawing path)
        exact = [[float(e.num.p(t)) + float(e.num.q(t)) * math.sqrt(e.num.d) for e in row] for row in M]
        dens = [[float(e.den(t)) for e in row] for row in M]
        num = np.array(exact) / np.array(dens)
        assert np.allclose(num, matrix_at(as_motion(preset("example-30")[key]), 3 / 7))


def test_round_trip_dict():
    d = {"shape": {"center": [0, 0, 0], "semi_axes": [2, 3, 4], "orientation": [1, 0, 0, 0]},
         "translation": ["0", "7", "(t - 4)/2"], "rotation": {"quaternion": ["1", "0", "t", "0"]}, "scale": [1, 1, 2]}
    m = motion_from_dict(d)
    d2 = motion_to_dict(m)
    assert motion_from_dict(d2).matrix() == m.matrix()
    assert d2["translation"] == ["0", "7", "(t - 4)/2"]
    mm = as_motion([["1", "0", "-t"], ["0", "1", "0"], ["-t", "0", "t^2 - 1"]])
    assert motion_to_dict(mm) == {"matrix": [["1", "0", "-t"], ["0", "1", "0"], ["-t", "0", "t^2 - 1"]]}


@pytest.mark.parametrize(
    "bad, fragment",
    [
        ({"matrix": [["1", "t"], ["0", "1"]]}, "3x3"),
        ({"matrix": [["1", "t", "0"], ["0", "1", "0"], ["0", "0", "-1"]]}, "not symmetric"),
        ({"matrix": [["1", "0", "0"], ["0", "1", "0"], ["0", "0", "-1 + y"]]}, "matrix entry (2,2): unexpected 'y'"),
        ({"shape": {"center": [0, 0], "semi_axes": [1]}}, "semi_axes must have 2 entries"),
        ({"shape": {"center": [0, 0], "semi_axes": [1, 1]}, "translation": ["t"]}, "translation must have 2"),
        ({"shape": {"center": [0, 0], "semi_axes": [1, 1]}, "rotation": {"euler": [1]}}, "'rotation' must be"),
        ({"shape": {"center": [0, 0], "semi_axes": [1, 1]}, "spin": 1}, "unknown motion keys"),
        ({"shape": {"center": [0, 0], "semi_axes": [1, 1]}, "translation": ["sqrt(2)*t", "sqrt(3)"]}, "only one sqrt"),
        ({"shape": {"center": [0, 0, 0], "semi_axes": [1, 1, 1]}, "rotation": {"quaternion": ["0", "0", "0", "0"]}}, "identically zero"),
        ("A", "a motion is a dict"),
    ],
)
def test_bad_motions(bad, fragment):
    with pytest.raises(ValueError) as e:
        motion_from_dict(bad).matrix()
    assert fragment in str(e.value)


def test_float_matrix_matches_exact_evaluation_for_every_preset():
    """matrix_at's cached float Horner agrees with the exact matrix rounded (display path)."""
    import numpy as np

    from core.moving.motions import as_motion, matrix_at, matrix_at_exact
    from core.moving.presets import preset_arguments, preset_names

    for name in preset_names():
        args = preset_arguments(name)
        for key in ("A_t", "B_t"):
            m = as_motion(args[key])
            for t in ("-7/10", "0", "3/10", "19/10"):
                got = matrix_at(m, float(F(t)))
                try:
                    ref = np.array([[float(v) for v in row] for row in matrix_at_exact(m, t)])
                except ValueError:  # sqrt(d) entries: compare with the entries' own float values
                    ref = np.array([[e.value_float(float(F(t))) for e in row] for row in m.matrix()])
                assert np.allclose(got, ref, rtol=1e-12, atol=1e-12 * np.abs(ref).max()), (name, key, t)
