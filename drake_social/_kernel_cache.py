"""Keeps numba's on-disk cache of the compiled kernels consistent.

numba (``@njit(cache=True)``) invalidates a cached function only when its
own source file changes, not when a function it calls (and compiles in)
changes in another file: :func:`drake_social.planning.rrt_star.tree_kernel.grow` would
go on running an old :mod:`~drake_social.collision.planar_kernel` after an
edit of that file. :func:`ensure_fresh` therefore stamps the cache
directories with a hash of all kernel sources and drops every cached kernel
when the hash changes: the ``__pycache__`` folders beside the sources, and
the folders numba uses instead (``NUMBA_CACHE_DIR`` when set; the user-wide
``numba`` cache folder when the package's folder is read-only), where only
files below a ``drake_social`` folder are touched. Nothing here imports
numba or pydrake. Filling the cache ahead of the first command is
:mod:`drake_social.warmup`'s job (``make install`` runs it).
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

__all__ = ["KERNEL_SOURCES", "ensure_fresh", "sources_hash"]

_PACKAGE = Path(__file__).resolve().parent
#: The kernel modules, which call each other's compiled functions, the limits
#: they compile in, and the NamedTuple of the checker's scene they take.
KERNEL_SOURCES = (
    "cost/kernel.py", "collision/planar_kernel.py", "planning/rrt_star/tree_kernel.py", "limits.py",
    "collision/validity.py", "cost/timed_kernel.py", "collision/people_kernel.py", "people/prediction_kernel.py",
)
_STAMP = "drake_social_kernels.stamp"
_done = False


def sources_hash() -> str:
    """SHA-256 (hex, 16 digits) of the kernel sources, in order."""
    h = hashlib.sha256()
    for name in KERNEL_SOURCES:
        h.update(name.encode())
        h.update((_PACKAGE / name).read_bytes())
    return h.hexdigest()[:16]


#: numba names a cached kernel's files after its module ("timed_kernel.msc_sums_timed-58.py311.nbi"):
#: those of every kernel module above.
_PATTERNS = tuple(f"{Path(name).stem}.*.{ext}" for name in KERNEL_SOURCES if name.endswith("kernel.py")
                  for ext in ("nbi", "nbc"))


def _clear(folder: Path, stamp: str, recursive: bool) -> None:
    """Drops the kernels' cache files in ``folder`` (below it, in folders
    named after drake_social, when ``recursive``) unless its stamp is current."""
    marker = folder / _STAMP
    if marker.is_file() and marker.read_text() == stamp:
        return
    if recursive:
        if not folder.is_dir():
            return
        files = (f for pattern in _PATTERNS for f in folder.rglob(pattern) if "drake_social" in str(f.parent))
    else:
        folder.mkdir(exist_ok=True)
        files = (f for pattern in _PATTERNS for f in folder.glob(pattern))
    for f in list(files):
        f.unlink(missing_ok=True)
    marker.write_text(stamp)


def _other_cache_folders() -> list[Path]:
    """Where numba may cache instead of ``__pycache__``: NUMBA_CACHE_DIR, and
    its user-wide folder (``$XDG_CACHE_HOME/numba``, default ``~/.cache/numba``)."""
    out = []
    if os.environ.get("NUMBA_CACHE_DIR"):
        out.append(Path(os.environ["NUMBA_CACHE_DIR"]))
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    out.append(Path(base) / "numba")
    return out


def ensure_fresh() -> None:
    """Drops numba's cached kernels wherever numba may have written them when
    any kernel source changed since they were written (once per process;
    a folder that cannot be written is left alone)."""
    global _done
    if _done:
        return
    _done = True
    try:
        stamp = sources_hash()
    except OSError:  # sources not readable: numba's own checks still apply
        return
    for folder in sorted({(_PACKAGE / name).parent / "__pycache__" for name in KERNEL_SOURCES}):
        try:
            _clear(folder, stamp, recursive=False)
        except OSError:  # read-only installation: numba then caches elsewhere (below)
            pass
    for folder in _other_cache_folders():
        try:
            _clear(folder, stamp, recursive=True)
        except OSError:
            pass
