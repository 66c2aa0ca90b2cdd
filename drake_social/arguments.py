"""Checks of the public functions' arguments, at the door.

Each helper raises a ``TypeError`` (the wrong kind of object) or a
``ValueError`` (the right kind with a value outside what is allowed) whose
message names the function, the argument and what is allowed, so that a
caller never meets an ``AttributeError`` from deep inside the library. No
Drake here: the pure-numpy core uses these too.

Example::

    from drake_social.arguments import require_checker, require_scenario

    def plan(scenario, checker):
        require_scenario(scenario, "plan", "scenario")
        require_checker(checker, "plan", "checker")
"""

from __future__ import annotations

import numbers
import os
from decimal import Decimal
from typing import Any, Callable, Mapping

import numpy as np

from drake_social.scenario import ExecutionOptions, Scenario
from drake_social.io.textfile import shorten

__all__ = [
    "CHECKER_METHODS",
    "Rule",
    "check_arguments",
    "real_array",
    "require_callable",
    "require_checker",
    "require_choice",
    "require_choices",
    "require_execution_options",
    "require_file_name",
    "require_file_names",
    "require_instance",
    "require_int",
    "require_number",
    "require_scenario",
    "require_scenario_or_file",
    "require_strings",
]


def _shown(value: Any) -> str:
    return f"{type(value).__name__} {shorten(repr(value))}"


def require_instance(value: Any, kind: type | tuple[type, ...], who: str, argument: str, allowed: str, *,
                     optional: bool = False) -> None:
    """Refuses ``value`` unless it is an instance of ``kind`` (or None when ``optional``).

    Args:
        value: the argument's value.
        kind: the accepted type(s).
        who: the public function or class, e.g. ``"simulate"``.
        argument: the argument's name, e.g. ``"scenario"``.
        allowed: what is allowed, in words (``"a Scenario (load_scenario(path))"``).
        optional: None is allowed too.

    Raises:
        TypeError: ``<who>: <argument> must be <allowed>, got <type> <value>``.
    """
    if value is None and optional:
        return
    if not isinstance(value, kind):
        raise TypeError(f"{who}: {argument} must be {allowed}{' or None' if optional else ''}, got {_shown(value)}")


def require_scenario(value: Any, who: str, argument: str = "scenario") -> None:
    """Refuses anything but a :class:`~drake_social.scenario.Scenario` (a file
    name is told to be loaded first).

    Raises:
        TypeError: naming ``who``, ``argument`` and what was given.
    """
    if isinstance(value, Scenario):
        return
    hint = " (load the file first: drake_social.scenario.load_scenario(path))" if isinstance(value, (str, bytes)) or \
        type(value).__name__.endswith("Path") else ""
    raise TypeError(f"{who}: {argument} must be a drake_social.scenario.Scenario, got {_shown(value)}{hint}")


def require_execution_options(value: Any, who: str, argument: str = "execution_options") -> None:
    """Refuses anything but an :class:`~drake_social.scenario.ExecutionOptions`
    (a scenario's ``execution`` section).

    Raises:
        TypeError: naming ``who``, ``argument`` and what was given.
    """
    require_instance(value, ExecutionOptions, who, argument,
                     "a drake_social.scenario.ExecutionOptions (a scenario's execution section, scenario.execution)")


#: The methods of :class:`~drake_social.collision.validity.ValidityChecker`,
#: checked by name so that this module does not import the planning package
#: (which imports this one).
CHECKER_METHODS = ("is_valid", "are_valid", "is_motion_valid", "are_motions_valid", "clearance")


def require_checker(value: Any, who: str, argument: str = "checker", *, optional: bool = False) -> None:
    """Refuses anything but a validity checker (an object with the methods of
    :class:`~drake_social.collision.validity.ValidityChecker`); a checker's
    name such as ``"planar"`` is told how to build one.

    Raises:
        TypeError: naming ``who``, ``argument``, the missing methods and what was given.
    """
    if (value is None and optional) or all(callable(getattr(value, m, None)) for m in CHECKER_METHODS):
        return
    allowed = ("a validity checker object (drake_social.collision.drake_checker.make_checker(scenario, kind), "
               "with is_valid, are_valid, is_motion_valid, are_motions_valid and clearance)")
    hint = ""
    if isinstance(value, str):
        hint = f" (a checker's name: build the checker with make_checker(scenario, {shorten(repr(value))}))"
    raise TypeError(f"{who}: {argument} must be {allowed}{' or None' if optional else ''}, got {_shown(value)}{hint}")


