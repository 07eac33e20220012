"""Size limits on user text (core.shapes.limits): numbers, bounded expression arithmetic, sqrt(n).

Each hostile input of issue 11 is refused *before* the work (so these tests run in
milliseconds: a test that computed the work would take minutes or gigabytes), with a message
naming the limit; the same inputs under generous limits give the exact value, so the limit is
what refuses them.
"""

import pickle
import time
from fractions import Fraction

import pytest
from flint import fmpq, fmpz

from core.algebra.qsqrt import squarefree_decomposition
from core.moving.expressions import RationalFunction, parse_expression
from core.moving.motions import motion_from_dict
from core.shapes.limits import LIBRARY, SERVER, LimitExceeded, Limits, current, using
from core.shapes.numbers import parse_number, to_fmpq

SEMIPRIME_100 = (10**50 + 151) * (10**50 + 447)  # two 51-digit primes: factoring it takes forever


# --- numbers -------------------------------------------------------------------------------------

def test_library_reads_long_exact_numbers():
    """Issue 10: a valid 403-character rational is a number, not an error."""
    text = "1" * 201 + "/" + "3" * 201
    assert to_fmpq(text) == fmpq(int("1" * 201), int("3" * 201))
    assert to_fmpq("0." + "0" * 5000 + "1") == fmpq(1, 10**5001)


def test_server_caps_length_and_written_exponent():
    assert parse_number("1" * 400, SERVER) == int("1" * 400)
    with pytest.raises(LimitExceeded, match=r"number string too long \(401 > 400 characters\)"):
        parse_number("1" * 401, SERVER)
    assert parse_number("1e1000", SERVER) == fmpz(10) ** 1000
    with pytest.raises(LimitExceeded, match=r"\|e\| <= 1000 after 'e'"):
        parse_number("1e1001", SERVER)
    with pytest.raises(LimitExceeded, match=r"\|e\| <= 1000 after 'e'"):
        parse_number("1e-1001", SERVER)


def test_exponent_limit_message_states_the_real_limit():
    """The limit named is the one applied: |e| <= N accepted, N + 1 refused (also with a fraction)."""
    n = LIBRARY.decimal_exponent
    assert to_fmpq(f"1.5e{n}") == fmpq(15, 10) * fmpz(10) ** n
    with pytest.raises(ValueError, match=rf"\|e\| <= {n} after 'e'"):
        to_fmpq(f"1.5e{n + 1}")
    t0 = time.perf_counter()
    with pytest.raises(ValueError, match="exponent out of range"):
        to_fmpq("1e" + "9" * 40)
    assert time.perf_counter() - t0 < 1.0


@pytest.mark.parametrize("text", ["\uff11\uff12", "\u0661\u0662", "1\u0660", "\u0967", "1e\uff13", "3/\u0667"])
def test_only_ascii_digits_are_numbers(text):
    with pytest.raises(ValueError, match="not a number"):
        to_fmpq(text)


# --- expressions: sizes checked before the work --------------------------------------------------

@pytest.mark.parametrize(
    "text, fragment",
    [
        ("((((1e1000)^64)^64)^64)^64*t", "constant too large"),
        ("(((1e1000)^64)^64)^64*t", "constant too large"),
        ("(t+1e999)^64*(t+2e999)^64/(t+1e999)^63", "constant too large"),
        ("(1e1000)^64", "constant too large"),
        ("(sqrt(2)+1e300*t)^64", "constant too large"),
        ("1/(t^64+1e80*t+3)^4 + 1/(t^64+7e80*t+1)^4", "degree in t too high: 512 (limit 256)"),
        ("((1e1400)^64)^64*t", "|e| <= 1000"),
    ],
)
def test_hostile_expressions_are_refused_at_once(text, fragment):
    t0 = time.perf_counter()
    with pytest.raises(LimitExceeded) as e:
        parse_expression(text, limits=SERVER)
    assert time.perf_counter() - t0 < 1.0
    assert fragment in str(e.value)


def test_limit_message_gives_size_limit_and_position():
    with pytest.raises(LimitExceeded) as e:
        parse_expression("t + (1e1000)^64", limits=SERVER)
    msg = str(e.value)
    assert msg.startswith("constant too large: about 2^")
    assert "limit 20000 bits at position 12: t + (1e1000)^64" in msg
    bits = int(msg.split("(")[1].split(" bits")[0])
    assert bits >= 64 * 3321  # the value is 10^64000: its size bound is at least its size


