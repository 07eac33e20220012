"""The hat forms the code runs against the paper's explicit formulas and against flint.

``core.formulae.subresultants`` computes sign-equivalent "hat" forms (Section 4.3's layout);
the paper's s0, s1, s1,0 (NOTES.md, Remarks 11/23 with the corrected signs) are kept there as
``s*_full`` and must equal -a_n * c_j * hs_j exactly. s0 is also checked against flint's own
resultant Res(P, P') (Sylvester order), an independent implementation.
"""

from __future__ import annotations

from fractions import Fraction

import pytest
from flint import fmpq, fmpz_poly
from hypothesis import given
from hypothesis import strategies as st

from core.formulae.subresultants import (
    hat_s0,
    hat_s1,
    hat_s10,
    hat_scale,
    s0_full,
    s1_full,
    s10_full,
)

coeffs = st.integers(-50, 50)


@pytest.mark.parametrize("n", [3, 4])
@given(data=st.data())
def test_hat_forms_are_the_papers_subresultants_up_to_the_stated_factor(n, data):
    a = [data.draw(coeffs) for _ in range(n)] + [data.draw(st.integers(-50, -1))]  # a_n < 0
    c0, c1, c10 = (fmpq(c.numerator, c.denominator) for c in hat_scale(n))
    an = fmpq(a[n])
    assert fmpq(s0_full(a)) == -an * c0 * fmpq(hat_s0(a))
    assert fmpq(s1_full(a)) == -an * c1 * fmpq(hat_s1(a))
    assert fmpq(s10_full(a)) == -an * c10 * fmpq(hat_s10(a))


@pytest.mark.parametrize("n", [3, 4])
@given(data=st.data())
def test_s0_is_the_resultant_of_p_and_its_derivative(n, data):
    a = [data.draw(coeffs) for _ in range(n)] + [data.draw(st.integers(-50, -1))]
    P = fmpz_poly(a)
    assert s0_full(a) == P.resultant(P.derivative())


def test_the_scale_factors_are_positive():
    for n in (3, 4):
        assert all(c > 0 for c in hat_scale(n)) and all(isinstance(c, Fraction) for c in hat_scale(n))