def require_choice(value: Any, who: str, argument: str, allowed: tuple[str, ...], *, optional: bool = False) -> None:
    """Refuses a value that is not one of the strings ``allowed`` (None too when ``optional``).

    Raises:
        TypeError: not a string; ValueError: not one of ``allowed``.
    """
    if value is None and optional:
        return
    if not isinstance(value, str):
        raise TypeError(f"{who}: {argument} must be one of {', '.join(allowed)}{' or None' if optional else ''}, "
                        f"got {_shown(value)}")
    if value not in allowed:
        raise ValueError(f"{who}: unknown {argument} {shorten(repr(value))}; allowed: {', '.join(allowed)}")


def require_number(value: Any, who: str, argument: str, *, positive: bool = False, optional: bool = False,
                   unit: str = "", minimum: float | None = None, maximum: float | None = None) -> None:
    """Refuses anything but a finite real number (> 0 when ``positive``, in
    ``[minimum, maximum]`` when they are given).

    Raises:
        TypeError: not a real number (booleans are refused); ValueError: not
            finite, not > 0 when ``positive``, or out of range.
    """
    if value is None and optional:
        return
    unit = f" {unit}" if unit else ""
    rules = ["> 0"] if positive else []
    rules += [] if minimum is None else [f">= {minimum:g}"]
    rules += [] if maximum is None else [f"<= {maximum:g}"]
    what = f"a finite number{' ' + ' and '.join(rules) if rules else ''}{unit}"
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise TypeError(f"{who}: {argument} must be {what}{' or None' if optional else ''}, got {_shown(value)}")
    try:
        number = float(value)
    except OverflowError:  # an integer beyond the floats
        number = float("inf")
    if not (number == number and abs(number) != float("inf")) or (positive and not value > 0) \
            or (minimum is not None and not value >= minimum) or (maximum is not None and not value <= maximum):
        raise ValueError(f"{who}: {argument} must be {what}, got {shorten(str(value))}")


def require_int(value: Any, who: str, argument: str, *, minimum: int | None = None, maximum: int | None = None,
                optional: bool = False) -> None:
    """Refuses anything but an integer in ``[minimum, maximum]``.

    Raises:
        TypeError: not an integer (booleans and floats are refused);
            ValueError: out of range.
    """
    if value is None and optional:
        return
    low = "" if minimum is None else f" >= {minimum}"
    high = "" if maximum is None else f" <= {maximum:,}"
    what = f"an integer{low}{' and' if low and high else ''}{high}"
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise TypeError(f"{who}: {argument} must be {what}{' or None' if optional else ''}, got {_shown(value)}")
    if (minimum is not None and value < minimum) or (maximum is not None and value > maximum):
        raise ValueError(f"{who}: {argument} must be {what}, got {value}")


def require_file_name(value: Any, who: str, argument: str, *, optional: bool = False) -> None:
    """Refuses anything but a file or folder name: a ``str`` or an
    ``os.PathLike`` such as :class:`pathlib.Path` (None too when ``optional``).

    Raises:
        TypeError: naming ``who``, ``argument`` and what was given.
    """
    if (value is None and optional) or isinstance(value, (str, os.PathLike)):
        return
    raise TypeError(f"{who}: {argument} must be a file name (a str or pathlib.Path){' or None' if optional else ''}, "
                    f"got {_shown(value)}")


def require_scenario_or_file(value: Any, who: str, argument: str = "scenario") -> None:
    """Refuses anything but a :class:`~drake_social.scenario.Scenario` or
    the name of its YAML file (a ``str`` or ``os.PathLike``).

    Raises:
        TypeError: naming ``who``, ``argument`` and what was given.
    """
    if not isinstance(value, (Scenario, str, os.PathLike)):
        raise TypeError(f"{who}: {argument} must be a scenario file name (a str or pathlib.Path) or a "
                        f"drake_social.scenario.Scenario, got {_shown(value)}")


