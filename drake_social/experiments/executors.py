"""Where a study's runs execute: in this process, a process pool, or a Dask cluster.

Every backend maps one function over plain-data tasks (dicts of strings and
numbers: scenario text, overrides, algorithm, seed, ...) and returns the
records in task order, so a study's numbers never depend on the backend or
the number of workers (each task carries its own seed).

* ``"process"`` (:mod:`concurrent.futures`): ``workers == 1`` runs in this
  process; more use a :class:`~concurrent.futures.ProcessPoolExecutor` of
  freshly spawned interpreters (``spawn``: no state inherited from the
  caller's Drake or numba threads).
* ``"dask"`` (the ``distributed`` package): the tasks go to the scheduler at
  ``scheduler`` (e.g. ``tcp://10.0.0.5:8786``), or to a
  :class:`distributed.LocalCluster` of ``workers`` single-threaded worker
  processes started for the study and closed after it.
"""

from __future__ import annotations

import logging
import multiprocessing
import signal
from concurrent.futures import ProcessPoolExecutor, as_completed
from typing import Callable, Sequence

__all__ = ["EXECUTORS", "map_tasks"]

#: Backends of :func:`map_tasks`.
EXECUTORS = ("process", "dask")

_log = logging.getLogger(__name__)


def map_tasks(
    fn: Callable[[dict], dict],
    tasks: Sequence[dict],
    *,
    executor: str = "process",
    workers: int = 1,
    scheduler: str | None = None,
    progress: Callable[[int, int, dict], None] | None = None,
) -> list[dict]:
    """``[fn(t) for t in tasks]``, in task order, on the chosen backend.

    Args:
        fn: a module-level function (workers import it by name).
        tasks: plain-data task dicts.
        executor: one of :data:`EXECUTORS`.
        workers: processes (``"process"``) or LocalCluster workers (``"dask"``
            without ``scheduler``); >= 1.
        scheduler: address of a running Dask scheduler (``"dask"`` only).
        progress: ``progress(done, total, record)`` after each finished task
            (in completion order).

    Raises:
        ValueError: an unknown executor, workers < 1, or a scheduler address
            for the process pool.
    """
    if executor not in EXECUTORS:
        raise ValueError(f"unknown executor {executor!r}; allowed: {', '.join(EXECUTORS)}")
    if workers < 1:
        raise ValueError(f"workers must be >= 1, got {workers}")
    if scheduler is not None and executor != "dask":
        raise ValueError("a scheduler address needs executor 'dask'")
    total = len(tasks)
    results: list[dict | None] = [None] * total

    def done(k: int, record: dict, count: int) -> None:
        results[k] = record
        if progress is not None:
            progress(count, total, record)

    if executor == "dask":
        _map_dask(fn, tasks, workers, scheduler, done)
    elif workers == 1 or total <= 1:
        for k, task in enumerate(tasks):
            done(k, fn(task), k + 1)
    else:
        context = multiprocessing.get_context("spawn")
        # Workers ignore SIGINT: Ctrl-C reaches the main process only, which
        # then cancels what has not started and stops the workers at once
        # (a pool's own shutdown would wait for every queued task).
        pool = ProcessPoolExecutor(max_workers=min(workers, total), mp_context=context,
                                   initializer=_ignore_sigint)
        try:
            futures = {pool.submit(fn, task): k for k, task in enumerate(tasks)}
            for count, future in enumerate(as_completed(futures), start=1):
                done(futures[future], future.result(), count)
        except BaseException:
            for process in list(getattr(pool, "_processes", {}).values()):
                process.terminate()
            pool.shutdown(wait=False, cancel_futures=True)
            raise
        pool.shutdown(wait=True)
    return results  # type: ignore[return-value]


def _ignore_sigint() -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def _map_dask(fn, tasks, workers: int, scheduler: str | None, done) -> None:
    try:
        from distributed import Client, LocalCluster, as_completed as dask_completed
    except ImportError as e:  # pragma: no cover - the bench extra installs it
        raise RuntimeError("--executor dask needs the 'distributed' package (pip install 'drake-social[bench]')") from e
    cluster = None
    if scheduler is None:
        cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None)
        _log.info("started a Dask LocalCluster of %d workers at %s", workers, cluster.scheduler_address)
    client = Client(cluster if cluster is not None else scheduler)
    try:
        futures = client.map(fn, list(tasks), pure=False)
        index = {f.key: k for k, f in enumerate(futures)}
        for count, future in enumerate(dask_completed(futures), start=1):
            done(index[future.key], future.result(), count)
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
