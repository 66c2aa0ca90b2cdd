"""Numbers for strict JSON: non-finite floats become null.

Python's :mod:`json` writes ``NaN`` and ``Infinity``, which strict JSON
readers refuse; the records of the benchmarks and studies are written with
``allow_nan=False`` after :func:`finite_or_none`.
"""

import math

__all__ = ["finite_or_none"]


def finite_or_none(x):
    """``x`` with every non-finite float (NaN, +-inf) replaced by None, through
    nested dicts, lists and tuples (tuples become lists, as JSON writes them).

    Args:
        x: a value made of dicts, lists, tuples, floats and other JSON scalars.

    Returns:
        The same structure, ready for ``json.dumps(..., allow_nan=False)``.
    """
    if isinstance(x, dict):
        return {k: finite_or_none(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [finite_or_none(v) for v in x]
    if isinstance(x, float) and not math.isfinite(x):
        return None
    return x
