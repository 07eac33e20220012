"""Safe expression parser (core.moving.expressions): exact values, errors with positions, limits."""

from fractions import Fraction

import pytest
from flint import fmpq, fmpq_poly

from core.moving.expressions import MAX_DEGREE, RationalFunction, parse_expression


def poly_value(f: RationalFunction, t: Fraction) -> Fraction:
    """Evaluate a rational (no sqrt) function exactly at t, by hand from the coefficients."""
    assert f.num.q.is_zero()
    num = sum(Fraction(int(c.p), int(c.q)) * t**k for k, c in enumerate(f.num.p.coeffs()))
    den = sum(Fraction(int(c.p), int(c.q)) * t**k for k, c in enumerate(f.den.coeffs()))
    return num / den


@pytest.mark.parametrize(
    "text, t, expected",
    [
        ("3*t + 1", Fraction(2), Fraction(7)),
        ("0.1", Fraction(0), Fraction(1, 10)),
        ("1e-3*t", Fraction(5), Fraction(5, 1000)),
        (".5 + t^2", Fraction(3), Fraction(19, 2)),
        ("-t^2", Fraction(3), Fraction(-9)),  # unary minus binds looser than ^
        ("2^3", Fraction(0), Fraction(8)),
        ("(t - 1)*(t + 1)/(t - 1)", Fraction(5), Fraction(6)),
        ("1/(t^2 + 1)", Fraction(2), Fraction(1, 5)),
        ("2*(t^2 - 1)/(t^2 + 1)", Fraction(1, 2), Fraction(-6, 5)),
        ("t**2 - 1/3", Fraction(1), Fraction(2, 3)),
        ("((((t))))", Fraction(7), Fraction(7)),
        ("t^0", Fraction(9), Fraction(1)),
        ("12 - 3 - 4", Fraction(0), Fraction(5)),  # left associative
        ("12 / 3 / 4", Fraction(0), Fraction(1)),
    ],
)
def test_values(text, t, expected):
    assert poly_value(parse_expression(text), t) == expected


def test_sqrt_is_exact_and_reduced():
    f = parse_expression("sqrt(8)/2 * t")  # = sqrt(2) t
    assert f.num.d == 2 and f.num.p.is_zero() and f.num.q == fmpq_poly([0, 1])
    assert parse_expression("sqrt(4)") == parse_expression("2")
    g = parse_expression("sqrt(2)*sqrt(2)")
    assert g.num.q.is_zero() and g.num.p == fmpq_poly([2])
    h = parse_expression("sqrt(1/2)")  # sqrt(2)/2
    assert h.num.q == fmpq_poly([fmpq(1, 2)]) and h.num.d == 2
    # 1/(1 + sqrt 2) = sqrt 2 - 1: the denominator is made rational
    inv = parse_expression("1/(1 + sqrt(2))")
    assert inv.is_polynomial() and inv.num.p == fmpq_poly([-1]) and inv.num.q == fmpq_poly([1])


def test_round_trip_of_printed_form():
    for text in ["(-8*t^2 + 8*t - 1)/(8*t^2 - 8*t + 3)", "sqrt(2)*(t - 1)*(3*t - 1)/(-6*t^2 + 6*t - 2)", "3/7*t^3 - t"]:
        f = parse_expression(text)
        assert parse_expression(str(f)) == f


@pytest.mark.parametrize(
    "text, fragment",
    [
        ("3*t + x", "unexpected 'x' at position 6"),
        ("3*t + $", "unexpected '$' at position 6"),
        ("sin(t)", "unexpected 'sin' at position 0"),
        ("2t", "unexpected 't' at position 1"),
        ("(t + 1", "unexpected end of input at position 6"),
        ("t + 1)", "unexpected ')' at position 5"),
        ("", "empty expression"),
        ("t / 0", "division by zero"),
        ("t / (t - t)", "division by zero"),
        ("t^-1", "non-negative integer"),
        ("t^1.5", "non-negative integer"),
        ("t^t", "non-negative integer"),
        ("t^2^2", "parentheses"),
        ("t^99", "exponent 99 too large"),
        ("sqrt(t)", "positive rational constant"),
        ("sqrt(-2)", "non-positive"),
        ("sqrt(0)", "non-positive"),
        ("sqrt(2) + sqrt(3)", "only one sqrt(d)"),
        ("__import__('os')", "unexpected '__import__'"),
        ("T", "unexpected 'T'"),
        ("t\u00b2", "unexpected '\u00b2' at position 1"),
        ("\u0661\u0662", "unexpected '\u0661' at position 0"),
    ],
)
def test_errors_name_the_offender(text, fragment):
    with pytest.raises(ValueError) as e:
        parse_expression(text)
    assert fragment in str(e.value)


def test_limits():
    from core.shapes.limits import SERVER

    long_text = "1+" * (SERVER.expression_chars // 2) + "1"
    with pytest.raises(ValueError, match="too long"):  # the server's edge caps the length ...
        parse_expression(long_text, limits=SERVER)
    assert str(parse_expression(long_text)) == str(SERVER.expression_chars // 2 + 1)  # ... the library does not
    with pytest.raises(ValueError, match="degree in t too high"):
        parse_expression(f"t^{MAX_DEGREE + 1}")
    assert parse_expression(f"t^{MAX_DEGREE + 1} / t").degree() == MAX_DEGREE  # after cancellation
    with pytest.raises(ValueError, match="nested too deeply"):
        parse_expression("(" * 100 + "t" + ")" * 100)
    with pytest.raises(ValueError, match="nested too deeply"):
        parse_expression("-" * 100 + "t")


def test_numbers_are_constants():
    assert parse_expression(3) == parse_expression("3")
    assert parse_expression(fmpq(1, 3)) == parse_expression("1/3")
    assert parse_expression(0.5) == parse_expression("1/2")
