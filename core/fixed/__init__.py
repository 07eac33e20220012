"""Two fixed shapes: the certified classifier (Sections 3.1-3.3 and 4.1-4.3 of the paper).

* :mod:`.classify`: ``classify`` / ``classify_detailed``, float filter first, exact where it abstains.
* :mod:`.explain`: the numbers behind one decision.
* :mod:`.filters` (numpy) and :mod:`.compiled` (C, every core): the float filter with proven bounds.
* :mod:`.exact`: rational arithmetic (python-flint) that always decides.
* :mod:`.errorbound` and :mod:`.kernelgen`: the error-bound proofs and the generator of the
  kernels (``_kernels.py``, ``_kernels.c``: run ``python -m core.fixed.kernelgen`` after a change).
"""
