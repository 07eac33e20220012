"""Build the compiled float filter (``core.fixed._filter``) when the package is installed.

Everything else is declared in pyproject.toml. The kernels are generated C
(``python -m core.fixed.kernelgen`` writes core/fixed/_kernels.h from core/fixed/driver.py)
compiled with the standard setuptools ``Extension``: on x86-64 three variants (baseline, AVX2,
AVX-512) in one build, the module picks the best one this CPU runs when it is imported.

Floating-point flags: no contraction into fused multiply-adds and no value-changing
optimisation (-ffp-contract=off, -fno-fast-math), because the proven error bounds count one
rounding per operation as written. -fno-math-errno and -fno-trapping-math change no value;
they let sqrt and the selects vectorise.
"""

import hashlib
import platform
import sys
from pathlib import Path

from setuptools import Extension, setup

# the extension remembers which generated kernels it was built from: core.fixed.compiled warns
# when core/fixed/_kernels.h changed since (regenerated but not rebuilt)
_HASH = hashlib.sha256(Path(__file__).with_name("core").joinpath("fixed", "_kernels.h").read_bytes()).hexdigest()[:16]

_X86 = platform.machine().lower() in ("x86_64", "amd64")
_SOURCES = ["core/fixed/_filter.c", "core/fixed/_filter_base.c"]
if _X86:
    _SOURCES += ["core/fixed/_filter_avx2.c", "core/fixed/_filter_avx512.c"]

if sys.platform == "win32":  # MSVC: no per-function target pragmas; the baseline variant only
    _FLAGS = ["/O2", "/fp:precise"]
    _SOURCES = ["core/fixed/_filter.c", "core/fixed/_filter_base.c"]
else:
    _FLAGS = ["-O3", "-std=c99", "-ffp-contract=off", "-fno-fast-math", "-fno-math-errno", "-fno-trapping-math"]

setup(
    ext_modules=[
        Extension(
            "core.fixed._filter",
            sources=_SOURCES,
            depends=["core/fixed/_kernels.h", "core/fixed/_blocks.h", "core/fixed/_variant.h"],
            extra_compile_args=_FLAGS,
            define_macros=[("KERNELS_SHA256", f'"{_HASH}"')],
            libraries=[] if sys.platform == "win32" else ["m"],
        ),
        # the first-contact filter of moving bodies (core/moving/sweep_filter.py calls it through
        # ctypes); the same floating-point flags, for the same reason
        Extension(
            "core.moving._sweep_filter",
            sources=["core/moving/_sweep_filter.c", "core/moving/_sweep_module.c"],
            extra_compile_args=_FLAGS,
            libraries=[] if sys.platform == "win32" else ["m"],
        ),
    ]
)
