"""Where a study's runs execute: in this process, a process pool, or a Dask cluster.

Every backend maps one function over plain-data tasks (dicts of strings and
numbers: scenario text, overrides, algorithm, seed, ...) and returns the
records in task order, so a study's numbers never depend on the backend or
the number of workers (each task carries its own seed).

* ``"process"`` (:mod:`concurrent.futures`): ``workers == 1`` runs in this
  process; more use a :class:`~concurrent.futures.ProcessPoolExecutor` of
  worker processes forked by multiprocessing's fork server (a fresh
  interpreter: no state inherited from the caller's Drake or numba threads).
* ``"dask"`` (the ``distributed`` package): the tasks go to the scheduler at
  ``scheduler`` (``[tcp://|tls://]HOST:PORT``, e.g. ``tcp://10.0.0.5:8786``,
  checked by :func:`check_scheduler_address` before anything starts), or to a
  :class:`distributed.LocalCluster` of ``workers`` single-threaded worker
  processes (forked by the same fork server) started for the study and closed
  after it; the connections an interruption cuts short are closed without
  logging.

Ctrl-C is the main process's alone: a terminal sends it to every process of
its group, and a worker stopped by it prints a traceback. The fork server is
started with SIGINT ignored, so every worker forked from it ignores SIGINT
from its first instruction (a handler set in the worker would leave the
moment of its start-up uncovered); the main process then stops them.
"""

from __future__ import annotations

import contextlib
import logging
import multiprocessing
import re
import signal
import threading
from concurrent.futures import ProcessPoolExecutor, as_completed
from typing import Callable, Iterator, Sequence

from drake_social.limits import EXECUTORS  # the backends of map_tasks
from drake_social.io.outputs import DeferredSignals  # SIGINT and SIGTERM held back over a block

__all__ = ["EXECUTORS", "SCHEDULER_SCHEMES", "check_scheduler_address", "map_tasks"]

#: Protocols of a Dask scheduler address (the plain TCP of ``dask scheduler``, and TLS).
SCHEDULER_SCHEMES = ("tcp", "tls")

_log = logging.getLogger(__name__)

#: HOST (a name, an IPv4 address or a bracketed IPv6 address) and PORT.
#: Names may hold '_' (docker-compose service names such as dask_scheduler resolve).
_HOST_PORT = re.compile(r"(\[[0-9A-Fa-f:.]+\]|[A-Za-z0-9_](?:[A-Za-z0-9._-]*[A-Za-z0-9_])?):([0-9]+)")
#: Dask's settings a tls:// client needs (its CA and its certificate), as
#: (Security attribute, Dask config key).
_TLS_SETTINGS = (("tls_ca_file", "distributed.comm.tls.ca-file"),
                 ("tls_client_cert", "distributed.comm.tls.client.cert"))


def check_scheduler_address(address: str) -> str:
    """Checks the address of a running Dask scheduler; returns it unchanged.

    The form is ``[tcp://|tls://]HOST:PORT`` with PORT in 1..65535, e.g.
    ``tcp://10.0.0.5:8786``, ``localhost:8786``, ``dask_scheduler:8786`` or
    ``tls://[::1]:8786``; ``tls://`` only with Dask's TLS settings
    (``distributed.comm.tls.ca-file`` and ``distributed.comm.tls.client.cert``).

    Raises:
        ValueError: the address has another form; the message states the
            allowed one.
    """
    form = (f"the form is [{'|'.join(s + '://' for s in SCHEDULER_SCHEMES)}]HOST:PORT with PORT in 1..65535, "
            "e.g. tcp://10.0.0.5:8786")
    if not isinstance(address, str):
        raise ValueError(f"scheduler address must be a string, got {type(address).__name__}; {form}")
    rest = address
    if "://" in address:
        scheme, rest = address.split("://", 1)
        if scheme not in SCHEDULER_SCHEMES:
            raise ValueError(f"scheduler address {address!r}: unknown protocol {scheme!r}; {form}")
    match = _HOST_PORT.fullmatch(rest)
    if match is None:
        what = "is empty" if not rest else ("has no port" if ":" not in rest.strip("[]") or rest.endswith("]")
                                            else "is not HOST:PORT")
        raise ValueError(f"scheduler address {address!r} {what}; {form}")
    port = int(match.group(2))
    if not 1 <= port <= 65535:
        raise ValueError(f"scheduler address {address!r}: port {port} is out of range; {form}")
    if address.startswith("tls://"):
        missing = _missing_tls_settings()
        if missing:
            raise ValueError(f"scheduler address {address!r}: tls:// needs Dask's TLS settings, and "
                             f"{' and '.join(missing)} {'is' if len(missing) == 1 else 'are'} not set (in the Dask "
                             "config, or as DASK_DISTRIBUTED__COMM__TLS__... variables); or use tcp://")
    return address