def _sequence(value: Any, who: str, argument: str, what: str, optional: bool, nonempty: bool) -> bool:
    """Refuses a value that is not a list or tuple (a lone string included),
    or an empty one when ``nonempty``; True when it is None and ``optional``."""
    if value is None and optional:
        return True
    if not isinstance(value, (list, tuple)):
        hint = f" (a list of one: [{shorten(repr(value))}])" if isinstance(value, (str, os.PathLike)) else ""
        raise TypeError(f"{who}: {argument} must be a list or tuple of {what}{' or None' if optional else ''}, "
                        f"got {_shown(value)}{hint}")
    if nonempty and not value:
        raise ValueError(f"{who}: {argument} must be a non-empty list or tuple of {what}, got {_shown(value)}")
    return False


def require_strings(value: Any, who: str, argument: str, *, optional: bool = False, nonempty: bool = False) -> None:
    """Refuses anything but a list or tuple of strings (never a lone string).

    Raises:
        TypeError: not a list or tuple, or an item not a string; ValueError:
            empty when ``nonempty``.
    """
    if _sequence(value, who, argument, "strings", optional, nonempty):
        return
    for i, item in enumerate(value):
        if not isinstance(item, str):
            raise TypeError(f"{who}: {argument}[{i}] must be a string, got {_shown(item)}")


def require_choices(value: Any, who: str, argument: str, allowed: tuple[str, ...], *, optional: bool = False,
                    distinct: bool = True) -> None:
    """Refuses anything but a non-empty list or tuple of names of ``allowed``
    (each at most once when ``distinct``).

    Raises:
        TypeError: not a list or tuple of strings; ValueError: empty, a
            name not allowed or (``distinct``) a name twice.
    """
    if _sequence(value, who, argument, f"names of {', '.join(allowed)}", optional, True):
        return
    for i, item in enumerate(value):
        require_choice(item, who, f"{argument}[{i}]", allowed)
    if distinct and len(set(value)) != len(value):
        raise ValueError(f"{who}: {argument} must name each of {', '.join(allowed)} at most once, "
                         f"got {_shown(list(value))}")


def require_file_names(value: Any, who: str, argument: str, *, optional: bool = False) -> None:
    """Refuses anything but a non-empty list or tuple of file names (``str`` or ``os.PathLike``).

    Raises:
        TypeError: not a list or tuple, or an item not a file name; ValueError: empty.
    """
    if _sequence(value, who, argument, "file names (str or pathlib.Path)", optional, True):
        return
    for i, item in enumerate(value):
        require_file_name(item, who, f"{argument}[{i}]")


#: A check of one argument: ``rule(value, who, argument)`` raises a
#: ``TypeError`` or ``ValueError`` naming ``who`` and ``argument``.
Rule = Callable[[Any, str, str], None]


def check_arguments(who: str, rules: Mapping[str, Rule], values: Mapping[str, Any]) -> None:
    """Checks each of ``values`` (argument name -> value) by its rule of ``rules``.

    Example::

        RULES = {"seed": lambda v, who, name: require_int(v, who, name, minimum=0, optional=True)}
        check_arguments("run_plan", RULES, {"seed": seed})

    Raises:
        TypeError: a name without a rule (``who``'s allowed names listed),
            or a rule's TypeError; ValueError: a rule's ValueError.
    """
    for name, value in values.items():
        rule = rules.get(name)
        if rule is None:
            raise TypeError(f"{who}: unexpected argument {name!r}; allowed: {', '.join(rules)}")
        rule(value, who, name)


def require_callable(value: Any, who: str, argument: str, *, optional: bool = True) -> None:
    """Refuses a value that cannot be called (None is allowed when ``optional``).

    Raises:
        TypeError: naming ``who`` and ``argument``.
    """
    if value is None and optional:
        return
    if not callable(value):
        raise TypeError(f"{who}: {argument} must be a callable{' or None' if optional else ''}, got {_shown(value)}")



def _shape_text(shape: tuple[int | None, ...]) -> str:
    """``an (N, 4) array``, ``a (4,) array``."""
    dims = ["N" if n is None else str(n) for n in shape]
    text = f"({dims[0]},)" if len(dims) == 1 else f"({', '.join(dims)})"
    return f"{'an' if dims[0] in ('N', '8', '11', '18') else 'a'} {text} array"


