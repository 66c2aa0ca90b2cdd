"""Reading the user's text files (scenarios, sweeps, path CSVs) with one set of guards.

Every file the command line or the library reads on a user's behalf goes
through :func:`read_text_file`, so all of them are refused the same way:

* a path that is not a regular file is named for what it is (a directory, a
  FIFO, a character or block device, a socket), found with ``stat`` before the
  file is opened, so a FIFO is never opened for reading (that would block
  until a writer appears) and ``/dev/zero`` is never read (it never ends);
* a file larger than its limit (:data:`MAX_YAML_FILE_BYTES` for scenario
  and sweep files, :data:`MAX_PATH_FILE_BYTES` for path CSVs) is refused
  with the limit stated, before anything is read;
* the text must be UTF-8; the error names the byte offset at fault.

Errors are :class:`~drake_social.errors.ScenarioError` (invalid input: the
command line prints it and exits 2), naming the file and, when given, the
option that named it (``--path``).

A file may be named by another file (a scenario's ``world.map`` and
``people_file``, a map's ``image``, a sweep's ``scenarios``), so the file
read may be any file the process can read (a password file, a key). The
readers therefore never repeat a file's text until it has shown to be of
its kind (a YAML mapping with one of the schema's keys at its top, a CSV
whose first line names the columns, an image Pillow decodes): before that
an error names the file, the line and what the file is not, and describes
what it found (``a list``, ``text``) without quoting it. :func:`yaml_problem`
is PyYAML's error in that form.
"""

from __future__ import annotations

import os
import re
import secrets
import stat
from pathlib import Path

from drake_social.errors import ScenarioError
from drake_social.limits import MAX_WAYPOINTS

__all__ = ["MAX_PATH_FILE_BYTES", "MAX_YAML_FILE_BYTES", "check_out_file", "check_regular_file", "read_text_file",
           "read_yaml_file", "describe_mode", "replace_file", "shorten", "yaml_problem"]

#: Bytes allowed per row of a path CSV: four numbers of 17 significant digits
#: with exponent and sign take at most 4 x 24 + 3 commas + CRLF = 101 bytes;
#: this leaves room for spaces.
PATH_ROW_BYTES = 256
#: Largest path CSV (``simulate --path``), bytes: the header and
#: :data:`~drake_social.limits.MAX_WAYPOINTS` rows of :data:`PATH_ROW_BYTES`
#: (2.56 MB; a path of that many waypoints written by ``plan`` is about 0.5 MB).
MAX_PATH_FILE_BYTES = (MAX_WAYPOINTS + 1) * PATH_ROW_BYTES
#: Largest scenario or sweep file, bytes: 4 MiB. The shipped ones are a few
#: kilobytes, a room with 2,000 obstacles about 120 kB; PyYAML reads about
#: 2 MB/s, so this also bounds the time spent parsing.
MAX_YAML_FILE_BYTES = 4 * 1024 * 1024

_KINDS = (
    (stat.S_ISDIR, "a directory"),
    (stat.S_ISFIFO, "a FIFO"),
    (stat.S_ISCHR, "a character device"),
    (stat.S_ISBLK, "a block device"),
    (stat.S_ISSOCK, "a socket"),
)


#: Most characters of the user's input an error message repeats (:func:`shorten`).
SHOWN_CHARACTERS = 80
#: Most characters of a file name an error message repeats.
SHOWN_PATH_CHARACTERS = 300


def shorten(text: str, limit: int = SHOWN_CHARACTERS) -> str:
    """``text`` as an error message repeats it: whole up to ``limit`` characters,
    else its first ``limit`` characters, an ellipsis and its length.

    Args:
        text: the input to repeat (a value's repr, a line, an override).
        limit: the most characters repeated.

    Returns:
        e.g. ``"'aaaa... (4,000 characters)"``.
    """
    if len(text) <= limit:
        return text
    return f"{text[:limit]}... ({len(text):,} characters)"


#: The names PyYAML's messages quote from the text (an anchor, an alias, a
#: tag or tag handle), a quoted string after the word that introduces it.
_YAML_QUOTED_NAME = re.compile(r"""\b(tag handle|alias|anchor|the tag) (?:'(?:[^'\\]|\\.)*'|"(?:[^"\\]|\\.)*")""")


