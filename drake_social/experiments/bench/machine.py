"""The machine a benchmark ran on: its processor and its load.

Wall-clock times hold for one processor and load only; every bench names them.
"""

from __future__ import annotations

import os
import platform
from pathlib import Path

__all__ = ["cpu_model", "load_average"]


def cpu_model(cpuinfo: str | Path = "/proc/cpuinfo") -> str | None:
    """The processor's model name (Linux's ``/proc/cpuinfo``), else
    ``platform.processor()``, else None: times from different processors
    are not comparable, so the bench says which one it ran on."""
    try:
        for line in Path(cpuinfo).read_text(errors="replace").splitlines():
            key, sep, value = line.partition(":")
            if sep and key.strip() == "model name" and value.strip():
                return value.strip()
    except OSError:
        pass
    return platform.processor() or None


def load_average() -> list[float] | None:
    """The 1, 5 and 15 minute load averages (None where the OS has none).
    The bench itself keeps about one CPU busy: a load well above 1 at its
    end, or above 0 at its start, means other work shared the machine."""
    try:
        return [round(x, 2) for x in os.getloadavg()]
    except (AttributeError, OSError):
        return None
