"""Output sets that never mix runs: staged, locked, and committed as a whole.

A command writes its files through an :class:`OutputSet`::

    with OutputSet(out_dir, command="simulate") as outputs:
        outputs.write_text("sim.json", text)
        fig.savefig(outputs.path("tracking.png"))   # any writer, into the staging folder
    # here every file is in out_dir, or (on an exception, Ctrl-C) none of them changed

* Files are written into a private staging folder inside ``out_dir``
  (``.staging-<command>-<pid>-<random>``) and moved into place by
  ``os.replace`` only when the block ends normally, so a crash or Ctrl-C
  while writing leaves the previous set untouched (and the staging folder
  removed).
* The move happens with SIGINT and SIGTERM deferred (Python-level handlers
  that only note the signal, re-raised once the move is done: blocking the
  signal in the main thread would not do, since Drake's and numba's threads
  may receive it), so Ctrl-C cannot split it; files of this command's
  *previous* set that the new one does not have (listed in
  ``.<command>.manifest``) are removed in the same step, so the folder never
  holds a new ``path.csv`` beside an old ``path.png``. A Ctrl-C that arrives
  during the move raises :class:`InterruptedAfterCommit` (a
  ``KeyboardInterrupt``) after it, so the caller can say the set was written.
* Committed files get the permissions of a plainly created file
  (``0o666 & ~umask``): the staging folder is private (``mkdtemp``: 0700) and
  writers using ``tempfile`` create 0600 files.
* A second run writing the same command's set into the same folder at the
  same time is refused (:class:`OutputBusyError`) through an advisory lock
  (``fcntl.flock`` on ``.<command>.lock``, released by the kernel when the
  process dies, so a crashed run never leaves a stale lock; the staging
  folders a killed run left are removed by the next run of the command).

Different commands (``show`` and ``plan``) keep their own sets in one folder.

What this does not cover: the move is a handful of renames, each atomic, not
one; a process killed by SIGKILL or a power loss in those milliseconds can
leave part of the new set beside part of the old one (the manifest then still
lists the old set).
"""

from __future__ import annotations

import errno
import fcntl
import os
import shutil
import signal
import tempfile
import threading
from pathlib import Path

__all__ = ["InterruptedAfterCommit", "OutputBusyError", "OutputSet"]

#: Signals deferred while a set is moved into place.
_DEFERRED_SIGNALS = (signal.SIGINT, signal.SIGTERM)


class OutputBusyError(OSError):
    """Another run is writing the same output set."""

    def __str__(self) -> str:  # the sentence, without OSError's "[Errno 16]"
        return str(self.strerror)


class InterruptedAfterCommit(KeyboardInterrupt):
    """Ctrl-C arrived while the set was moved into place: the set is complete.

    Attributes:
        committed: the files of the set, in their final place.
    """

    def __init__(self, committed: list[Path]):
        super().__init__(f"interrupted after writing {len(committed)} files")
        self.committed = committed


def _umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


class OutputSet:
    """A set of files of one command, written together into ``out_dir``.

    Args:
        out_dir: the output folder (created when missing).
        command: the set's name (e.g. ``"plan"``); sets of different names
            in one folder are independent.
    """

    def __init__(self, out_dir: str | os.PathLike, command: str):
        self.out_dir = Path(out_dir)
        self.command = command
        self._lock_fd: int | None = None
        self._staging: Path | None = None
        self.committed: list[Path] = []

    # ---- the block ------------------------------------------------------------

    def __enter__(self) -> "OutputSet":
        self.out_dir.mkdir(parents=True, exist_ok=True)
        lock = self.out_dir / f".{self.command}.lock"
        fd = os.open(lock, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as e:
            os.close(fd)
            if e.errno in (errno.EWOULDBLOCK, errno.EAGAIN, errno.EACCES):
                raise OutputBusyError(
                    errno.EBUSY, f"another drake-social {self.command} run is writing into {self.out_dir}; "
                    "wait for it or choose another --out") from None
            raise
        self._lock_fd = fd
        try:
            # We hold the lock: a staging folder of this command is a killed run's.
            for stale in self.out_dir.glob(f".staging-{self.command}-*"):
                shutil.rmtree(stale, ignore_errors=True)
            self._staging = Path(tempfile.mkdtemp(prefix=f".staging-{self.command}-{os.getpid()}-",
                                                  dir=self.out_dir))
        except BaseException:
            self._release()
            raise
        return self

    def __exit__(self, exc_type, exc, tb) -> bool:
        with _Deferred() as deferred:
            try:
                if exc_type is None:
                    self._commit()
            finally:
                self._release()
        if deferred.received:
            if signal.SIGINT in deferred.received and self.committed:
                raise InterruptedAfterCommit(self.committed)
            deferred.reraise()
        return False

    def _release(self) -> None:
        if self._staging is not None:
            shutil.rmtree(self._staging, ignore_errors=True)
            self._staging = None
        if self._lock_fd is not None:
            os.close(self._lock_fd)  # releases the flock
            self._lock_fd = None

    # ---- writing --------------------------------------------------------------

    @property
    def folder(self) -> Path:
        """The staging folder, for writers that take a folder and write
        several files (plain, non-hidden file names only)."""
        if self._staging is None:
            raise RuntimeError("OutputSet.folder outside its 'with' block")
        return self._staging

    def path(self, name: str) -> Path:
        """Where to write file ``name`` of the set (inside the staging folder)."""
        if self._staging is None:
            raise RuntimeError("OutputSet.path() outside its 'with' block")
        if Path(name).name != name or name.startswith("."):
            raise ValueError(f"output name must be a plain file name, got {name!r}")
        return self._staging / name

    def write_text(self, name: str, text: str) -> Path:
        """Writes ``text`` as file ``name`` of the set."""
        p = self.path(name)
        p.write_text(text)
        return p

    # ---- commit ---------------------------------------------------------------

    def _manifest(self) -> Path:
        return self.out_dir / f".{self.command}.manifest"

    def _commit(self) -> None:
        entries = list(self._staging.iterdir())
        odd = [p.name for p in entries if not p.is_file() or p.name.startswith(".")]
        if odd:  # never drop a writer's output silently
            raise RuntimeError(f"output set {self.command!r}: staged entries that are not plain files: {odd}")
        staged = sorted(p.name for p in entries)
        try:
            previous = set(self._manifest().read_text().splitlines())
        except FileNotFoundError:
            previous = set()
        mode = 0o666 & ~_umask()
        for name in staged:
            os.chmod(self._staging / name, mode)
        manifest_tmp = self._staging / ".manifest"
        manifest_tmp.write_text("".join(f"{n}\n" for n in staged))
        os.chmod(manifest_tmp, mode)
        for name in staged:
            os.replace(self._staging / name, self.out_dir / name)
        for name in sorted(previous - set(staged)):
            if name and Path(name).name == name and not name.startswith("."):
                (self.out_dir / name).unlink(missing_ok=True)
        os.replace(manifest_tmp, self._manifest())
        self.committed = [self.out_dir / n for n in staged]


class _Deferred:
    """Holds back SIGINT and SIGTERM over a block (main thread only; elsewhere
    Python runs no signal handler anyway): the signals received are noted and
    :meth:`reraise` delivers them afterwards with the original handlers."""

    def __init__(self):
        self.received: list[int] = []
        self._old: dict[int, object] = {}

    def __enter__(self) -> "_Deferred":
        if threading.current_thread() is threading.main_thread():
            for sig in _DEFERRED_SIGNALS:
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
        for sig in dict.fromkeys(self.received):
            signal.raise_signal(sig)
