"""Keeps numba's on-disk cache of the compiled kernels consistent.

numba (``@njit(cache=True)``) invalidates a cached function only when its
own source file changes, not when a function it calls (and compiles in)
changes in another file: :func:`drake_social.planning.tree_kernel.grow` would
go on running an old :mod:`~drake_social.planning.planar_kernel` after an
edit of that file. :func:`ensure_fresh` therefore stamps the cache
directories with a hash of all kernel sources and drops every cached kernel
when the hash changes. Nothing here imports numba or pydrake.
"""

from __future__ import annotations

import hashlib
from pathlib import Path

__all__ = ["KERNEL_SOURCES", "ensure_fresh", "sources_hash"]

_PACKAGE = Path(__file__).resolve().parent
#: The kernel modules, which call each other's compiled functions.
KERNEL_SOURCES = ("cost/kernel.py", "planning/planar_kernel.py", "planning/tree_kernel.py")
_STAMP = "drake_social_kernels.stamp"
_done = False


def sources_hash() -> str:
    """SHA-256 (hex, 16 digits) of the kernel sources, in order."""
    h = hashlib.sha256()
    for name in KERNEL_SOURCES:
        h.update(name.encode())
        h.update((_PACKAGE / name).read_bytes())
    return h.hexdigest()[:16]


def ensure_fresh() -> None:
    """Drops numba's cached kernels next to the sources when any kernel
    source changed since they were written (once per process; a read-only
    installation is left alone: there numba cannot write caches either)."""
    global _done
    if _done:
        return
    _done = True
    try:
        stamp = sources_hash()
        for folder in sorted({(_PACKAGE / name).parent / "__pycache__" for name in KERNEL_SOURCES}):
            marker = folder / _STAMP
            if marker.is_file() and marker.read_text() == stamp:
                continue
            folder.mkdir(exist_ok=True)
            for pattern in ("*_kernel.*.nbi", "*_kernel.*.nbc", "kernel.*.nbi", "kernel.*.nbc"):
                for f in folder.glob(pattern):
                    f.unlink(missing_ok=True)
            marker.write_text(stamp)
    except OSError:  # read-only or vanished: numba's own checks still apply
        pass
