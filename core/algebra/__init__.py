"""Exact algebra underneath the moving analysis: Q(sqrt d)[t], real roots, real algebraic numbers.

* :mod:`.qsqrt`: polynomials p(t) + q(t) sqrt(d) (Example 30's rotation has sqrt 2 entries).
* :mod:`.realroots`: exact isolation of the real roots in an interval (Descartes' rule).
* :mod:`.algebraic`: real algebraic numbers, exact signs of polynomials at them, decimals, their JSON form.
* :mod:`.polysign`: certified float signs of exact polynomials at a float t (the filter in front
  of exact evaluation).
"""