def test_limits_are_what_refuses():
    """The same text is exact under a larger coefficient limit (so the refusal is the limit's)."""
    text = "(1e100*t + 1e100)^64 / (t + 1)^64"
    with pytest.raises(LimitExceeded, match="constant too large"):
        parse_expression(text, limits=SERVER)
    roomy = Limits(**{**SERVER.__dict__, "coefficient_bits": 100_000})
    f = parse_expression(text, limits=roomy)
    assert f.is_constant() and f.num.p.coeffs() == [fmpq(10) ** 6400]
    assert current() is LIBRARY  # the limits were in force only during the call


def test_library_refuses_a_billion_bit_power():
    with pytest.raises(LimitExceeded, match="limit 1000000 bits"):
        parse_expression("(((1e1400)^64)^64)^64*t")


def test_exponent_and_depth_limits_come_from_the_limits():
    small = Limits(**{**LIBRARY.__dict__, "exponent": 3, "depth": 4})
    assert parse_expression("t^3", limits=small).degree() == 3
    with pytest.raises(LimitExceeded, match=r"exponent 4 too large \(max 3\)"):
        parse_expression("t^4", limits=small)
    with pytest.raises(LimitExceeded, match=r"nested too deeply \(> 4\)"):
        parse_expression("((((((t))))))", limits=small)


def test_operators_check_the_limits_in_force():
    big = RationalFunction.constant(fmpz(2) ** 15_000)
    assert (big * big).bits() > 20_000  # the library allows it
    with using(SERVER), pytest.raises(LimitExceeded, match="constant too large"):
        big * big
    with using(SERVER), pytest.raises(LimitExceeded, match="degree in t too high"):
        RationalFunction.variable() ** 300


# --- sqrt(n) without factoring -----------------------------------------------------------------

def test_sqrt_of_a_semiprime_is_instant_and_exact():
    t0 = time.perf_counter()
    f = parse_expression(f"sqrt({SEMIPRIME_100})*t", limits=SERVER)
    assert time.perf_counter() - t0 < 1.0
    assert f.d == SEMIPRIME_100 and f.num.q.coeffs() == [0, 1]
    g = parse_expression(f"sqrt({4 * SEMIPRIME_100}) - 2*sqrt({SEMIPRIME_100})", limits=SERVER)
    assert g.num.is_zero()


@pytest.mark.parametrize(
    "n, k, d",
    [
        (8, 2, 2),
        (4, 2, 1),
        (3 * (10**30 + 57) ** 2, 10**30 + 57, 3),  # square of a prime beyond trial division
        ((10**20 + 39) ** 2 * (10**30 + 57) ** 2, (10**20 + 39) * (10**30 + 57), 1),
        (12 * SEMIPRIME_100, 2, 3 * SEMIPRIME_100),
    ],
)
def test_squarefree_decomposition(n, k, d):
    assert squarefree_decomposition(n) == (k, d)


def test_partial_decomposition_never_leaves_a_square():
    """k^2 d = n and d is never a perfect square, for products of large primes too."""
    p, q = 10**20 + 39, 10**30 + 57
    for n in (p * q, p**3, p**2 * q**3, 2 * p**2 * q**2, p**5 * q**4):
        k, d = squarefree_decomposition(n, trial_primes=10)
        assert k * k * d == n
        r = fmpz(d).isqrt()
        assert d == 1 or r * r != d


# --- parsed motions travel between processes ------------------------------------------------------

def test_parsed_motion_pickles_with_its_matrix():
    m = motion_from_dict(
        {"shape": {"center": [0, 0], "semi_axes": ["1/2", 1]}, "translation": ["sqrt(2)*t", "1/(t^2+1)"]},
        limits=SERVER,
    )
    M = m.matrix()
    back = pickle.loads(pickle.dumps(m))
    assert back._matrix and back.matrix() == M and back.source == m.source
    t = Fraction(1, 3)
    e = back.matrix()[2][2]
    assert e.value_float(float(t)) == M[2][2].value_float(float(t))


def test_motion_limits_apply_while_building_the_matrix():
    data = {"shape": {"center": [0, 0], "semi_axes": [1, 1]}, "translation": ["1e900*t", "0"]}
    tight = Limits(**{**SERVER.__dict__, "coefficient_bits": 5000})
    with pytest.raises(LimitExceeded, match="limit 5000 bits"):
        motion_from_dict(data, limits=tight)  # 1e900 fits; its square (A's constant term) does not
    assert motion_from_dict(data, limits=SERVER).matrix()[2][2].bits() > 5000


def test_limits_reject_nonsense():
    with pytest.raises(ValueError, match="Limits.coefficient_bits must be a positive integer"):
        Limits(**{**SERVER.__dict__, "coefficient_bits": 0})
