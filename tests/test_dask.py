"""The Dask path: classify on dask arrays (lazy, chunk by chunk) and contacts on a LocalCluster.

One LocalCluster with 2 worker processes (1 thread each) serves the module (~1 s to start).
References: the same computation in numpy on this process (identical results, not just equal
labels: the same pairs, certifiers and counts).
"""

from __future__ import annotations

import numpy as np
import pytest

distributed = pytest.importorskip("distributed")
da = pytest.importorskip("dask.array")

from bench.bodies_data import random_bodies  # noqa: E402
from core import Relation, bodies_from_axes, classify, contacts  # noqa: E402
from core.bodies.distributed import WarmUp  # noqa: E402

pytestmark = pytest.mark.dask


@pytest.fixture(scope="module")
def client():
    import dask

    # a worker that stops answering is restarted after 60 s, not Dask's 5 min (a CI run under load once
    # saw a worker fall silent for 596 s); the search then starts again (test_a_search_outlives_...)
    with dask.config.set({"distributed.scheduler.worker-ttl": "60s"}):
        cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None)
    c = distributed.Client(cluster)
    yield c
    c.close()
    cluster.close()


def _bodies(n, dim=3, seed=1):
    b = random_bodies(n, dim=dim, fraction=0.35, seed=seed)
    return bodies_from_axes(b.centers, b.semi_axes, b.orientations), b.side


def _same(a, b):
    for key in ("i", "j", "relation", "certified_by"):
        assert np.array_equal(getattr(a, key), getattr(b, key)), key
    assert a.counts == b.counts and a.invalid == b.invalid
    assert (a.image is None) == (b.image is None)
    if a.image is not None:
        assert np.array_equal(a.image, b.image)


def test_classify_on_dask_arrays_is_lazy_and_equals_numpy(client):
    Q, _ = _bodies(6000)
    A, B = Q[:3000], Q[3000:]
    B[:40] = A[:40]  # identical shapes overlap; and some exact work: a tangent pair
    B[40] = bodies_from_axes([[0, 0, 0]], [[1, 1, 1]])[0]
    A[40] = bodies_from_axes([[2, 0, 0]], [[1, 1, 1]])[0]
    lazy = classify(da.from_array(A, chunks=(700, 4, 4)), da.from_array(B, chunks=(1000, 4, 4)))
    assert isinstance(lazy, da.Array) and lazy.dtype == np.int8 and lazy.shape == (3000,)
    assert lazy.numblocks == (5,)  # A's chunks of pairs
    got = lazy.compute()
    assert np.array_equal(got, classify(A, B)) and got[40] == Relation.TANGENT
    # a numpy operand broadcasts against a dask one
    assert np.array_equal(classify(da.from_array(A, chunks=1000), B[0]).compute(), classify(A, B[0]))


def test_classify_on_dask_names_the_pair_in_the_whole_batch(client):
    Q, _ = _bodies(3000)
    other, _ = _bodies(3000, seed=7)
    Q[2345] = np.diag([1.0, 1.0, 1.0, 1.0])
    lazy = classify(da.from_array(Q, chunks=(1000, 4, 4)), other)
    with pytest.raises(ValueError, match=r"^pair 2345: A has an empty interior"):
        lazy.compute()
    marked = classify(da.from_array(Q, chunks=(1000, 4, 4)), other, on_invalid="mark").compute()
    assert marked[2345] == Relation.INVALID and (marked >= 0).sum() == 2999


def test_kernels_are_loaded_once_per_worker_by_the_plugin(client):
    """Each worker has the kernels this process has (the same install): loaded, the same variant.

    Was: "no C compiler" passed too, so the test passed with no kernels anywhere."""
    from core.fixed import compiled

    here = compiled.status()
    if compiled.variant() is None:
        pytest.skip(f"this install has no compiled kernels for the workers to load: {here}")
    client.register_plugin(WarmUp())
    status = client.run(lambda: __import__("core.fixed.compiled", fromlist=["status"]).status())
    variant = client.run(lambda: __import__("core.fixed.compiled", fromlist=["variant"]).variant())
    assert len(status) == 2
    assert set(status.values()) == {here} and here.startswith("compiled kernels loaded"), status
    assert len(set(variant.values())) == 1 and set(variant.values()) <= set(compiled.variants()), variant


