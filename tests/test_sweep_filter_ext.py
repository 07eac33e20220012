"""The sweep filter as a CPython extension (core.moving._sweep_filter): its argument checks, the GIL
released while it runs, its error allowances checked against traces (core.moving.sweepbounds), and the
one check of every generated file and traced constant (core.generated). Its answers are checked
against exact arithmetic in tests/test_sweep.py and tests/test_first_contact.py."""

from __future__ import annotations

import re
import threading
import types

import numpy as np
import pytest

from bench.sweep_data import random_pairs
from core import generated
from core.moving import _sweep_filter as ext
from core.moving import sweep_filter, sweepbounds
from core.moving.linear import read_linear_motions
from core.witness import detgen

# ------------------------------------------------------------------------ the extension's arguments


def _bodies(M: int, dim: int = 3, seed: int = 3):
    m = random_pairs(M, dim=dim, rotate=True, seed=seed)
    bodies, _ = read_linear_motions(*m.arguments())
    return bodies


def _arguments(M: int = 4, dim: int = 3) -> dict:
    """Valid arguments of sweep_pairs, in order; the outputs hold sentinels."""
    bodies = _bodies(M, dim)
    i = np.arange(0, 2 * M, 2, dtype=np.int64)
    return {
        "d": dim, "bodies": bodies.packed(), "pi": i, "pj": i + 1, "shift": None,
        "status": np.full(M, 9, np.int8), "t_lo": np.full(M, 7.0), "t_hi": np.full(M, 7.0), "iterations": np.full(M, 99, np.int32),
    }


def _call(args: dict) -> None:
    ext.sweep_pairs(*args.values())


def test_the_extension_answers_as_the_driver_and_shares_its_status_codes():
    args = _arguments(30)
    _call(args)
    res = sweep_filter.first_contacts_float(_bodies(30), args["pi"], args["pj"], threads=1)
    assert (args["status"] == res.status).all() and (args["iterations"] == res.iterations).all()
    assert np.array_equal(args["t_lo"], res.t_lo, equal_nan=True) and np.array_equal(args["t_hi"], res.t_hi, equal_nan=True)
    assert set(args["status"].tolist()) <= {ext.NEVER, ext.CONTACT, ext.OVERLAP_AT_START, ext.UNDECIDED}
    assert (ext.NEVER, ext.CONTACT, ext.OVERLAP_AT_START, ext.UNDECIDED) == (
        sweep_filter.NEVER, sweep_filter.CONTACT, sweep_filter.OVERLAP_AT_START, sweep_filter.UNDECIDED)
    assert sweep_filter.available()


def test_any_buffer_serves_not_only_numpy():
    args = _arguments(6, dim=2)
    views = {k: (memoryview(v) if isinstance(v, np.ndarray) else v) for k, v in args.items()}
    views["shift"] = memoryview(np.zeros((6, 2)))
    _call(views)
    want = _arguments(6, dim=2)
    _call(want)
    assert (args["status"] == want["status"]).all() and not (args["status"] == 9).any()


