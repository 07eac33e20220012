"""One shape and the numbers it is made of: conventions, exact reading of user input, size limits.

* :mod:`.quadrics`: ellipses and ellipsoids as homogeneous quadric matrices (THE conventions),
  validation, centre / semi-axes / orientation <-> matrix.
* :mod:`.numbers`: every user number read exactly (floats of any width, strings, Fractions).
* :mod:`.limits`: the sizes user text may reach (library defaults, the server's own).
"""
