"""Two fixed shapes: the certified classifier (Sections 3.1-3.3 and 4.1-4.3 of the paper).

* :mod:`.classify`: ``classify`` / ``classify_detailed``, float filter first, exact where it abstains.
* :mod:`.explain`: the numbers behind one decision (``explain``, ``explain_float``).
* :mod:`.driver`: the float filter's steps, written once (prepare, tree, s0, certificates);
  :mod:`.filters` runs them with numpy, :mod:`.compiled` calls the C extension built from them
  (``_kernels.h`` generated, ``_blocks.h`` / ``_variant.h`` / ``_filter*.c`` hand-written,
  compiled by ``setup.py`` when the package is installed).
* :mod:`.exact`: rational arithmetic (python-flint) that always decides.
* :mod:`.errorbound` and :mod:`.kernelgen`: the error-bound proofs and the generator of the
  kernels (``_kernels.py``, ``_kernels.h``: run ``python -m core.fixed.kernelgen`` after a change,
  then ``pip install -e .``); :mod:`.lanes` reads one lane program as numpy or as C.
"""