@pytest.mark.parametrize("periodic", [False, True])
def test_contacts_on_the_cluster_equal_the_local_search(client, periodic):
    Q, side = _bodies(8000, seed=4)
    box = (side, side, side) if periodic else None
    local = contacts(Q, box=box)
    assert len(local) > 1000
    _same(contacts(Q, box=box, scheduler=client, partitions=6), local)
    _same(contacts(da.from_array(Q, chunks=(1500, 4, 4)), box=box, partitions=3), local)  # the active client


def test_contacts_on_the_cluster_2d_invalid_and_exact_lattice(client):
    Q, side = _bodies(3000, dim=2, seed=2)
    Q[17] = np.nan
    with pytest.raises(ValueError, match=r"^body 17 entry \(0,0\): not a finite number"):
        contacts(Q, scheduler=client)
    _same(contacts(Q, scheduler=client, on_invalid="mark"), contacts(Q, on_invalid="mark"))
    c = np.array([[x, y] for x in range(12) for y in range(12)], dtype=float)
    lattice = contacts(bodies_from_axes(c, np.full_like(c, 0.5)), box=(12, 12), scheduler=client, partitions=5)
    assert len(lattice) == 2 * 144 and np.all(lattice.relation == Relation.TANGENT)


def test_contacts_scatter_the_data_once_no_large_graph_warning(client, recwarn):
    """The matrices are scattered, never embedded in a task graph: no "Sending large graph"."""
    import dask

    Q, _ = _bodies(8000, seed=9)  # 1 MB of matrices, ten times the threshold set here
    with dask.config.set({"distributed.admin.large-graph-warning-threshold": "100kB"}):
        got = contacts(Q, scheduler=client, partitions=4)
    assert not [w for w in recwarn if "large graph" in str(w.message)], [str(w.message) for w in recwarn]
    _same(got, contacts(Q))


def test_contacts_on_dask_show_progress_when_asked(client, capsys):
    Q, _ = _bodies(3000, seed=3)
    calls = []
    _same(contacts(Q, scheduler=client, partitions=3, progress=lambda done, total: calls.append((done, total))), contacts(Q))
    assert calls == [(1, 3), (2, 3), (3, 3)]
    contacts(Q, scheduler=client, partitions=3, progress=True)
    err = capsys.readouterr()
    assert "contacts [" in err.err and "100%" in err.err and err.out == ""
    contacts(Q, scheduler="threads", progress=True)  # a local scheduler: dask.diagnostics' bar
    err = capsys.readouterr()
    assert "100%" in err.err and err.out == ""


def test_a_search_outlives_one_lost_worker_and_names_a_second_loss(client, monkeypatch):
    """Workers restarted mid-search lose the scattered data: the search warns and starts again once."""
    from distributed.client import FutureCancelledError

    from core.bodies import distributed as dist

    Q, _ = _bodies(3000, seed=5)
    local = contacts(Q)
    restarts = []

    def restart_once(done, total):
        if not restarts:
            restarts.append(done)
            client.restart()  # every future of the search is cancelled, the scattered block is gone

    with pytest.warns(RuntimeWarning, match="a Dask worker was lost with data of this search; starting it again"):
        _same(contacts(Q, scheduler=client, partitions=3, progress=restart_once), local)
    assert restarts == [1]

    def lost(self, tasks, label, *, final=False):  # a loss in every attempt (a second restart is slow under load)
        raise FutureCancelledError("_partition_task-0", reason="already forgotten")

    with monkeypatch.context() as m:
        m.setattr(dist._Runner, "compute", lost)
        with pytest.warns(RuntimeWarning), pytest.raises(RuntimeError, match=r"^the Dask cluster lost a worker holding this search's data in each of 2 attempt\(s\)"):
            contacts(Q, scheduler=client, partitions=3)
    _same(contacts(Q, scheduler=client, partitions=3), local)  # the cluster serves again


