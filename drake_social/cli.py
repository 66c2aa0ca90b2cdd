"""The ``drake-social`` command: a thin argparse front end.

Each subcommand is a pair of functions: ``_add_<name>(subparsers)`` declares
its arguments and sets ``run`` to ``_run_<name>(args) -> int``, which loads
the scenario and calls the library. Add a subcommand by writing such a pair
and listing ``_add_<name>`` in :data:`_SUBCOMMANDS`.

Usage::

    drake-social show scenarios/office_bar.yaml --out out/office_bar
    drake-social show scenarios/tiny.yaml --set "social: {sigma_h: 1.5}"

Exit codes: 0 success, 1 an output could not be written, 2 bad command line
or invalid scenario (the message names the file and the field).
"""

from __future__ import annotations

import argparse
import logging
import sys
from pathlib import Path
from typing import Callable, Sequence

import matplotlib

from drake_social import __version__
from drake_social.scenario import Scenario, ScenarioError, load_scenario

__all__ = ["main", "build_parser", "load_with_overrides"]

_log = logging.getLogger("drake_social")


def load_with_overrides(path: str | Path, sets: Sequence[str] | None) -> Scenario:
    """Loads a scenario with the ``--set`` overrides of the command line.

    Each ``--set`` text is a YAML mapping applied over the file, e.g.
    ``"random_seed: 3"`` or ``"social: {sigma_h: 1.5, threshold: 0.1}"``.
    Several are joined into one mapping; giving the same top-level key twice
    is an error, since YAML would silently keep only the last one.

    Raises:
        ScenarioError: the file, an override or a value is invalid.
    """
    import yaml  # the composer only: top-level keys, custom tags left alone

    texts = list(sets or [])
    seen: dict[str, int] = {}
    for i, text in enumerate(texts):
        try:
            node = yaml.compose(text)
        except yaml.YAMLError as e:
            raise ScenarioError(f"{path} (--set {text!r}): not valid YAML: {e}") from e
        if not isinstance(node, yaml.MappingNode):
            raise ScenarioError(f"{path} (--set {text!r}): must be a YAML mapping such as 'random_seed: 3'")
        for key, _ in node.value:
            if key.value in seen:
                raise ScenarioError(
                    f"{path} (--set {text!r}): key '{key.value}' is already set by --set {texts[seen[key.value]]!r}; "
                    f"give all its fields in one --set, e.g. 'social: {{sigma_h: 1.5, threshold: 0.1}}'"
                )
            seen[key.value] = i
    return load_scenario(path, "\n".join(texts) if texts else None)


def _add_scenario_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("scenario", type=Path, help="scenario YAML file, e.g. scenarios/office_bar.yaml")
    parser.add_argument(
        "--set",
        action="append",
        metavar="YAML",
        help="override scenario fields with a YAML mapping, e.g. \"social: {sigma_h: 1.5}\" "
        "(repeatable, one top-level key per --set)",
    )


def _default_out(scenario_path: Path) -> Path:
    return Path("out") / scenario_path.stem


# ---- show --------------------------------------------------------------------


def _add_show(subparsers) -> None:
    p = subparsers.add_parser(
        "show",
        help="draw the scenario: map, people, social-cost heat map, robot at start and goal",
        description="Writes DIR/scene.png: the map, obstacles, people with facing arrows, the social-cost "
        "heat map with its colour bar, and the robot with arm and object at start and goal.",
    )
    _add_scenario_arguments(p)
    p.add_argument("--out", type=Path, metavar="DIR", help="output directory (default: out/<scenario name>)")
    p.set_defaults(run=_run_show)


def _run_show(args: argparse.Namespace) -> int:
    from drake_social.viz import write_show  # matplotlib figures: only when drawing

    scenario = load_with_overrides(args.scenario, args.set)
    out = args.out if args.out is not None else _default_out(args.scenario)
    path = write_show(scenario, out, title=scenario.description or args.scenario.name)
    print(f"wrote {path}")
    return 0


# ---- parser and entry point ----------------------------------------------------

_SUBCOMMANDS: list[Callable] = [_add_show]


def build_parser() -> argparse.ArgumentParser:
    """The argument parser with every subcommand."""
    parser = argparse.ArgumentParser(
        prog="drake-social",
        description="Socially-aware object transport by a planar mobile manipulator, built on Drake.",
    )
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    parser.add_argument("-v", "--verbose", action="store_true", help="log progress (INFO level)")
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND")
    for add in _SUBCOMMANDS:
        add(subparsers)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Runs ``drake-social``; returns the exit code.

    Args:
        argv: the arguments after the program name; None = ``sys.argv[1:]``.
    """
    matplotlib.use("Agg")  # files only, never a window (CI has no display)
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as e:  # --help, --version or a usage error already printed
        return int(e.code or 0)
    if args.command is None:
        parser.print_help(sys.stderr)
        return 2
    logging.basicConfig(level=logging.INFO if args.verbose else logging.WARNING, format="%(name)s: %(message)s")
    try:
        return args.run(args)
    except ScenarioError as e:
        print(f"drake-social: error: {e}", file=sys.stderr)
        return 2
    except OSError as e:  # e.g. --out names a file, or a directory without write access
        print(f"drake-social: error: {e}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
