"""SIGINT and SIGTERM held back over a block, and delivered after it.

:class:`DeferredSignals` serves two kinds of block:

* a step that must not be cut in half (an output set's commit,
  :mod:`drake_social.io.outputs`; a process pool taking its workers,
  :mod:`drake_social.experiments.study.executors`);
* a call into compiled code whose argument passing runs Python code that
  does not survive an exception: numba's unboxing of a
  ``numpy.random.Generator`` calls ``ctypes.cast`` and reads the result's
  ``value`` without checking it for NULL, so a Ctrl-C whose
  ``KeyboardInterrupt`` is raised inside that call is a segmentation fault
  (:meth:`drake_social.planning.rrt_star.compiled.CompiledRun.run` holds the
  signals over each call of the tree loop).

Python-level handlers that only note the signal stand in for the block;
blocking the signal itself would not do, since Drake's and numba's threads
may receive it. Nothing here imports more than the standard library.
"""

from __future__ import annotations

import signal
import threading

__all__ = ["DEFERRED_SIGNALS", "DeferredSignals"]

#: The signals held back.
DEFERRED_SIGNALS = (signal.SIGINT, signal.SIGTERM)


class DeferredSignals:
    """Holds back SIGINT and SIGTERM over a block (main thread only; elsewhere
    Python runs no signal handler anyway): the signals received are noted and
    :meth:`reraise` delivers them afterwards with the original handlers.

    Example::

        with DeferredSignals() as held:
            state = kernel(rng, state)   # no KeyboardInterrupt inside
        held.reraise()                   # a Ctrl-C of the block is raised here
    """

    def __init__(self):
        self.received: list[int] = []
        self._old: dict[int, object] = {}

    def __enter__(self) -> "DeferredSignals":
        if threading.current_thread() is threading.main_thread():
            for sig in DEFERRED_SIGNALS:
                if signal.getsignal(sig) is not None:  # None: a handler set outside Python, left alone
                    self._old[sig] = signal.signal(sig, self._note)
        return self

    def _note(self, signum, frame) -> None:
        self.received.append(signum)

    def __exit__(self, *exc) -> bool:
        for sig, handler in self._old.items():
            signal.signal(sig, handler)
        return False

    def reraise(self) -> None:
        """Delivers each signal received in the block once, in order, to its own handler."""
        for sig in dict.fromkeys(self.received):
            signal.raise_signal(sig)
