"""The worker processes start warm: every job (app.jobs, app.api.jobs, the scene's in app.scene.pair.motion)
runs on what the fork server preloaded, and none of it loads FastAPI.

multiprocessing has one fork server per process, shared by the API's and the scene's pools; a
job that needs a module the fork server did not import pays the import in every child (the API's
witness jobs paid ~0.7 s of CPU per request whenever the scene's pool had started the fork
server first). Each job runs here as a worker child runs it: its arguments pickled by the
server, then unpickled and run in a fresh process that imported only ``JOB_MODULES``.
"""

from __future__ import annotations

import inspect
import os
import pickle
import subprocess
import sys
from pathlib import Path

import pool_jobs
import pytest

import app.api.jobs
import app.jobs
import app.scene.pair.motion
from app.api.contacts_schemas import ContactsIn
from app.api.schemas import PairItem
from app.api.sweep_schemas import SweepIn
from app.api.witness_schemas import ContactScaleIn, WitnessIn
from app.workers import JOB_MODULES, WorkerPool, WorkerTimeout

ROOT = Path(__file__).resolve().parents[1]
PAIR = {"a": {"center": ["3", "0"], "semi_axes": ["1", "2"]}, "b": {"center": [0, 0], "semi_axes": [1, 2]}}
MOVING = [["1", "0", "-t"], ["0", "1", "0"], ["-t", "0", "t^2 - 1"]]  # the unit circle at (t, 0)
STILL = [["1", "0", "0"], ["0", "1", "0"], ["0", "0", "-1"]]

CALLS = {  # each job with arguments as its route builds them (app/api/routes, app/scene/pair/analysis.py)
    "analyse_job": (MOVING, STILL, "0, 3"),
    "read_motion_job": ({},),
    "classify_job": ([PairItem.model_validate(PAIR)], "exact", 30.0, True),
    "explain_job": (PairItem.model_validate(PAIR), 30.0),
    "contact_scale_job": (ContactScaleIn.model_validate({**PAIR, "exact": True}),),
    "separating_plane_job": (WitnessIn.model_validate(PAIR),),
    "contact_point_job": (WitnessIn.model_validate({**PAIR, "b": {"center": [2, 0], "semi_axes": [1, 2]}}),),
    "witness_job": (WitnessIn.model_validate(PAIR),),
    "contacts_job": (ContactsIn.model_validate({"bodies": [[0, 0, 0.5, 0.5, 0], [1, 0, 0.5, 0.5, 0]]}), 30.0, 1000, 1000),
    "sweep_job": (SweepIn.model_validate({"start": [[0, 0, 1, 1, 0], [3, 0, 1, 1, 0]], "end": [[0, 0, 1, 1, 0], [1, 0, 1, 1, 0]],
                                          "exact_times": True}), 30.0, 1000, 1000, 10),
}

JOB_HOMES = (app.jobs, app.api.jobs, app.scene.pair.motion)
"""Where the jobs live: the shared one at the bottom, the API's and the scene's beside their models."""

CHILD = """
import pickle, sys
for m in {modules!r}:
    try:  # as the fork server does
        __import__(m)
    except ImportError:
        pass
assert "fastapi" not in sys.modules and "starlette" not in sys.modules, "the worker side loaded FastAPI"
before = set(sys.modules)
for name, fn, args in pickle.loads(sys.stdin.buffer.read()):
    out = fn(*args)
    assert out is not None, name
print("\\n".join(sorted(set(sys.modules) - before)))
"""


def test_every_job_is_called_here():
    """A new job in app.jobs, app.api.jobs or app.scene.pair.motion must be added to CALLS (so the check below covers it)."""
    names = {n for m in JOB_HOMES for n, f in inspect.getmembers(m, inspect.isfunction)
             if n.endswith("_job") and f.__module__ == m.__name__}
    assert names == set(CALLS)


def test_jobs_import_nothing_the_fork_server_did_not_preload():
    job = {n: getattr(m, n) for m in JOB_HOMES for n in dir(m) if n.endswith("_job")}
    payload = pickle.dumps([(name, job[name], args) for name, args in CALLS.items()])
    r = subprocess.run([sys.executable, "-c", CHILD.format(modules=JOB_MODULES)], input=payload, capture_output=True,
                       cwd=ROOT, timeout=300, check=False)
    assert r.returncode == 0, r.stderr.decode()[-3000:]
    ours = [m for m in r.stdout.decode().split() if m.split(".")[0] in {"app", "core", "fastapi", "pydantic", "starlette", "viser"}]
    assert not ours, f"jobs imported these in their worker, add them to app.workers.JOB_MODULES: {ours}"


def test_jobs_run_under_the_batch_policy():
    """A job does not keep a waking server thread waiting (SCHED_BATCH), and keeps its niceness."""
    pool = WorkerPool(1)
    try:
        policy = pool.run(os.sched_getscheduler, 0, timeout=60)
        nice = pool.run(os.nice, 0, timeout=60)  # os.nice(0) returns the niceness it runs at
    finally:
        pool.shutdown()
    assert (policy, nice) == (os.SCHED_BATCH, os.nice(0))


def test_a_job_slow_to_start_still_says_where_its_budget_stopped_it():
    """A job's own budget counts from when the pool started its clock, as the pool's kill does.

    Was: it counted from when the job began, so a job slow to start (a loaded machine: the fork,
    reading its arguments) was killed at the pool's deadline (plus the grace) before its own
    budget ran out, and the answer said only "exceeded its time budget". Here the start takes
    2 s, the budget 2 s, the grace 1 s: the job's check at 2 s is over its budget (it was 4 s)."""
    pool = WorkerPool(1)
    try:
        with pytest.raises(WorkerTimeout) as stop:
            pool.run(pool_jobs.budget_checks_after_a_slow_start, 2.0, 2.0, timeout=2.0, grace=1.0)
    finally:
        pool.shutdown()
    assert str(stop.value) == "stopped after 0 steps: over the time budget of 2 s per request"
