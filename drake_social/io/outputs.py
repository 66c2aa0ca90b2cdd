"""Output sets that never mix runs: staged, locked, and swapped in by one rename.

A command writes its files through an :class:`OutputSet`::

    with OutputSet(out_dir, command="simulate") as outputs:
        outputs.write_text("sim.json", text)
        fig.savefig(outputs.path("tracking.png"))   # any writer, into the staging folder
    # here every file is in out_dir, or (on an exception, Ctrl-C) none of them changed

The layout of one command's set (here ``plan``) in ``out_dir``::

    .plan.gen-<id>/                  the files of the set, and .manifest (their names)
    .plan.current -> .plan.gen-<id>  the set's generation: the one thing a commit swaps
    path.csv -> .plan.current/path.csv         one link per file of the set
    .plan.manifest -> .plan.current/.manifest
    .plan.lock

* Files are written into a private staging folder inside ``out_dir``
  (``.staging-<command>-<pid>-<random>``), which becomes the next generation.
  The commit makes a link ``<name> -> .<command>.current/<name>`` for every
  new name, then replaces the ``.<command>.current`` link by one
  ``os.replace``: every file of the set changes at that instant, and since
  every visible name reads through ``.<command>.current``, the folder shows
  either the whole old set or the whole new one at any moment, also when the
  process is killed (SIGKILL, power loss: the files and folders are fsynced
  before the swap) between any two steps. A link whose file the current
  generation does not have reads as a missing file, never as another run's.
  After the swap the links of names the new set does not have and the old
  generation are removed; a run killed before that leaves them to the next
  run of the command, which removes them first.
* :func:`current_set` tells a reader which generation ``out_dir`` holds and
  its files.
* A folder written before generations existed (plain files listed in a plain
  ``.<command>.manifest``) is first taken over as a generation of its own,
  hard links to the same files, so the swap is atomic from the first run on.
* The commit happens with SIGINT and SIGTERM deferred (Python-level handlers
  that only note the signal, re-raised once it is done: blocking the signal
  in the main thread would not do, since Drake's and numba's threads may
  receive it). A Ctrl-C that arrives during it raises
  :class:`InterruptedAfterCommit` (a ``KeyboardInterrupt``) after it, so the
  caller can say the set was written.
* Committed files and generation folders get the permissions of a plainly
  created file or folder (``0o666 & ~umask``, ``0o777 & ~umask``): the staging
  folder is private (``mkdtemp``: 0700) and writers using ``tempfile`` create
  0600 files.
* A second run writing the same command's set into the same folder at the
  same time is refused (:class:`OutputBusyError`) through an advisory lock
  (``fcntl.flock`` on ``.<command>.lock``, released by the kernel when the
  process dies, so a crashed run never leaves a stale lock).

Different commands (``show`` and ``plan``) keep their own sets in one folder;
a name written by two commands belongs to the one that wrote it last.

On a file system without symbolic links (FAT, some network shares) the set
is moved into place file by file, each file by an atomic rename, with the
plain manifest last; there a process killed in those milliseconds can leave
part of the new set beside part of the old one, and a warning says so.
"""

from __future__ import annotations

import dataclasses as dc
import errno
import fcntl
import logging
import os
import secrets
import shutil
import signal
import tempfile
from collections.abc import Iterable
from pathlib import Path

from drake_social.interrupts import DeferredSignals  # held back while a set is moved into place (re-exported)

__all__ = ["CommittedSet", "DeferredSignals", "InterruptedAfterCommit", "OutputBusyError", "OutputInTheWayError",
           "OutputSet", "check_out_folder", "current_set"]

_log = logging.getLogger(__name__)

#: The generation's list of its files (inside the generation folder).
_MANIFEST = ".manifest"


class OutputBusyError(OSError):
    """Another run is writing the same output set."""

    def __str__(self) -> str:  # the sentence, without OSError's "[Errno 16]"
        return str(self.strerror)


class OutputInTheWayError(IsADirectoryError):
    """A folder (or another entry a file cannot replace) has the name of one
    of the set's files."""

    def __str__(self) -> str:  # the sentence, without OSError's "[Errno 21]"
        return str(self.strerror)


class InterruptedAfterCommit(KeyboardInterrupt):
    """Ctrl-C arrived while the set was moved into place: the set is complete.

    Attributes:
        committed: the files of the set, in their final place.
    """

    def __init__(self, committed: list[Path]):
        super().__init__(f"interrupted after writing {len(committed)} files")
        self.committed = committed


