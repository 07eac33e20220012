"""Build the compiled filters (``core.fixed._filter``, ``core.moving._sweep_filter``) and ship ``static/``.

Everything else is declared in pyproject.toml. The kernels are generated C
(``python -m core.fixed.kernelgen`` writes core/fixed/_kernels.h from core/fixed/driver.py)
compiled with the standard setuptools ``Extension``: on x86-64 three variants (baseline, AVX2,
AVX-512) in one build, the module picks the best one this CPU runs when it is imported.

Build switches (environment variables read here):

* ``ELLIPSOID_BUILD_VARIANTS=baseline``: a developer build of the baseline variant alone (about a
  sixth of the compile time); CI and wheels build every variant (the default, ``all``).
* ``ELLIPSOID_BUILD_JOBS=N``: compile the C sources on N processes (default: the CPUs this
  process may use, at most 4); the variants are separate files, so they compile side by side.

Floating-point flags: no contraction into fused multiply-adds and no value-changing
optimisation (-ffp-contract=off, -fno-fast-math), because the proven error bounds count one
rounding per operation as written. -fno-math-errno and -fno-trapping-math change no value;
they let sqrt and the selects vectorise.
"""

import hashlib
import os
import platform
import shutil
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext
from setuptools.command.build_py import build_py

HERE = Path(__file__).resolve().parent

# the extension remembers which generated kernels it was built from: core.fixed.compiled warns
# when core/fixed/_kernels.h changed since (regenerated but not rebuilt)
_HASH = hashlib.sha256(HERE.joinpath("core", "fixed", "_kernels.h").read_bytes()).hexdigest()[:16]

_VARIANTS = os.environ.get("ELLIPSOID_BUILD_VARIANTS", "all").strip().lower()
if _VARIANTS not in ("all", "baseline"):
    sys.exit(f"ELLIPSOID_BUILD_VARIANTS={_VARIANTS!r}: expected 'all' (the default) or 'baseline'")

_X86 = platform.machine().lower() in ("x86_64", "amd64")
_SOURCES = ["core/fixed/_filter_base.c", "core/fixed/_filter.c"]
_MACROS = [("KERNELS_SHA256", f'"{_HASH}"')]
if _X86 and _VARIANTS == "all":
    _SOURCES = ["core/fixed/_filter_avx2.c", "core/fixed/_filter_avx512.c", *_SOURCES]  # longest first
elif _X86:
    _MACROS.append(("BASELINE_ONLY", "1"))  # _filter.c then declares no x86 variants

if sys.platform == "win32":  # MSVC: no per-function target pragmas; the baseline variant only
    _FLAGS = ["/O2", "/fp:precise"]
    _SOURCES = ["core/fixed/_filter.c", "core/fixed/_filter_base.c"]
    _MACROS = [m for m in _MACROS if m[0] != "BASELINE_ONLY"]
else:
    _FLAGS = ["-O3", "-std=c99", "-ffp-contract=off", "-fno-fast-math", "-fno-math-errno", "-fno-trapping-math"]


def _jobs() -> int:
    """Compile processes: ELLIPSOID_BUILD_JOBS, else the usable CPUs (at most 4)."""
    if os.environ.get("ELLIPSOID_BUILD_JOBS", "").strip():
        return max(1, int(os.environ["ELLIPSOID_BUILD_JOBS"]))
    cpus = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
    return max(1, min(4, cpus))


class ParallelBuildExt(build_ext):
    """build_ext that compiles an extension's C files side by side.

    The three filter variants take ~20, ~60 and ~45 s of one core each at -O3; linking is unchanged.
    """

    def build_extension(self, ext: Extension) -> None:
        """Build one extension, its sources compiled on :func:`_jobs` processes."""
        compile_one = self.compiler.compile
        jobs = _jobs()
        if jobs > 1 and len(ext.sources) > 1:

            def compile_all(sources, *args, **kwargs):  # type: ignore[no-untyped-def]
                with ThreadPoolExecutor(jobs) as pool:  # each call runs the compiler as a process
                    parts = list(pool.map(lambda src: compile_one([src], *args, **kwargs), sources))
                return [obj for objs in parts for obj in objs]

            self.compiler.compile = compile_all  # type: ignore[method-assign]
        try:
            super().build_extension(ext)
        finally:
            self.compiler.compile = compile_one  # type: ignore[method-assign]


class BuildPyWithStatic(build_py):
    """build_py that also copies the landing page ``static/`` into the built ``app/static/``.

    A wheel install then serves ``GET /`` (app.api.settings.default_static_dir looks there first);
    editable installs read ``static/`` from the checkout instead.
    """

    def run(self) -> None:
        """Build the packages, then copy ``static/``."""
        super().run()
        source = HERE / "static"
        if source.is_dir():
            target = Path(self.build_lib) / "app" / "static"
            shutil.rmtree(target, ignore_errors=True)
            shutil.copytree(source, target, ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))


setup(
    cmdclass={"build_ext": ParallelBuildExt, "build_py": BuildPyWithStatic},
    ext_modules=[
        Extension(
            "core.fixed._filter",
            sources=_SOURCES,
            depends=["core/fixed/_kernels.h", "core/fixed/_blocks.h", "core/fixed/_variant.h", "core/fixed/_spheres.h", "core/fixed/_near.h"],
            extra_compile_args=_FLAGS,
            define_macros=_MACROS,
            libraries=[] if sys.platform == "win32" else ["m"],
        ),
        # the first-contact filter of moving bodies (its kernel and the module around it, which
        # core/moving/sweep_filter.py calls); the same floating-point flags, for the same reason
        Extension(
            "core.moving._sweep_filter",
            sources=["core/moving/_sweep_filter.c", "core/moving/_sweep_module.c"],
            extra_compile_args=_FLAGS,
            libraries=[] if sys.platform == "win32" else ["m"],
        ),
    ],
)
