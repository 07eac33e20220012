"""The paper's formulae, written once for any ring (floats, rationals, polynomials in t).

* :mod:`.pencil`: P(T) = det(T A + B) (Definitions 6 and 18).
* :mod:`.subresultants`: s0, s1, s1,0 (Remarks 11 and 23, Section 4.3's 18-multiplication form).
* :mod:`.decision`: the decision trees of Sections 3.3 and 4.3 on certified signs, and their tables.
"""