@dc.dataclass(frozen=True)
class CommittedSet:
    """The set of one command that a folder holds.

    Attributes:
        generation: the generation folder's name (``.<command>.gen-<id>``),
            different for every commit.
        files: the set's file names, each readable as ``out_dir / name``.
    """

    generation: str
    files: tuple[str, ...]


def current_set(out_dir: str | os.PathLike, command: str) -> CommittedSet | None:
    """The set of ``command`` in ``out_dir`` (None: no set committed).

    Reads the ``.<command>.current`` link once, so the answer is one
    generation even while another run commits. A set of plain files (written
    where there are no symbolic links, or a folder copied with ``cp -rL``,
    where ``.<command>.current`` is a plain folder) is the files of the plain
    ``.<command>.manifest`` that are there, with ``generation`` empty.
    """
    out = Path(out_dir)
    current = out / f".{command}.current"
    try:
        generation = os.readlink(current)
    except FileNotFoundError:
        generation = None
    except OSError as e:
        if e.errno != errno.EINVAL:  # EINVAL: there, but not a link
            raise
        generation = None
    if generation is None:
        names = _plain_set(out, command)
        return CommittedSet("", tuple(names)) if names is not None else None
    try:
        names = (out / generation / _MANIFEST).read_text().splitlines()
    except FileNotFoundError:
        return None
    return CommittedSet(generation, tuple(n for n in names if n))


def _plain_set(out: Path, command: str) -> list[str] | None:
    """The files of a set of plain files: the names in a plain (not linked)
    ``.<command>.manifest`` that are in ``out`` as plain files (or as the
    set's links, left by an earlier generation; None: no such manifest)."""
    manifest = out / f".{command}.manifest"
    if manifest.is_symlink() or not manifest.is_file():
        return None

    def there(name: str) -> bool:
        entry = out / name
        if entry.is_symlink():
            return os.readlink(entry) == f".{command}.current/{name}" and entry.is_file()
        return entry.is_file()

    return [n for n in manifest.read_text().splitlines()
            if n and Path(n).name == n and not n.startswith(".") and there(n)]


def _remove(entry: Path) -> None:
    """Removes a file, link or folder tree (errors ignored: the next run retries)."""
    if entry.is_dir() and not entry.is_symlink():
        shutil.rmtree(entry, ignore_errors=True)
    else:
        try:
            entry.unlink()
        except OSError:
            pass


def _umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def _fsync(path: Path) -> None:
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