def yaml_problem(error, text: str) -> str:
    """PyYAML's error as one line that quotes none of the text: ``line <n>,
    column <c>: <problem> (<context> at line <n>, column <c>)``.

    PyYAML's own message adds the lines at fault (an excerpt of the text) and
    quotes the names of anchors, aliases and tags; both are left out (the
    text may be any file's, see the module docstring). The single characters
    it quotes (``found character '\\t'``) are kept.

    Args:
        error: a ``yaml.YAMLError`` (a marked error, or a reader error of an
            unacceptable character).
        text: the text PyYAML read (to turn a reader error's position into a line).

    Returns:
        e.g. ``"line 2, column 1: found unexpected end of stream (while
        scanning a quoted scalar at line 1, column 1)"``.
    """
    def where(mark) -> str:
        return f"line {mark.line + 1}, column {mark.column + 1}"

    def scrub(message: str) -> str:
        return _YAML_QUOTED_NAME.sub(r"\1", message)

    problem, mark = getattr(error, "problem", None), getattr(error, "problem_mark", None)
    context, context_mark = getattr(error, "context", None), getattr(error, "context_mark", None)
    if problem is None and context is None:  # a reader error: an unacceptable character at a position
        position = getattr(error, "position", None)
        first = str(error).splitlines()[0] if str(error) else type(error).__name__
        if not isinstance(position, int):
            return scrub(first)
        line = text.count("\n", 0, position)
        column = position - (text.rfind("\n", 0, position) + 1)
        return f"line {line + 1}, column {column + 1}: {scrub(first)}"
    if problem is None:
        problem, mark, context, context_mark = context, context_mark, None, None
    out = f"{where(mark)}: {scrub(problem)}" if mark is not None else scrub(problem)
    if context:
        out += f" ({scrub(context)}" + (f" at {where(context_mark)})" if context_mark is not None else ")")
    return out


def _error(path: Path | str, message: str, option: str | None):
    return ScenarioError(f"{shorten(str(path), SHOWN_PATH_CHARACTERS)}: {message}"
                         + ("" if option is None else f" ({option})"))


def _not_regular(path: Path, mode: int, what: str, option: str | None):
    if stat.S_ISDIR(mode):
        return _error(path, f"is a directory, not a {what} file", option)
    return _error(path, f"not a regular file ({_kind(mode)}); a {what} file must be a regular file", option)


def describe_mode(mode: int) -> str:
    """What a file of ``os.stat`` mode ``mode`` is, for messages: "a directory", "a FIFO", ..."""
    return _kind(mode)


def _kind(mode: int) -> str:
    for test, name in _KINDS:
        if test(mode):
            return name
    return "not a regular file"


def check_regular_file(path: str | Path, what: str, option: str | None = None) -> os.stat_result:
    """Checks that ``path`` names an existing regular file, without opening it.

    Args:
        path: the file.
        what: what the file should be, for the message, e.g. ``"scenario"``.
        option: the command-line option that named it (e.g. ``"--path"``), or None.

    Returns:
        The file's ``os.stat`` (symbolic links followed).

    Raises:
        ScenarioError: ``<path>: no such <what> file``, ``<path>: not a
            regular file (a FIFO)`` (or a directory, a character device, ...),
            ``<path>: cannot be read (...)`` or ``'<path>': not a valid file name (...)``.
    """
    if str(path) == "":  # Path("") would be the working directory
        raise _error(repr(""), f"an empty file name; a {what} file is needed", option)
    path = Path(path)
    try:
        st = os.stat(path)
    except (FileNotFoundError, NotADirectoryError):
        raise _error(path, f"no such {what} file", option) from None
    except OSError as e:
        raise _error(path, f"cannot be read ({e.strerror or e})", option) from None
    except ValueError as e:  # a NUL in the name, or a character the file system's encoding lacks
        raise _error(repr(str(path)), f"not a valid file name ({e})", option) from None
    if not stat.S_ISREG(st.st_mode):
        raise _not_regular(path, st.st_mode, what, option)
    return st


