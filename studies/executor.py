"""Run independent cases in-process or on a Dask cluster, handing each result over as it arrives.

The caller writes each finished case (atomically) in ``on_result``, so a worker or client
killed mid-run loses no finished case: Dask reschedules a case whose worker died, and a
rerun of the caller computes only the cases that have no file yet.

- ``workers=None, scheduler=None``: in-process, one case after another.
- ``workers=N``: a :class:`distributed.LocalCluster` of ``N`` worker processes (``0``: one
  per core) with one thread each and numba/BLAS/OpenMP threads 1 per worker.
- ``scheduler="tcp://HOST:PORT"``: an existing cluster (dask-jobqueue, Kubernetes, or
  ``dask scheduler`` + ``dask worker``); its workers must be able to import ``studies``
  and read the scene's files.

Examples
--------
>>> got = {}
>>> run_tasks([2, 3], lambda n: n * n, lambda i, r: got.update({i: r}))
>>> got
{0: 4, 1: 9}
"""

from __future__ import annotations

import atexit
import contextlib
import logging
import os
import warnings
from collections.abc import Callable, Sequence
from typing import Any

from springfem.errors import InputError

WORKER_ENV = {
    "NUMBA_NUM_THREADS": "1",
    "OPENBLAS_NUM_THREADS": "1",
    "OMP_NUM_THREADS": "1",
    "MKL_NUM_THREADS": "1",
    "OMP_WAIT_POLICY": "passive",
}
"""Environment of the local worker processes: one thread each (a process per core)."""


def worker_count(workers: int | None, scheduler: str | None) -> int:
    """How many processes run the cases: 1 in-process, ``workers`` (0: one per core) on a
    local cluster, or 0 when an existing cluster (``scheduler``) decides.

    Examples
    --------
    >>> worker_count(None, None), worker_count(3, None)
    (1, 3)
    """
    if scheduler is not None:
        return 0
    if workers is None:
        return 1
    return workers or os.cpu_count() or 1


def run_tasks(
    tasks: Sequence[Any],
    work: Callable[[Any], Any],
    on_result: Callable[[int, Any], None],
    workers: int | None = None,
    scheduler: str | None = None,
    on_error: Callable[[int, BaseException], None] | None = None,
    keys: Sequence[str] | None = None,
) -> None:
    """Call ``on_result(i, work(tasks[i]))`` for every task, in order of completion.

    Parameters
    ----------
    tasks
        Picklable task arguments.
    work
        The function a worker runs (importable by the workers, or picklable by value).
    on_result
        Called in the calling process with the task's index and result.
    workers, scheduler
        Where to run (module docstring); at most one of them.
    on_error
        Called with the index and exception of a task that raised (on a cluster, also one
        whose workers kept dying); default: the exception propagates.
    keys
        Dask task keys (default: generated); names the tasks on the dashboard.
    """
    if workers is not None and scheduler is not None:
        raise InputError("give --workers or --scheduler, not both")
    if not tasks:
        return  # no cluster for nothing to do
    if workers is None and scheduler is None:
        for i, task in enumerate(tasks):
            try:
                res = work(task)
            except Exception as exc:
                if on_error is None:
                    raise
                on_error(i, exc)
                continue
            on_result(i, res)
        return
    from distributed import as_completed

    with _client(workers, scheduler) as client:
        futures = {}
        for i, task in enumerate(tasks):
            kw = {"key": keys[i]} if keys is not None else {}
            futures[client.submit(work, task, pure=False, **kw)] = i
        for fut in as_completed(list(futures)):
            i = futures[fut]
            try:
                res = fut.result()
            except Exception as exc:  # the task raised, or KilledWorker
                if on_error is None:
                    raise
                on_error(i, exc)
                continue
            on_result(i, res)
            fut.release()


#: The local cluster of this process, by its number of workers: started by the first study
#: that asks for it and kept for the next (a report's studies share it), closed at exit.
_LOCAL: dict[int, tuple[Any, Any]] = {}


def close_local_clusters() -> None:
    """Close the local clusters this process started (at exit, or after a test)."""
    while _LOCAL:
        _, (client, cluster) = _LOCAL.popitem()
        with contextlib.suppress(Exception):
            client.close()
            cluster.close()


atexit.register(close_local_clusters)


class _client:
    """A distributed Client on the process's LocalCluster or an existing scheduler (context
    manager; the local cluster stays up for the next study, :data:`_LOCAL`)."""

    def __init__(self, workers: int | None, scheduler: str | None):
        self.workers, self.scheduler, self.cluster, self.client = workers, scheduler, None, None

    def __enter__(self):
        from distributed import Client, LocalCluster

        if self.scheduler is not None:
            try:
                self.client = Client(self.scheduler, timeout="10s")
            except (OSError, TimeoutError) as exc:
                raise InputError(
                    f"cannot reach the Dask scheduler {self.scheduler}: {exc}"
                ) from None
            return self.client
        n = self.workers or os.cpu_count() or 1
        if n < 0:
            raise InputError(f"--workers must be at least 1, got {n}")
        if n in _LOCAL:
            client, _ = _LOCAL[n]
            if client.status == "running":
                return client
            close_local_clusters()
        # the spawned workers (and any respawned after a crash) inherit these too; the
        # caller's own values come back once it is up: numba rereads NUMBA_NUM_THREADS at every
        # compile and raises if it changed after its threads started
        self.saved_env = {k: os.environ.get(k) for k in WORKER_ENV}
        for k, v in WORKER_ENV.items():
            os.environ.setdefault(k, v)
        with warnings.catch_warnings():  # "port 8787 is in use" of a second cluster
            warnings.simplefilter("ignore", UserWarning)
            self.cluster = LocalCluster(
                n_workers=n,
                threads_per_worker=1,
                processes=True,
                env=dict(WORKER_ENV),
                dashboard_address=None,
                silence_logs=logging.ERROR,
            )
        self.client = Client(self.cluster)
        self._restore_env()
        _LOCAL[n] = (self.client, self.cluster)
        return self.client

    def __exit__(self, *exc) -> None:
        if self.scheduler is not None and self.client is not None:
            self.client.close()  # a remote cluster: only our connection

    def _restore_env(self) -> None:
        for k, v in getattr(self, "saved_env", {}).items():
            if v is None:
                os.environ.pop(k, None)
            else:
                os.environ[k] = v