class OutputSet:
    """A set of files of one command, written together into ``out_dir``.

    Args:
        out_dir: the output folder (created when missing).
        command: the set's name (e.g. ``"plan"``); sets of different names
            in one folder are independent.
        names: the file names the set may hold, when known up front: a
            folder of such a name in ``out_dir`` is refused on entering the
            block (:class:`OutputInTheWayError`), before any work. The
            commit checks the names actually written the same way.
    """

    def __init__(self, out_dir: str | os.PathLike, command: str, names: Iterable[str] = ()):
        self.out_dir = Path(out_dir)
        self.command = command
        self.names = tuple(names)
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
            # We hold the lock: what a killed run of this command left is removed.
            self._tidy()
            self.check_names([*self.names, self._manifest.name])
            self._staging = Path(tempfile.mkdtemp(prefix=f".staging-{self.command}-{os.getpid()}-",
                                                  dir=self.out_dir))
        except BaseException:
            self._release()
            raise
        return self

    def __exit__(self, exc_type, exc, tb) -> bool:
        with DeferredSignals() as deferred:
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

    def check_names(self, names: Iterable[str]) -> None:
        """Refuses names of the set that ``out_dir`` holds as a folder (not
        ours to replace, and a rename cannot put a file there).

        Raises:
            OutputInTheWayError: ``<out_dir>/<name> is a folder in the way of
                <command>'s output ...``.
        """
        for name in names:
            entry = self.out_dir / name
            if entry.is_dir() and not entry.is_symlink():
                raise OutputInTheWayError(
                    errno.EISDIR, f"{entry} is a folder in the way of {self.command}'s output {name}; remove or "
                    "rename it, or choose another --out", str(entry))

    # ---- the folder's layout --------------------------------------------------

    @property
    def _current(self) -> Path:
        return self.out_dir / f".{self.command}.current"

    @property
    def _manifest(self) -> Path:
        return self.out_dir / f".{self.command}.manifest"

    def _link_target(self, name: str) -> str:
        member = _MANIFEST if name == self._manifest.name else name
        return f".{self.command}.current/{member}"

    def _ours(self, entry: Path) -> bool:
        """Whether ``entry`` is a link of this command's set."""
        try:
            return os.readlink(entry) == self._link_target(entry.name)
        except OSError:  # not a link, or gone
            return False

    def _swap(self, link: Path, target: str) -> None:
        """Makes ``link`` a symbolic link to ``target`` by one rename."""
        tmp = self.out_dir / f".{self.command}.new-{secrets.token_hex(6)}"
        os.symlink(target, tmp)
        try:
            os.replace(tmp, link)
        except OSError as e:  # named by the user's path, not the temporary link's
            tmp.unlink(missing_ok=True)
            raise type(e)(e.errno, e.strerror, str(link)) from None
        except BaseException:
            tmp.unlink(missing_ok=True)
            raise

    def _link_all(self, names) -> None:
        """Links ``<name> -> .<command>.current/<name>`` for every name that is not linked yet."""
        for name in names:
            if not self._ours(self.out_dir / name):
                self._swap(self.out_dir / name, self._link_target(name))

    def _seal(self, generation: Path, names: list[str]) -> None:
        """Writes the generation's manifest, sets normal permissions and
        flushes it to disk (the swap must never point at lost data)."""
        mode = 0o666 & ~_umask()
        for name in names:
            os.chmod(generation / name, mode)
            _fsync(generation / name)
        manifest = generation / _MANIFEST
        manifest.write_text("".join(f"{n}\n" for n in names))
        os.chmod(manifest, mode)
        _fsync(manifest)
        os.chmod(generation, 0o777 & ~_umask())
        _fsync(generation)

    # ---- commit ---------------------------------------------------------------

    def _commit(self) -> None:
        entries = list(self._staging.iterdir())
        odd = [p.name for p in entries if not p.is_file() or p.is_symlink() or p.name.startswith(".")]
        if odd:  # never drop a writer's output silently
            raise RuntimeError(f"output set {self.command!r}: staged entries that are not plain files: {odd}")
        staged = sorted(p.name for p in entries)
        self.check_names(staged)
        if not self._links_work():
            self._commit_file_by_file(staged)
            return
        self._adopt_plain_set()
        self._seal(self._staging, staged)
        generation = self.out_dir / f".{self.command}.gen-{secrets.token_hex(6)}"
        os.rename(self._staging, generation)
        self._staging = None
        try:
            # Links of new names dangle until the swap (the old generation
            # lacks them): to a reader, those files do not exist yet.
            self._link_all([*staged, self._manifest.name])
            self._swap(self._current, generation.name)  # the commit: one atomic rename
        except BaseException:
            self._tidy_quietly()  # the new generation and its dangling links
            raise
        self.committed = [self.out_dir / n for n in staged]
        _fsync(self.out_dir)
        self._tidy_quietly()

    def _links_work(self) -> bool:
        """Whether the file system of ``out_dir`` has symbolic links (FAT and
        some network shares have none)."""
        probe = self.out_dir / f".{self.command}.new-{secrets.token_hex(6)}"
        try:
            os.symlink(".", probe)
        except OSError as e:
            if e.errno in (errno.EPERM, errno.ENOTSUP, errno.EOPNOTSUPP, errno.ENOSYS):
                return False
            raise
        probe.unlink()
        return True

    def _commit_file_by_file(self, staged: list[str]) -> None:
        """The commit without symbolic links: each file moved into place by
        its own rename, the files of the previous set that the new one does
        not have removed, the plain manifest last."""
        _log.warning("%s has no symbolic links: the %s set is moved into place file by file, so a process "
                     "killed in those milliseconds can leave a mix of two sets", self.out_dir, self.command)
        try:
            previous = set(self._manifest.read_text().splitlines())
        except FileNotFoundError:
            previous = set()
        self._seal(self._staging, staged)
        for name in staged:
            os.replace(self._staging / name, self.out_dir / name)
        for name in sorted(previous - set(staged)):
            if name and Path(name).name == name and not name.startswith("."):
                (self.out_dir / name).unlink(missing_ok=True)
        os.replace(self._staging / _MANIFEST, self._manifest)
        self.committed = [self.out_dir / n for n in staged]

    def _tidy_quietly(self) -> None:
        try:
            self._tidy()
        except OSError as e:  # the next run of the command removes the rest
            _log.warning("%s: could not remove the previous %s set's leftovers: %s", self.out_dir, self.command, e)

    def _adopt_plain_set(self) -> None:
        """Turns a set of plain files listed in a plain ``.<command>.manifest``
        (written where there were no symbolic links, or a folder copied with
        ``cp -rL``) into a generation, hard links to the same files, so that
        every file reads the same at every step. A ``.<command>.current``
        that is not a link (the copy's plain folder) is moved aside for the
        generation's link and removed with the other leftovers."""
        names = _plain_set(self.out_dir, self.command)
        if names is None and (self._current.is_symlink() or not os.path.lexists(self._current)):
            return
        generation = Path(tempfile.mkdtemp(prefix=f".{self.command}.gen-", dir=self.out_dir))
        for name in names or []:
            source = os.path.realpath(self.out_dir / name)
            try:
                os.link(source, generation / name)
            except OSError:  # a file system without hard links
                shutil.copy2(source, generation / name)
        self._seal(generation, names or [])
        if os.path.lexists(self._current) and not self._current.is_symlink():
            # Every visible name of such a set is a plain file: moving the
            # plain .current aside changes no file a reader sees.
            os.rename(self._current, self.out_dir / f".{self.command}.gen-{secrets.token_hex(6)}")
        self._swap(self._current, generation.name)
        self._link_all([*(names or []), self._manifest.name])
        _fsync(self.out_dir)

    def _tidy(self) -> None:
        """Removes what is not part of the current set: staging folders,
        unfinished links, other generations, and links of names the current
        generation does not have."""
        prefix = f".{self.command}."
        current = os.readlink(self._current) if self._current.is_symlink() else None
        shown = current_set(self.out_dir, self.command)
        have = set(shown.files) if shown is not None else set()
        for entry in self.out_dir.iterdir():
            name = entry.name
            if name.startswith(f".staging-{self.command}-") or (
                    name.startswith(prefix + "gen-") and name != current):
                _remove(entry)
            elif name.startswith(prefix + "new-"):
                entry.unlink(missing_ok=True)
            elif not name.startswith(".") and name not in have and self._ours(entry):
                entry.unlink(missing_ok=True)