def read_text_file(path: str | Path, what: str, option: str | None = None, *, limit: int) -> str:
    """The UTF-8 text of a regular file of at most ``limit`` bytes.

    The file is checked with :func:`check_regular_file` before it is opened,
    opened non-blocking (a FIFO swapped in after the check does not block)
    and checked again on the open descriptor, then read to at most
    ``limit + 1`` bytes.

    Args:
        path: the file.
        what: what the file should be, for messages (``"scenario"``, ``"sweep"``, ``"path"``).
        option: the command-line option that named it, or None.
        limit: the largest size accepted, bytes.

    Returns:
        The file's text.

    Raises:
        ScenarioError: the file is missing, not a regular file, larger than
            ``limit``, unreadable or not UTF-8; the message names the file.
    """
    st = check_regular_file(path, what, option)
    path = Path(path)
    too_big = f"a {what} file may have at most {limit:,} bytes"
    if st.st_size > limit:
        raise _error(path, f"{st.st_size:,} bytes; {too_big}", option)
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0))
    except OSError as e:
        raise _error(path, f"cannot be read ({e.strerror or e})", option) from None
    with os.fdopen(fd, "rb") as f:
        mode = os.fstat(fd).st_mode
        if not stat.S_ISREG(mode):  # replaced between the stat and the open
            raise _not_regular(path, mode, what, option)
        try:
            data = f.read(limit + 1)
        except OSError as e:
            raise _error(path, f"cannot be read ({e.strerror or e})", option) from None
    if len(data) > limit:  # grew after the stat
        raise _error(path, f"more than {limit:,} bytes; {too_big}", option)
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as e:
        raise _error(path, f"not a text (UTF-8) file: byte {e.start} ({data[e.start:e.start + 1]!r}) is not "
                           f"valid UTF-8", option) from None


def read_yaml_file(path: str | Path, what: str, option: str | None = None) -> str:
    """:func:`read_text_file` with the limit of YAML files, :data:`MAX_YAML_FILE_BYTES`.

    Args:
        path: the file.
        what: ``"scenario"`` or ``"sweep"``, for messages.
        option: the command-line option that named it, or None.
    """
    return read_text_file(path, what, option, limit=MAX_YAML_FILE_BYTES)


def check_out_file(path: str | Path, option: str | None = None) -> None:
    """Refuses a file name to write where something other than a regular file
    stands (a directory, a FIFO, a device, a socket, or a link to one): the
    atomic rename of :func:`replace_file` would put a regular file in its
    place. A new name, or an existing regular file (replaced), is accepted.

    Args:
        path: the file to write.
        option: the command-line option that named it (``--out``), or None.

    Raises:
        ScenarioError: ``<path>: --out: must name a regular file (it is
            replaced) or a new file, got a FIFO``.
    """
    if str(path) == "":
        raise ScenarioError(f"{repr('')}: {option or 'the file to write'}: must name a file, got an empty name")
    where = f"{shorten(str(path), SHOWN_PATH_CHARACTERS)}: {option + ': ' if option else ''}"
    try:
        mode = os.stat(path).st_mode
    except (FileNotFoundError, NotADirectoryError):
        return  # a new file (a missing or blocked folder is the writer's error)
    except OSError as e:
        raise ScenarioError(f"{where}cannot be used ({e.strerror or e})") from None
    except ValueError as e:  # a NUL in the name
        raise ScenarioError(f"{where}not a valid file name ({e})") from None
    if not stat.S_ISREG(mode):
        raise ScenarioError(f"{where}must name a regular file (it is replaced) or a new file, got {_kind(mode)}")


def replace_file(path: str | Path, write, option: str | None = None) -> Path:
    """Writes ``path`` atomically: ``write(f)`` fills a new temporary file
    (binary) beside it, which is flushed to disk and renamed over ``path``,
    so a reader sees the old file or the whole new one; on any error or
    interrupt the temporary file is removed. It is created with mode 0o666
    less the umask, as ``open`` would create ``path``.

    ``path`` is checked with :func:`check_out_file` before the temporary
    file is made and again just before the rename: a directory, FIFO or
    device there is never replaced.

    Args:
        path: the file to write.
        write: fills the open binary file.
        option: the command-line option that named ``path``, for messages.

    Returns:
        ``path``.

    Raises:
        ScenarioError: ``path`` names something other than a regular file.
    """
    path = Path(path)
    check_out_file(path, option)
    temporary = path.with_name(f".{path.name}.{secrets.token_hex(6)}.tmp")
    fd = os.open(temporary, os.O_WRONLY | os.O_CREAT | os.O_EXCL | getattr(os, "O_CLOEXEC", 0), 0o666)
    try:
        with os.fdopen(fd, "wb") as f:
            write(f)
            f.flush()
            os.fsync(f.fileno())
        check_out_file(path, option)
        os.replace(temporary, path)
    except BaseException:
        temporary.unlink(missing_ok=True)
        raise
    return path