def real_array(value: Any, who: str, argument: str, shape: tuple[int | None, ...], *, layout: str = "",
               rows: tuple[int, int | None] = (0, None), rows_note: str = "", row_name: str = "row",
               finite: bool = True, error: type[ValueError] = ValueError) -> np.ndarray:
    """``value`` as a new float array of exactly ``shape``, refused otherwise
    (never reshaped, truncated or rounded).

    Accepted: an array or nested sequence of real numbers: Python and numpy
    integers and floats, and in an object array any :class:`numbers.Real`
    (``Fraction``) or ``Decimal``. Refused: booleans, complex numbers,
    strings, None and other objects, masked arrays (their mask would be
    lost), ragged rows, a wrong shape.

    Args:
        value: the argument's value.
        who: the public function, e.g. ``"simulate"`` (or the whole source
            of the value, a file, when ``argument`` is empty).
        argument: the argument's name, e.g. ``"waypoints"``.
        shape: the shape, None where any length goes (the first axis: the rows).
        layout: what the array holds, for the message (``"rows [x, y, psi1, psi2]"``).
        rows: (fewest, most or None) rows when ``shape[0]`` is None.
        rows_note: said after the rule when the number of rows is wrong.
        row_name: what a row is, for that message (``"waypoint"``).
        finite: refuse NaN and infinities too.
        error: the class of the errors for a wrong shape or value (a
            ``ValueError``, e.g. ``ScenarioError``).

    Returns:
        A new float array.

    Raises:
        TypeError: not an array of real numbers;
        ``error``: the wrong shape or number of rows, or a value not finite.
    """
    fewest, most = rows
    count = ""
    if shape and shape[0] is None and (fewest or most is not None):
        count = (f" with {fewest:,} <= N <= {most:,}" if most is not None else f" with N >= {fewest:,}")
    what = f"{_shape_text(shape)}{' of ' + layout if layout else ''}{count}"
    reals = f"{_shape_text(shape)} of real numbers{' (' + layout + ')' if layout else ''}{count}"
    prefix = f"{who}: {argument}" if argument else who
    if isinstance(value, np.ma.MaskedArray):
        raise TypeError(f"{prefix}: must be {reals}, got a masked array (its mask would be ignored: "
                        "pass the values to use, e.g. array.compressed() or array.filled(...))")
    if value is None or isinstance(value, (str, bytes, bool, np.bool_, complex, np.complexfloating)):
        raise TypeError(f"{prefix}: must be {reals}, got {_shown(value)}")
    try:
        raw = np.asarray(value)
    except (TypeError, ValueError) as e:  # ragged rows
        raise error(f"{prefix}: must be {what}; its rows differ in length ({e})") from None
    if raw.dtype.kind == "O":
        flat = raw.ravel()
        wrong = [v for v in flat if isinstance(v, (bool, np.bool_)) or not isinstance(v, (numbers.Real, Decimal))]
        if wrong:
            kinds = ", ".join(sorted({type(v).__name__ for v in wrong[:1000]}))
            raise TypeError(f"{prefix}: must be {reals}, got values of type {kinds}")
        try:
            raw = np.array([float(v) for v in flat], float).reshape(raw.shape)
        except (OverflowError, ValueError) as e:
            raise error(f"{prefix}: must be {reals} ({e})") from None
    elif raw.dtype.kind not in "iuf":
        raise TypeError(f"{prefix}: must be {reals}, got an array of {raw.dtype}")
    if raw.ndim != len(shape) or any(n is not None and m != n for m, n in zip(raw.shape, shape)):
        raise error(f"{prefix}: must be {what}, got shape {raw.shape}")
    if shape and shape[0] is None and not (fewest <= len(raw) and (most is None or len(raw) <= most)):
        n = len(raw)
        raise error(f"{prefix}: must be {what}{' ' + rows_note if rows_note else ''}, got {n:,} "
                    f"{row_name}{'' if n == 1 else 's'}")
    out = np.array(raw, dtype=float)
    if finite and not np.all(np.isfinite(out)):
        index = tuple(int(i) for i in np.argwhere(~np.isfinite(out))[0])
        raise error(f"{prefix}: must hold finite numbers only, got {out[index]} at index "
                    f"{index if len(index) > 1 else index[0]}")
    return out