def _missing_tls_settings() -> list[str]:
    """The Dask config keys of :data:`_TLS_SETTINGS` that are not set (none
    when distributed is not installed: :func:`map_tasks` says what to install)."""
    try:
        from distributed.security import Security
    except ImportError:
        return []
    security = Security()  # reads the settings only; the files are read on connecting
    return [key for attribute, key in _TLS_SETTINGS if not getattr(security, attribute, None)]


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
        ValueError: an unknown executor, workers < 1, a scheduler address
            for the process pool, or one not of the form of
            :func:`check_scheduler_address`.
    """
    if executor not in EXECUTORS:
        raise ValueError(f"unknown executor {executor!r}; allowed: {', '.join(EXECUTORS)}")
    if workers < 1:
        raise ValueError(f"workers must be >= 1, got {workers}")
    if scheduler is not None and executor != "dask":
        raise ValueError("a scheduler address needs executor 'dask'")
    if scheduler is not None:
        check_scheduler_address(scheduler)
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
        context = _worker_context()
        # Workers ignore SIGINT: Ctrl-C reaches the main process only, which
        # then cancels what has not started and stops the workers at once
        # (a pool's own shutdown would wait for every queued task).
        pool = ProcessPoolExecutor(max_workers=min(workers, total), mp_context=context,
                                   initializer=_ignore_sigint)
        try:
            # Submitting starts the workers: a Ctrl-C waits until every one
            # is registered with the pool, so that all are stopped below.
            with DeferredSignals() as deferred:
                futures = {pool.submit(fn, task): k for k, task in enumerate(tasks)}
            deferred.reraise()
            for count, future in enumerate(as_completed(futures), start=1):
                done(futures[future], future.result(), count)
        except BaseException:
            processes = list(getattr(pool, "_processes", {}).values())
            for process in processes:
                process.terminate()
            for process in processes:  # none outlives the study (nor prints after its last line)
                process.join(10)
            pool.shutdown(wait=False, cancel_futures=True)
            raise
        pool.shutdown(wait=True)
    return results  # type: ignore[return-value]


def _ignore_sigint() -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def _worker_context() -> multiprocessing.context.BaseContext:
    """multiprocessing's ``forkserver`` context, its server running with
    SIGINT ignored (a disposition that forked workers inherit). The server is
    started here when it is not running; only its start-up, a fork and an
    exec, runs with SIGINT ignored in this process."""
    from multiprocessing import forkserver

    context = multiprocessing.get_context("forkserver")
    if threading.current_thread() is threading.main_thread():
        previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
        try:
            forkserver.ensure_running()
        finally:
            signal.signal(signal.SIGINT, previous)
    return context


def _map_dask(fn, tasks, workers: int, scheduler: str | None, done) -> None:
    try:
        import dask
        from distributed import Client, LocalCluster, as_completed as dask_completed
        from distributed.utils import get_mp_context
    except ImportError as e:  # pragma: no cover - the bench extra installs it
        raise RuntimeError("--executor dask needs the 'distributed' package (pip install 'drake-social[bench]')") from e
    held: dict = {}  # what to close
    # The LocalCluster's nannies fork their workers from the fork server too.
    with dask.config.set({"distributed.worker.multiprocessing-method": "forkserver"}):
        try:
            if scheduler is None:
                get_mp_context()  # sets distributed's fork-server preload, before the server starts
                _worker_context()
                # A Ctrl-C waits until the cluster is up (cut short, distributed
                # cannot close it), and then stops it with the study. No
                # dashboard; the scheduler's HTTP server on a free local port
                # (its default, 8787, may be another cluster's). The workers
                # log nothing: a failed task reaches this process as its
                # exception, a lost worker through the nanny, here; what a
                # worker would say is its connections closing under it (an
                # ERROR when a busy worker's heartbeat finds the scheduler
                # gone after a Ctrl-C).
                with DeferredSignals() as deferred:
                    held["cluster"] = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                                                   dashboard_address=None, silence_logs=logging.CRITICAL + 1,
                                                   scheduler_kwargs={"dashboard_address": "127.0.0.1:0"})
                deferred.reraise()
                _log.info("started a Dask LocalCluster of %d workers at %s", workers,
                          held["cluster"].scheduler_address)
            try:
                held["client"] = Client(held.get("cluster", scheduler))
            except (OSError, TypeError, ValueError) as e:  # unreachable, or TLS files Dask cannot use
                raise ConnectionError(f"cannot connect to the Dask scheduler at {scheduler or 'the LocalCluster'}: "
                                      f"{e}") from None
            futures = held["client"].map(fn, list(tasks), pure=False)
            index = {f.key: k for k, f in enumerate(futures)}
            for count, future in enumerate(dask_completed(futures), start=1):
                done(index[future.key], future.result(), count)
        except BaseException:
            with _silenced("distributed"):  # connections cut short: expected, not news
                _close(held)
            raise
        _close(held)


def _close(held: dict) -> None:
    if "client" in held:
        held["client"].close()
    if "cluster" in held:
        held["cluster"].close()


@contextlib.contextmanager
def _silenced(logger: str) -> Iterator[None]:
    """No record of ``logger`` (and its children) is emitted in the block."""
    log = logging.getLogger(logger)
    disabled = log.disabled
    children = [child for name, child in logging.Logger.manager.loggerDict.items()
                if name.startswith(logger + ".") and isinstance(child, logging.Logger) and not child.disabled]
    log.disabled = True
    for child in children:
        child.disabled = True
    try:
        yield
    finally:
        log.disabled = disabled
        for child in children:
            child.disabled = False
