"""Two moving shapes: exact events and intervals (Sections 3.4 and 4.4 of the paper).

* :mod:`.expressions`: the safe parser of expressions in t (bounded arithmetic).
* :mod:`.motions`: a moving shape as a matrix of rational functions in t.
* :mod:`.analysis`: ``analyse``, the paper's cases 3.4, 4.4.1, 4.4.2, 4.4.3 as named steps.
* :mod:`.first_contact`: the first time two moving shapes are not separate (the analysis,
  stopped at the first root where the relation changes); for many pairs of bodies in linear
  motion (:mod:`.linear`) after the certified float filter :mod:`.sweep_filter`.
* :mod:`.result`: the typed result (events, intervals, sign table, ``relation_at``); it pickles.
* :mod:`.presets`: the paper's Examples 29-33 and 2D cases.
"""
