"""Benchmarks of the certified classifier: static pairs, moving shapes and the scene's server cost.

``python -m bench.report`` runs all three and writes their tables into ``bench/results/*.json``,
rendered as ``bench/REPORT.md`` and the documentation's Benchmarks page (``bench.render``), and
``bench/figures/*.png`` (``--quick`` for a run under a minute). Timings are on one core: the BLAS thread pools are pinned
to one thread here, before numpy is imported, when this package is imported first.
"""

from __future__ import annotations

import os
import sys

if "numpy" not in sys.modules:  # one core: numpy's eigenvalue baseline must not use a thread pool
    for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(_var, "1")