def _bad_cases(M: int = 4):
    """(argument, bad value from the valid arguments, exception, message) for sweep_pairs."""
    ro = np.full(M, 9, np.int8)
    ro.flags.writeable = False
    return [
        ("d", lambda a: 4, ValueError, r"d must be 2 or 3, got 4"),
        ("d", lambda a: "3", TypeError, None),
        ("bodies", lambda a: a["bodies"].astype(np.float32), TypeError, r"bodies must be an array of float64, got float32"),
        ("bodies", lambda a: a["bodies"].tolist(), TypeError, r"bodies must be an array of float64, got list"),
        ("bodies", lambda a: np.ascontiguousarray(a["bodies"][:, :16]), ValueError, r"bodies must have shape \(N, 17\), got \(8, 16\)"),
        ("bodies", lambda a: a["bodies"].ravel(), ValueError, r"bodies must have 2 dimensions, got 1"),
        ("bodies", lambda a: np.asfortranarray(a["bodies"]), ValueError, r"bodies must be C-contiguous"),
        ("pi", lambda a: a["pi"].astype(np.int32), TypeError, r"pi must be an array of int64, got int32"),
        ("pi", lambda a: a["pi"].astype(np.float64), TypeError, r"pi must be an array of int64, got float64"),
        ("pi", lambda a: a["pi"].astype(np.uint64), TypeError, r"pi must be an array of int64, got uint64"),
        ("pi", lambda a: np.array([0, 99, 2, 4], np.int64), ValueError, r"pi\[1\] = 99 is not a row of bodies \(0 to 7\)"),
        ("pj", lambda a: np.array([1, 3, -1, 7], np.int64), ValueError, r"pj\[2\] = -1 is not a row of bodies"),
        ("pj", lambda a: a["pj"][:3].copy(), ValueError, r"pj must hold 4 values \(one per pair\), got 3"),
        ("pj", lambda a: a["pj"].reshape(2, 2), ValueError, r"pj must have 1 dimension, got 2"),
        ("shift", lambda a: np.zeros((M, 2)), ValueError, r"shift must have shape \(4, 3\), got \(4, 2\)"),
        ("shift", lambda a: np.zeros((M, 3), np.int64), TypeError, r"shift must be an array of float64, got int64"),
        ("status", lambda a: np.zeros(M, np.int16), TypeError, r"status must be an array of int8, got int16"),
        ("status", lambda a: ro, ValueError, r"status must be writable"),
        ("status", lambda a: a["pi"].view(np.int8)[:M], ValueError, r"status shares memory with pi"),
        ("t_lo", lambda a: np.zeros(M, np.float32), TypeError, r"t_lo must be an array of float64, got float32"),
        ("t_lo", lambda a: np.zeros(2 * M)[::2], ValueError, r"t_lo must be C-contiguous"),
        ("t_lo", lambda a: bytes(8 * M), TypeError, r"t_lo must be an array of float64, got uint8"),
        ("t_hi", lambda a: a["t_lo"], ValueError, r"t_lo shares memory with t_hi"),
        ("iterations", lambda a: np.zeros(M, np.int64), TypeError, r"iterations must be an array of int32, got int64"),
        ("iterations", lambda a: np.zeros(M + 1, np.int32), ValueError, r"iterations must hold 4 values"),
    ]


@pytest.mark.parametrize("case", range(len(_bad_cases())))
def test_bad_arguments_get_one_clear_error_and_nothing_is_written(case):
    name, bad, error, message = _bad_cases()[case]
    args = _arguments()
    args[name] = bad(args)
    with pytest.raises(error, match=message):
        _call(args)
    for out, sentinel in (("status", 9), ("t_lo", 7.0), ("t_hi", 7.0), ("iterations", 99)):
        if out != name and not (name == "t_hi" and out == "t_lo"):
            assert (np.asarray(args[out]) == sentinel).all(), out


def test_the_driver_refuses_pairs_that_are_not_bodies():
    bodies = _bodies(4)
    with pytest.raises(ValueError, match=r"i and j must hold one body per pair each, got 2 and 3"):
        sweep_filter.first_contacts_float(bodies, np.array([0, 2]), np.array([1, 3, 5]))
    with pytest.raises(ValueError, match=r"pj\[1\] = 8 is not a row of bodies"):
        sweep_filter.first_contacts_float(bodies, np.array([0, 2]), np.array([1, 8]))


def test_a_stale_build_without_sweep_pairs_is_loud(monkeypatch):
    # a module built from the old _sweep_module.c (an empty module, opened with ctypes then)
    monkeypatch.setattr(sweep_filter, "_state", {"lib": None, "status": "not built yet", "tried": False})
    monkeypatch.setattr(sweep_filter.importlib, "import_module", types.ModuleType)
    with pytest.warns(RuntimeWarning, match=r"has no sweep_pairs.*older.*pip install"):
        assert not sweep_filter.available()
    assert "exact arithmetic answers every pair" in sweep_filter.filter_status()


def test_the_kernel_runs_without_the_gil():
    """While a thread is inside sweep_pairs this thread runs Python and sees its outputs written part
    way: impossible if the call held the GIL (no Python would run until it returned)."""
    bodies = _bodies(8000, seed=5)
    i = np.arange(0, 16000, 2, dtype=np.int64)
    seen = False
    for _attempt in range(3):  # a loaded machine may not run this thread before the batch ends
        t_lo = np.full(i.size, 7.0)
        done = threading.Event()

        def work(t_lo=t_lo, done=done):
            try:
                ext.sweep_pairs(3, bodies.packed(), i, i + 1, None, np.zeros(i.size, np.int8), t_lo, np.zeros(i.size), np.zeros(i.size, np.int32))
            finally:
                done.set()  # also when the call raises: the loop below must end

        thread = threading.Thread(target=work)
        thread.start()
        while not done.is_set():
            if t_lo[0] != 7.0 and t_lo[-1] == 7.0:  # begun, not finished
                seen = True
                break
        thread.join()
        assert t_lo[-1] != 7.0
        if seen:
            break
    assert seen