def check_out_folder(out: str | os.PathLike, option: str = "--out") -> None:
    """Refuses an output folder that is not a folder, nor could become one:
    it, or the nearest of its parents that exists, must be a directory.

    Args:
        out: the output folder.
        option: the command-line option that named it, for the message.

    Raises:
        NotADirectoryError: ``<out>: --out must be a folder ...`` naming what
            is in the way (an output that cannot be written).
    """
    import stat

    from drake_social.io.textfile import describe_mode, shorten

    out = Path(out)
    here = out
    while True:
        try:
            mode = os.stat(here).st_mode
        except (FileNotFoundError, NotADirectoryError):
            if os.path.islink(here):  # a link to nothing: mkdir cannot make the folder there
                where = "it is" if here == out else f"{here} is"
                raise NotADirectoryError(
                    f"{shorten(str(out), 300)}: {option} must be a folder (its outputs are written inside it); "
                    f"{where} a symbolic link to {shorten(os.readlink(here), 300)}, which does not exist") from None
            if here == here.parent:
                return
            here = here.parent
            continue
        except (OSError, ValueError) as e:
            raise NotADirectoryError(f"{shorten(str(out), 300)}: {option} cannot be used "
                                     f"({getattr(e, 'strerror', None) or e})") from None
        if stat.S_ISDIR(mode):
            return
        what = "a file" if stat.S_ISREG(mode) else describe_mode(mode)
        where = "it is" if here == out else f"{here} is"
        raise NotADirectoryError(f"{shorten(str(out), 300)}: {option} must be a folder (its outputs are written "
                                 f"inside it); {where} {what}")


#: Holds back SIGINT and SIGTERM over a ``with`` block (main thread only):
#: ``.received`` lists the signals that arrived, ``.reraise()`` delivers them.
#: For work that a Ctrl-C must not cut short, such as writing the records
#: that an interrupted command still commits.
