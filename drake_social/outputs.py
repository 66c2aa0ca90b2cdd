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
* The move happens with SIGINT held back, so Ctrl-C cannot split it; files
  of this command's *previous* set that the new one does not have (listed in
  ``.<command>.manifest``) are removed in the same step, so the folder never
  holds a new ``path.csv`` beside an old ``path.png``.
* A second run writing the same command's set into the same folder at the
  same time is refused (:class:`OutputBusyError`) through an advisory lock
  (``fcntl.flock`` on ``.<command>.lock``, released by the kernel when the
  process dies, so a crashed run never leaves a stale lock).

Different commands (``show`` and ``plan``) keep their own sets in one folder.
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

__all__ = ["OutputBusyError", "OutputSet"]


class OutputBusyError(OSError):
    """Another run is writing the same output set."""


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
        self._staging = Path(tempfile.mkdtemp(prefix=f".staging-{self.command}-{os.getpid()}-", dir=self.out_dir))
        return self

    def __exit__(self, exc_type, exc, tb) -> bool:
        try:
            if exc_type is None:
                self._commit()
        finally:
            if self._staging is not None:
                shutil.rmtree(self._staging, ignore_errors=True)
                self._staging = None
            if self._lock_fd is not None:
                os.close(self._lock_fd)  # releases the flock
                self._lock_fd = None
        return False

    # ---- writing --------------------------------------------------------------

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
        staged = sorted(p.name for p in self._staging.iterdir() if p.is_file())
        try:
            previous = set(self._manifest().read_text().split())
        except FileNotFoundError:
            previous = set()
        manifest_tmp = self._staging / ".manifest"
        manifest_tmp.write_text("".join(f"{n}\n" for n in staged))
        held = threading.current_thread() is threading.main_thread()
        if held:
            old = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT, signal.SIGTERM})
        try:
            for name in staged:
                os.replace(self._staging / name, self.out_dir / name)
            for name in sorted(previous - set(staged)):
                try:
                    (self.out_dir / name).unlink()
                except FileNotFoundError:
                    pass
            os.replace(manifest_tmp, self._manifest())
        finally:
            if held:
                signal.pthread_sigmask(signal.SIG_SETMASK, old)
        self.committed = [self.out_dir / n for n in staged]