# ------------------------------------------------------------------------ the error allowances


def _c() -> str:
    return sweepbounds.SOURCE.read_text()


def test_every_allowance_covers_what_its_trace_requires():
    assert sweepbounds.problems() == []
    table = {r.name: r for r in sweepbounds.rows()}
    # each primitive is checked; a sum of m products rounds m times (Higham), so its allowance grows with m
    for name in ("ADD_U", "ADD_ETA", "MUL_U", "MUL_ETA", "DIV_U", "INV_SQUARE_U", "TIMES_ETA", "RESCALE_ETA", "LERP_MAG_U",
                 "SPLIT_MAG_U", "DOT_U(20)", "DOT_ETA(20)", "COMBINE_U(5)", "RF", "CERTIFY_STEPS_UP", "BRACKET"):
        assert name in table and table[name].ok, name
    assert table["DOT_U(20)"].required > 19 * table["DOT_U(1)"].required


@pytest.mark.parametrize(
    ("old", "new", "message"),
    [
        ("#define MUL_ETA (5 * ETA)", "#define MUL_ETA (0 * ETA)", r"MUL_ETA = 0\.0 is below .*unsafe"),
        ("#define ADD_U U ", "#define ADD_U (U / 4) ", r"ADD_U = .* is below .*K = 1"),
        ("#define DOT_U(m) ((m) * U)", "#define DOT_U(m) ((m - 1) * U)", r"DOT_U\(1\) = 0\.0 is below"),
        ("#define SPLIT_MAG_U (4 * U)", "#define SPLIT_MAG_U (U)", r"SPLIT_MAG_U = .* is below .*K = 3"),
        ("#define CERTIFY_STEPS_UP 4", "#define CERTIFY_STEPS_UP 3", r"CERTIFY_STEPS_UP = 3\.0 is below 4\.0"),
        ("#define BRACKET 9.5e-10", "#define BRACKET 1e-9", r"BRACKET = 1e-09 is above"),
        ("#define RF (1.0 + 9.313225746154785e-10)", "#define RF (1.0 + 0x1p-40)", r"RF = .* is below"),
        ("+ MUL_U * fabs(z) + MUL_ETA}", "+ U * fabs(z) + MUL_ETA}", r"line \d+ of _sweep_filter.c uses U outside a named allowance"),
        ("#define TIMES_ETA ETA", "#define TIMES_ETA ETA\n#define SPARE_ETA (2 * ETA)", r"SPARE_ETA mentions U or ETA but has no derivation"),
        ("+ TIMES_ETA; }", "+ ETA; }", r"TIMES_ETA is defined but not used"),
        ("#define DIV_ETA ETA\n", "", r"defines no DIV_ETA"),
        ("#define MAXF 20 ", "#define MAXF 60 ", r"C\(\d+, \d+\) computed as .* is not exact"),
    ],
)
def test_an_altered_allowance_fails_the_check(old, new, message):
    text = _c()
    assert text.count(old) >= 1, old
    found = sweepbounds.problems(text.replace(old, new))
    assert any(re.search(message, line) for line in found), found


# ------------------------------------------------------------------------ one check of every generated file


def test_every_generated_file_is_current_and_every_traced_constant_safe(capsys):
    assert generated.main(["--check"]) == 0
    assert "2 generators' files current" in capsys.readouterr().out


def test_the_one_check_names_a_stale_file_and_an_unsafe_constant(tmp_path, monkeypatch):
    stale = tmp_path / "_det_kernels.py"
    stale.write_text(detgen.GENERATED_PATH.read_text().replace("DET2_CONSTANT = ", "DET2_CONSTANT = 0.5 * "))
    monkeypatch.setattr(detgen, "GENERATED_PATH", stale)
    unsafe = tmp_path / "_sweep_filter.c"
    unsafe.write_text(_c().replace("#define MUL_ETA (5 * ETA)", "#define MUL_ETA (0 * ETA)"))
    monkeypatch.setattr(sweepbounds, "SOURCE", unsafe)
    found = generated.stale()
    assert any(line.startswith(f"stale: {stale}: run python -m core.witness.detgen") for line in found), found
    assert any("MUL_ETA = 0.0 is below" in line and "python -m core.moving.sweepbounds" in line for line in found), found
    assert generated.main(["--check"]) == 1