def test_an_unreachable_scheduler_is_a_clear_error():
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    import dask

    Q, _ = _bodies(100)
    with dask.config.set({"ellipsoids.connect-timeout": "1s"}):  # the documented knob; 10 s by default
        with pytest.raises(RuntimeError, match=f"cannot reach the Dask scheduler at tcp://127.0.0.1:{port}"):
            contacts(Q, scheduler=f"tcp://127.0.0.1:{port}")


def test_a_worker_killed_mid_search_leaves_the_search_to_the_survivor():
    """SIGKILL one of two workers as the first partition finishes: the search ends with the local answer.

    Its running tasks are rescheduled on the survivor (``retries=``), and if it held scattered
    blocks the search warns and starts again. A cluster of its own: the module's keeps two workers.
    """
    import os
    import signal
    import warnings

    Q, _ = _bodies(20000, seed=6)
    local = contacts(Q)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0") as cluster, \
            distributed.Client(cluster) as c:
        contacts(Q[:200], scheduler=c)  # the kernels' plugin is registered, the workers warm
        victim = sorted(c.run(os.getpid).values())[0]
        killed = []

        def kill_once(done, total):
            if not killed:
                killed.append(done)
                os.kill(victim, signal.SIGKILL)

        with warnings.catch_warnings():
            warnings.filterwarnings("ignore", "a Dask worker was lost", RuntimeWarning)
            got = contacts(Q, scheduler=c, partitions=6, progress=kill_once)
    assert killed == [1]
    _same(got, local)


def test_a_lost_connection_is_a_lost_worker_and_a_killed_worker_one_clear_error(client, monkeypatch):
    """A worker lost as the plugin is installed or the blocks are scattered (Dask's CommClosedError) is
    survived like a cancelled future; a task that keeps killing its workers is one RuntimeError line."""
    from types import SimpleNamespace

    from distributed.comm.core import CommClosedError
    from distributed.scheduler import KilledWorker

    from core.bodies import distributed as dist

    Q, _ = _bodies(3000, seed=8)
    local = contacts(Q)

    def closed(*args, **kwargs):
        raise CommClosedError("in <TCP (closed) ConnectionPool.register_worker_plugin>: Stream is closed")

    with monkeypatch.context() as m:
        m.setattr(dist, "register", closed)
        _same(contacts(Q, scheduler=client, partitions=3), local)

    blocks, calls = dist._blocks, []

    def scatter_lost_once(Q, client):
        calls.append(1)
        if len(calls) == 1:
            raise CommClosedError("in <TCP (closed) ConnectionPool.scatter>: Stream is closed")
        return blocks(Q, client)

    with monkeypatch.context() as m:
        m.setattr(dist, "_blocks", scatter_lost_once)
        with pytest.warns(RuntimeWarning, match=r"starting it again \(CommClosedError: in <TCP \(closed\) ConnectionPool.scatter>"):
            _same(contacts(Q, scheduler=client, partitions=3), local)
    assert len(calls) == 2

    def killed(self, tasks, label, *, final=False):
        raise KilledWorker("_partition_task-0", SimpleNamespace(address="tcp://127.0.0.1:1234"), 3)

    with monkeypatch.context() as m:
        m.setattr(dist._Runner, "compute", killed)
        with pytest.raises(RuntimeError, match=r"^a task of this search killed the Dask workers that ran it, again and again: ") as e:
            contacts(Q, scheduler=client, partitions=3)
    assert "\n" not in str(e.value) and "'_partition_task-0' on 4 different workers" in str(e.value)
