"""The ``drake-social`` command: a thin argparse front end.

Each subcommand is a pair of functions: ``_add_<name>(subparsers)`` declares
its arguments and sets ``run`` to ``_run_<name>(args) -> int``, which loads
the scenario and calls the library. Add a subcommand by writing such a pair
and listing ``_add_<name>`` in :data:`_SUBCOMMANDS`.

Usage::

    drake-social show scenarios/office_bar.yaml --out out/office_bar
    drake-social show scenarios/tiny.yaml --set "social: {sigma_h: 1.5}"
    drake-social plan scenarios/office_bar.yaml --algorithm social_rrt_star --out out/office_bar
    drake-social simulate scenarios/office_bar.yaml --out out/office_bar
    drake-social simulate scenarios/tiny.yaml --mode dynamic --execution paper --path out/tiny/path.csv
    drake-social bench --seeds 10 --out out/bench

Exit codes: 0 success, 1 an output could not be written (also when another
run of the same command is writing into the same ``--out``: the second run is
refused at once, before any work, and writes nothing), 2 bad command line
or invalid input (the message names the file and the field, or the start or
goal in collision), 3 ``plan`` found no path (its outputs are still written),
4 ``plan`` returned a path that Drake's independent check rejects (a bug in
the checker that planned it; the outputs are still written, and one line on
stderr names the segment), 5 ``simulate`` did not reach the goal within
``execution.time_limit``, 6 ``simulate``'s executed trajectory collides,
7 it reached the goal collision-free but passed a joint limit (or left the
room bounds; ``simulate`` writes its files in every case and names each
finding on stderr), 130 interrupted (Ctrl-C): one
line says what, and no file of the interrupted run is left (outputs are
written as one set, see :mod:`drake_social.io.outputs`).
"""

from __future__ import annotations

import argparse
import atexit
import gc
import json
import logging
import shutil
import signal
import sys
from pathlib import Path
from typing import Callable, Sequence, TextIO

import numpy as np

from drake_social import __version__
from drake_social.planning.result import PlanningInputError
from drake_social.scenario import (ALGORITHMS, CHECKERS, Scenario, ScenarioError, compose_yaml, load_scenario,
                                    plant_time_step_problem)
from drake_social.io.textfile import check_regular_file, read_text_file, shorten

__all__ = ["EXIT_NO_PATH", "ProgressBar", "main", "build_parser", "load_with_overrides"]


def _skip_the_last_collection() -> None:
    """A command's process would end with a garbage collection over every
    object that numba, Drake and matplotlib made (about 1 s); the OS frees
    them anyway. Not when OMPL is loaded: its nanobind bindings would report
    the objects left as leaks."""
    if "ompl" not in sys.modules:
        gc.freeze()


atexit.register(_skip_the_last_collection)

#: Most seeds of ``bench --seeds``: as many as a study's runs per planner
#: (``experiments.study.MAX_RUNS``); each seed plans every algorithm on every scenario.
MAX_BENCH_SEEDS = 10_000
#: Most timings of one run in ``bench --repeats``: the median of 100 already
#: filters the machine's noise, and each repeat replans the whole path.
MAX_BENCH_REPEATS = 100
#: Most worker processes of ``experiment --workers``: each holds Drake and a
#: scenario's checker (a few hundred MB), so 64 already needs tens of GB; a
#: cluster is the place for more (``--executor dask --scheduler``).
MAX_WORKERS = 64
#: The files ``plan`` writes into ``--out`` (a folder of such a name is refused before planning).
PLAN_OUTPUTS = ("path.csv", "result.json", "path.png", "cost_profile.png", "convergence.png")
#: The files ``simulate`` may write into ``--out`` (replay.html when Meshcat records).
SIMULATE_OUTPUTS = ("replay.html", "executed.csv", "tracking.png", "sim.json")

#: Exit code of ``plan`` when no path reaches the goal.
EXIT_NO_PATH = 3
#: Exit code of ``plan`` when Drake's verification rejects the returned path (a bug, not bad input).
EXIT_UNVERIFIED = 4

_log = logging.getLogger("drake_social")


def load_with_overrides(path: str | Path, sets: Sequence[str] | None) -> Scenario:
    """Loads a scenario with the ``--set`` overrides of the command line.

    Each ``--set`` text is a YAML mapping applied over the file in turn, e.g.
    ``"random_seed: 3"`` or ``"social: {sigma_h: 1.5}"``; a later one merges
    into what the earlier ones left (``--set "social: {sigma_h: 1.5}" --set
    "social: {threshold: 0.1}"`` sets both).

    Raises:
        ScenarioError: the file, an override or a value is invalid; the
            message names the ``--set`` at fault.
    """
    import yaml  # to name the --set at fault before Drake's loader sees it

    texts = list(sets or [])
    for text in texts:
        node = compose_yaml(text, f"{path} (--set {shorten(repr(text))})")
        if not isinstance(node, yaml.MappingNode):
            raise ScenarioError(f"{path} (--set {shorten(repr(text))}): must be a YAML mapping such as "
                                f"'random_seed: 3'")
    return load_scenario(path, texts, overrides_name="--set")


def _add_scenario_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("scenario", type=Path, help="scenario YAML file, e.g. scenarios/office_bar.yaml")
    parser.add_argument(
        "--set",
        action="append",
        metavar="YAML",
        help="override scenario fields with a YAML mapping, e.g. \"social: {sigma_h: 1.5}\" "
        "(repeatable: applied in turn, each merging into the result of the earlier ones)",
    )


def _check_out_folder(out: Path) -> None:
    """Refuses an ``--out`` that is not a folder, nor could become one: it, or
    the nearest of its parents that exists, must be a directory.

    Raises:
        NotADirectoryError: ``<out>: --out must be a folder ...`` naming what
            is in the way (an output that cannot be written: exit 1).
    """
    import os
    import stat

    from drake_social.io.textfile import describe_mode

    here = out
    while True:
        try:
            mode = os.stat(here).st_mode
        except (FileNotFoundError, NotADirectoryError):
            if os.path.islink(here):  # a link to nothing: mkdir cannot make the folder there
                where = "it is" if here == out else f"{here} is"
                raise NotADirectoryError(
                    f"{shorten(str(out), 300)}: --out must be a folder (its outputs are written inside it); {where} "
                    f"a symbolic link to {shorten(os.readlink(here), 300)}, which does not exist") from None
            if here == here.parent:
                return
            here = here.parent
            continue
        except (OSError, ValueError) as e:
            raise NotADirectoryError(f"{shorten(str(out), 300)}: --out cannot be used "
                                     f"({getattr(e, 'strerror', None) or e})") from None
        if stat.S_ISDIR(mode):
            return
        what = "a file" if stat.S_ISREG(mode) else describe_mode(mode)
        where = "it is" if here == out else f"{here} is"
        raise NotADirectoryError(f"{shorten(str(out), 300)}: --out must be a folder (its outputs are written inside "
                                 f"it); {where} {what}")


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
    from drake_social.io.outputs import OutputSet
    from drake_social.viz import write_show  # matplotlib figures: only when drawing

    scenario = load_with_overrides(args.scenario, args.set)
    out = args.out if args.out is not None else _default_out(args.scenario)
    with OutputSet(out, "show", names=["scene.png"]) as outputs:
        write_show(scenario, outputs.folder, title=scenario.description or args.scenario.name)
    print(f"wrote {out / 'scene.png'}")
    return 0


# ---- plan --------------------------------------------------------------------


class ProgressBar:
    """A one-line progress bar on a stream (tqdm), e.g. ``planning [####......] 800/2000, best 5.1  00:01``.

    Called as ``bar(iteration, best_cost)`` (the planners' progress callback)
    or :meth:`update` with any status text; tqdm redraws at most every
    ``interval`` seconds (and at the end), so the callback stays cheap.
    :meth:`close` ends the line.

    Args:
        total: the last step, e.g. K iterations.
        stream: where to draw (standard error).
        label: text before the bar.
        width: characters of the bar.
        interval: least time between redraws, seconds.
    """

    def __init__(self, total: int, stream: TextIO, label: str = "planning", width: int = 30,
                 interval: float = 0.1):
        from tqdm import tqdm

        self._stream = _LineEnd(stream)
        try:  # tqdm draws the bar while it is made: a Ctrl-C then must not strand the line
            self._bar = tqdm(total=max(1, int(total)), file=self._stream, desc=label, ascii=".#",
                             mininterval=interval,
                             bar_format="{desc} [{bar:%d}] {n_fmt}/{total_fmt}{postfix}  {elapsed}" % width,
                             dynamic_ncols=False, leave=True)
        except BaseException:
            if self._stream.open:
                self._stream.write("\n")
            raise

    @property
    def total(self) -> int:
        return self._bar.total

    @total.setter
    def total(self, value: int) -> None:
        self._bar.total = max(1, int(value))

    def __call__(self, iteration: int, best_cost: float) -> None:
        self.update(iteration, f"best {best_cost:.4g}" if best_cost < float("inf") else "no path yet")

    def update(self, done: int, status: str) -> None:
        """Moves the bar to ``done`` of :attr:`total` steps with ``status`` after it."""
        self._bar.set_postfix_str(status, refresh=False)
        self._bar.update(int(done) - self._bar.n)

    def close(self) -> None:
        """Ends the bar's line, also when a Ctrl-C cut its last redraw short
        (tqdm then skips the final line)."""
        self._bar.close()
        if self._stream.open:
            self._stream.write("\n")


class _LineEnd:
    """A text stream that remembers whether its last line is still open."""

    def __init__(self, stream: TextIO):
        self._stream = stream
        self.open = False

    def write(self, text: str) -> int:
        if text:
            self.open = not text.endswith("\n")
        return self._stream.write(text)

    def flush(self) -> None:
        self._stream.flush()

    def __getattr__(self, name):  # isatty, encoding, ... of the wrapped stream
        return getattr(self._stream, name)


def _int_at_least(minimum: int, maximum: int | None = None) -> Callable[[str], int]:
    allowed = f"an integer >= {minimum}" if maximum is None else f"an integer in [{minimum}, {maximum:,}]"

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"must be {allowed}, got {shorten(repr(text))}") from None
        if value < minimum or (maximum is not None and value > maximum):
            raise argparse.ArgumentTypeError(f"must be {allowed}, got {shorten(text)}")
        return value

    return parse


_positive_int = _int_at_least(1)
_nonnegative_int = _int_at_least(0)


def _add_checker_argument(parser: argparse.ArgumentParser, default: str = "drake") -> None:
    parser.add_argument("--checker", choices=CHECKERS, default=default,
                        help=f"validity checker (default: {default}): planar (exact planar distances of the "
                        "SceneGraph's shapes, compiled; sound motion checks), drake (Drake's SceneGraph alone; "
                        "its motion checks are approximate: they trust Drake's clearance, which overestimates "
                        "some cylinder-box distances) or numpy (the pure-numpy reference, sound motion checks)")


def _make_checker(scenario: Scenario, kind: str, source: str):
    """The validity checker of ``kind``; the Drake one first explains a start
    or goal in collision by naming the touching bodies (ScenarioError)."""
    from drake_social.collision.drake_checker import make_checker  # imports Drake: only when planning

    return make_checker(scenario, kind, source=source)


def _add_planner_arguments(parser: argparse.ArgumentParser) -> None:
    """--algorithm, --iterations, --seed and --checker, as plan and simulate take them."""
    parser.add_argument("--algorithm", choices=ALGORITHMS, help="planner (default: the scenario's planner.algorithm)")
    parser.add_argument("--iterations", type=_positive_int, metavar="K",
                        help="samples drawn (default: the scenario's planner.iterations)")
    parser.add_argument("--seed", type=_nonnegative_int, metavar="S",
                        help="random seed >= 0 (default: the scenario's random_seed)")
    _add_checker_argument(parser, default="planar")


def _add_output_arguments(parser: argparse.ArgumentParser) -> None:
    """--out and --progress."""
    parser.add_argument("--out", type=Path, metavar="DIR", help="output directory (default: out/<scenario name>)")
    parser.add_argument("--progress", action="store_true",
                        help="draw the progress bar on stderr even when it is not a terminal")


def _show_progress(args: argparse.Namespace) -> bool:
    return bool(args.progress) or sys.stderr.isatty()


def _add_plan(subparsers) -> None:
    p = subparsers.add_parser(
        "plan",
        help="plan a path from start to goal; write path.csv, result.json and figures",
        description="Plans the scenario with one of the RRT* family, prints a one-line summary and writes "
        "DIR/path.csv (waypoints x,y,psi1,psi2), DIR/result.json (costs, counters, the anytime curve), "
        "DIR/path.png (the path over the social heat map with the robot along it), DIR/cost_profile.png "
        "(social cost versus cumulative configuration distance) and DIR/convergence.png (best cost per "
        "iteration). Exit code 3 when no path was found, 4 when Drake's independent check rejects the "
        "returned path (the files are written in both cases).",
    )
    _add_scenario_arguments(p)
    _add_planner_arguments(p)
    _add_output_arguments(p)
    p.set_defaults(run=_run_plan)


def _write_path_csv(path: Path, waypoints) -> None:
    """Writes waypoints (N, 4) as CSV with header ``x,y,psi1,psi2`` (17 digits: exact round trip)."""
    np.savetxt(path, np.asarray(waypoints, float).reshape(-1, 4), delimiter=",", header="x,y,psi1,psi2",
               comments="", fmt="%.17g")


def _json_lines(record: dict) -> str:
    """JSON with one top-level key per line (arrays such as the waypoints stay on their line)."""
    body = ",\n".join(f"  {json.dumps(k)}: {json.dumps(v, allow_nan=False)}" for k, v in record.items())
    return "{\n" + body + "\n}\n"


def _run_plan(args: argparse.Namespace) -> int:
    from drake_social.io.outputs import OutputSet
    from drake_social.planning.algorithms import plan
    from drake_social.viz.path import write_plan_figures  # matplotlib figures: only when drawing

    from drake_social.scenario import validate_planner_choice

    scenario = load_with_overrides(args.scenario, args.set)
    out = args.out if args.out is not None else _default_out(args.scenario)
    iterations = args.iterations or scenario.planner.iterations
    chosen = [f"--{name}" for name in ("algorithm", "iterations") if getattr(args, name) is not None]
    if chosen:  # the scenario was validated with its own planner options
        validate_planner_choice(scenario, args.algorithm or scenario.planner.algorithm, iterations,
                                source=f"{args.scenario} ({_listed(chosen)})")
    checker = _make_checker(scenario, args.checker, str(args.scenario))
    # Entered before planning: an unwritable or busy --out fails early (exit 1),
    # and nothing of this run lands in --out unless all of it does.
    with OutputSet(out, "plan", names=PLAN_OUTPUTS) as outputs:
        bar = ProgressBar(iterations, sys.stderr) if _show_progress(args) else None
        try:
            result = plan(scenario, checker, algorithm=args.algorithm, iterations=iterations, seed=args.seed,
                          progress=bar)
        except PlanningInputError as e:
            raise PlanningInputError(f"{args.scenario}: {e}") from e
        finally:
            if bar is not None:
                bar.close()
        print(result.summary())
        bad = None
        if result.success:  # Drake's independent second opinion, before anything is committed
            from drake_social.collision.drake_checker import verify_path

            bad = verify_path(checker, result.waypoints)

        _write_path_csv(outputs.path("path.csv"), result.waypoints)
        record = {
            "scenario": str(args.scenario),
            "overrides": list(args.set or []),
            "checker": args.checker,
            "iterations": iterations,
            # Every segment passes Drake's SceneGraphCollisionChecker (None: no path).
            "drake_verified": (bad is None) if result.success else None,
            **result.to_json_dict(),
        }
        outputs.write_text("result.json", _json_lines(record))
        figures = write_plan_figures(scenario, result, outputs.folder,
                                     title=scenario.description or args.scenario.name)
    names = ["path.csv", "result.json"] + [p.name for p in figures.values()]
    print(f"wrote {out}/: {', '.join(names)}")
    if result.success:
        if bad is not None:
            print(f"drake-social: Drake's check rejects segment {bad} of the path the {args.checker} checker "
                  f"accepted (a bug; exit code {EXIT_UNVERIFIED}); the path is in {out / 'path.csv'}", file=sys.stderr)
            return EXIT_UNVERIFIED
    if not result.success:
        print(f"drake-social: no path from start to goal in {iterations} iterations "
              f"(closest tree node {result.closest_distance_to_goal:.3g} from the goal); "
              f"{out / 'result.json'} has success: false", file=sys.stderr)
        return EXIT_NO_PATH
    return 0


# ---- simulate ------------------------------------------------------------------

#: Exit code of ``simulate`` when the robot did not reach the goal within the time limit.
EXIT_NOT_REACHED = 5
#: Exit code of ``simulate`` when the executed trajectory collides.
EXIT_COLLISION = 6
#: Exit code of ``simulate`` when the executed trajectory, collision-free, passes a joint limit (or a room bound).
EXIT_LIMIT = 7


def _add_simulate(subparsers) -> None:
    from drake_social.scenario import EXECUTIONS, SIM_MODES

    p = subparsers.add_parser(
        "simulate",
        help="plan (or load a path), execute it in a Drake diagram, write a Meshcat replay",
        description="Plans the scenario (or loads --path), executes the path with the waypoint sequencer, the "
        "holonomic P-controller on four mecanum wheels and Ruckig trajectories in Drake's Simulator, checks "
        "the executed trajectory for collisions, integrates its social cost and measures its deviation from "
        "the plan. Writes DIR/replay.html (a standalone Meshcat replay: open it in a browser, no server), "
        "DIR/executed.csv (t,x,y,psi1,psi2 and velocities), DIR/tracking.png (references against actual "
        f"over time) and DIR/sim.json. Exit code {EXIT_NO_PATH} no path, {EXIT_NOT_REACHED} goal not reached "
        f"within execution.time_limit, {EXIT_COLLISION} the executed trajectory collides, {EXIT_LIMIT} it "
        "passes a joint limit or a room bound (files are written in every case; stderr names each finding).",
    )
    _add_scenario_arguments(p)
    p.add_argument("--mode", choices=SIM_MODES,
                   help="kinematic (the base integrates its velocity, fast) or dynamic (the MultibodyPlant "
                        "driven by a computed-torque servo); default: the scenario's execution.mode")
    p.add_argument("--execution", choices=EXECUTIONS,
                   help="synchronized (one phase-synchronized reference per segment, stays on the planned "
                        "segment) or paper (independent base P-control and arm trajectory, the paper's); "
                        "default: the scenario's execution.execution")
    p.add_argument("--path", type=Path, metavar="CSV",
                   help="follow this path (a path.csv of 'drake-social plan': header x,y,psi1,psi2, from the "
                        "scenario's start to its goal, at most 10,000 rows; every waypoint and segment is checked "
                        "with --checker before anything runs) instead of planning; --algorithm, --iterations and "
                        "--seed are then refused")
    _add_planner_arguments(p)
    p.add_argument("--no-replay", action="store_true", help="do not record nor write replay.html (faster)")
    _add_output_arguments(p)
    p.set_defaults(run=_run_simulate)


def read_path_csv(path: Path, scenario: Scenario, checker=None) -> np.ndarray:
    """Reads a ``path.csv`` (header ``x,y,psi1,psi2``) for ``scenario`` and
    checks it as every path to execute is checked
    (:func:`drake_social.waypoints.check_waypoints`).

    Args:
        path: the CSV file.
        scenario: the scenario the path is for.
        checker: the validity checker of the run; None = the exact planar checker.

    Raises:
        ScenarioError: the file is missing or malformed, has fewer than 2 or
            more than :data:`~drake_social.limits.MAX_WAYPOINTS` rows (refused
            at the first row too many), a value is not finite, a waypoint is
            outside the room or the joint limits or in collision, a segment
            collides, or its first and last rows are not the scenario's start
            and goal (to ``waypoints.ENDPOINT_TOLERANCE``); the message names
            the file and the line.
    """
    return _checked_path(path, _parse_path_csv(path), scenario, checker)


def _checked_path(path: Path, parsed: tuple[np.ndarray, list[int]], scenario: Scenario, checker=None) -> np.ndarray:
    """The rows of :func:`_parse_path_csv` checked by :func:`~drake_social.waypoints.check_waypoints`."""
    from drake_social.waypoints import check_waypoints

    if checker is None:
        from drake_social.collision.drake_checker import make_checker

        checker = make_checker(scenario, "planar")
    rows, numbers = parsed
    return check_waypoints(scenario, rows, checker, source=f"{path} (--path)", lines=numbers)


def _parse_path_csv(path: Path) -> tuple[np.ndarray, list[int]]:
    """The rows (N, 4) of a ``path.csv`` and the file line of each (see :func:`read_path_csv`).

    The file may have at most :data:`~drake_social.io.textfile.MAX_PATH_FILE_BYTES`
    bytes; lines end with LF or CRLF (nothing else starts a line); a leading
    UTF-8 byte order mark (as spreadsheets write) is skipped.
    """
    from drake_social.limits import MAX_WAYPOINTS
    from drake_social.io.textfile import MAX_PATH_FILE_BYTES

    text = read_text_file(path, "path", "--path", limit=MAX_PATH_FILE_BYTES).removeprefix("\ufeff")
    lines = [line.removesuffix("\r") for line in text.split("\n")]
    if lines[0].replace(" ", "") != "x,y,psi1,psi2":
        raise ScenarioError(f"{path}: line 1: the header must be 'x,y,psi1,psi2', got {shorten(repr(lines[0]))} "
                            f"(--path)")
    rows = []
    numbers = []  # the file line of each row
    for i, line in enumerate(lines[1:], start=2):
        if not line.strip():
            continue
        if len(rows) == MAX_WAYPOINTS:
            raise ScenarioError(f"{path}: line {i}: more than {MAX_WAYPOINTS:,} waypoints; a path may have at most "
                                f"{MAX_WAYPOINTS:,} (drake_social.limits.MAX_WAYPOINTS) (--path)")
        cells = line.split(",")
        if len(cells) != 4:
            raise ScenarioError(f"{path}: line {i}: needs 4 numbers x,y,psi1,psi2, got {len(cells)} values: "
                                f"{shorten(repr(line))} (--path)")
        values = []
        for column, cell in zip(("x", "y", "psi1", "psi2"), cells):
            try:
                value = float(cell)
            except ValueError:
                value = None
            if value is None or not np.isfinite(value):
                raise ScenarioError(f"{path}: line {i}: {column}: must be a finite number, got "
                                    f"{shorten(repr(cell.strip()))} (--path)")
            values.append(value)
        rows.append(values)
        numbers.append(i)
    if len(rows) < 2:
        raise ScenarioError(f"{path}: needs at least 2 waypoints (start and goal), got {len(rows)} (--path)")
    return np.array(rows), numbers


def _write_executed_csv(path: Path, run) -> None:
    """t, configuration and its velocity per logged sample (17 digits)."""
    table = np.column_stack([run.times, run.q, run.v]) if len(run.times) else np.zeros((0, 9))
    np.savetxt(path, table, delimiter=",", header="t,x,y,psi1,psi2,vx,vy,dpsi1,dpsi2", comments="", fmt="%.17g")


def _listed(names: Sequence[str]) -> str:
    """``a``, ``a and b``, ``a, b and c``."""
    return names[0] if len(names) == 1 else f"{', '.join(names[:-1])} and {names[-1]}"


def _run_simulate(args: argparse.Namespace) -> int:
    from drake_social.io.outputs import OutputSet
    from drake_social.scenario import validate_scenario
    from drake_social.sim.run import run_checked
    from drake_social.viz.tracking import tracking_figure

    planning_only = [f"--{name}" for name in ("algorithm", "iterations", "seed") if getattr(args, name) is not None]
    if args.path is not None and planning_only:
        pronoun = "it" if len(planning_only) == 1 else "them"
        raise ScenarioError(f"{_listed(planning_only)}: only for planning; with --path {args.path} nothing is "
                            f"planned (the path is executed as given): leave {pronoun} out, or leave out --path to plan")
    scenario = load_with_overrides(args.scenario, args.set)
    if planning_only:
        import copy

        scenario = copy.deepcopy(scenario)
        scenario.planner.iterations = args.iterations or scenario.planner.iterations
        scenario.planner.algorithm = args.algorithm or scenario.planner.algorithm
        scenario.random_seed = scenario.random_seed if args.seed is None else args.seed
        validate_scenario(scenario, source=f"{args.scenario} ({_listed(planning_only)})")
    if args.mode is not None:  # the scenario's own mode was checked when it was loaded
        problem = plant_time_step_problem(scenario.execution, args.mode)
        if problem:
            raise ScenarioError(f"{args.scenario} (--mode {args.mode}): {problem[0]}: {problem[1]}")
    out = args.out if args.out is not None else _default_out(args.scenario)
    parsed = _parse_path_csv(args.path) if args.path is not None else None  # a malformed file before the checker
    checker = _make_checker(scenario, args.checker, str(args.scenario))
    waypoints = _checked_path(args.path, parsed, scenario, checker) if parsed is not None else None
    meshcat = None
    if not args.no_replay:
        from drake_social.sim.replay import make_meshcat

        meshcat = make_meshcat()
    limit = scenario.execution.time_limit
    bar = ProgressBar(int(round(limit * 10)), sys.stderr, label="simulating") if _show_progress(args) else None

    def progress(t: float) -> None:
        bar.update(int(t * 10), f"t = {t:.1f} s")

    with OutputSet(out, "simulate", names=SIMULATE_OUTPUTS) as outputs:
        try:
            # The scenario is validated (loaded) and the path checked with the checker above: once.
            opts = scenario.execution
            run = run_checked(scenario, mode=args.mode or opts.mode, execution=args.execution or opts.execution,
                              waypoints=waypoints, checker=checker, meshcat=meshcat, time_limit=float(opts.time_limit),
                              analyze=True, analysis_checker=None,
                              progress=progress if bar is not None else None)
        except PlanningInputError as e:
            raise PlanningInputError(f"{args.scenario}: {e}") from e
        finally:
            if bar is not None:
                bar.close()
        if run.planner is not None:
            print(run.planner.summary())
        print(run.summary())
        names = []
        if meshcat is not None:
            from drake_social.sim.replay import draw_overlays, set_top_view, write_replay_html

            draw_overlays(meshcat, scenario, run.waypoints if len(run.waypoints) else None)
            fit = set_top_view(meshcat, scenario)
            size = write_replay_html(meshcat, outputs.path("replay.html"), fit=fit)
            names.append(f"replay.html ({size / 1e6:.2f} MB)")
        _write_executed_csv(outputs.path("executed.csv"), run)
        e = scenario.execution
        fig = tracking_figure(run, max_base_speed=e.max_base_speed, max_wheel_speed=e.max_wheel_speed,
                              title=f"{scenario.description or args.scenario.name}\n{run.mode} / {run.execution}: "
                                    f"{run.message}")
        fig.savefig(outputs.path("tracking.png"), dpi=130)
        record = {"scenario": str(args.scenario), "overrides": list(args.set or []),
                  "path": None if args.path is None else str(args.path), "checker": args.checker,
                  **run.to_json_dict(), "waypoints": np.asarray(run.waypoints).tolist()}
        outputs.write_text("sim.json", _json_lines(record))
        names += ["executed.csv", "tracking.png", "sim.json"]
    print(f"wrote {out}/: {', '.join(names)}")
    if meshcat is not None:
        # The folder resolved, not the link: the link outlives this run's generation folder.
        print(f"open {(out.resolve() / 'replay.html').as_uri()} in a browser to watch the replay")
    if run.planner is not None and not run.planner.success:
        print(f"drake-social: no path from start to goal ({run.planner.message}); nothing was executed",
              file=sys.stderr)
        return EXIT_NO_PATH
    # Every finding is named; the exit code is the first of: not reached,
    # collision, limit.
    codes = []
    if not run.reached:
        print(f"drake-social: {run.message}", file=sys.stderr)
        codes.append(EXIT_NOT_REACHED)
    if run.report is not None and not run.report.collision_free:
        print(f"drake-social: the executed trajectory collides (first at t = {run.report.first_collision_time:.2f} s)",
              file=sys.stderr)
        codes.append(EXIT_COLLISION)
    if run.report is not None and not run.report.within_limits:
        for violation in run.report.limit_violations:
            print(f"drake-social: the executed trajectory passes {violation.kind}: {violation}", file=sys.stderr)
        codes.append(EXIT_LIMIT)
    return codes[0] if codes else 0


# ---- bench -------------------------------------------------------------------

#: Scenarios of ``drake-social bench`` (relative to the working directory: the repository).
BENCH_SCENARIOS = ("scenarios/office_bar.yaml", "scenarios/generic_L.yaml")


def _add_bench(subparsers) -> None:
    p = subparsers.add_parser(
        "bench",
        help="benchmark the planners over seeds: wall time and social cost (JSON and Markdown)",
        description="Runs every algorithm on every scenario for N seeds and reports the median and spread "
        "of wall time and final social cost; with the ompl package importable, also OMPL's RRTstar on "
        "the same problem (same checks, same cost). Writes JSON and a Markdown table into DIR.",
    )
    p.add_argument("--scenarios", nargs="+", type=Path, metavar="YAML", default=[Path(s) for s in BENCH_SCENARIOS],
                   help=f"scenario files (default: {' '.join(BENCH_SCENARIOS)})")
    p.add_argument("--algorithms", nargs="+", choices=ALGORITHMS, default=list(ALGORITHMS), metavar="A",
                   help=f"planners (default: all of {', '.join(ALGORITHMS)})")
    p.add_argument("--iterations", type=_positive_int, default=2000, metavar="K", help="samples per run (default 2000)")
    p.add_argument("--seeds", type=_int_at_least(1, MAX_BENCH_SEEDS), default=10, metavar="N",
                   help=f"seeds 0..N-1 per planner, at most {MAX_BENCH_SEEDS:,} (default 10)")
    p.add_argument("--repeats", type=_int_at_least(1, MAX_BENCH_REPEATS), default=1, metavar="R",
                   help=f"time each seeded run R times (at most {MAX_BENCH_REPEATS}), ours and OMPL's, and report the "
                        "median (the same path each time: this only filters out the machine's noise; default 1)")
    _add_checker_argument(p, default="planar")
    p.add_argument("--ompl-checker", choices=CHECKERS, default="drake",
                   help="the checker of OMPL's RRTstar (default: drake, Drake's SceneGraph checks as before "
                        "the planar checker); when it is not --checker, OMPL also runs with --checker")
    p.add_argument("--no-ompl", action="store_true", help="leave out OMPL's RRTstar even when ompl is importable")
    p.add_argument("--no-checker-bench", action="store_true",
                   help="leave out the validity-checker throughput measurement")
    p.add_argument("--sim-runs", type=_nonnegative_int, default=3, metavar="N",
                   help="timed simulations per (mode, execution) of the execution benchmark, plus one recorded "
                        "(default 3; 0 leaves it out)")
    p.add_argument("--scaling", action="store_true",
                   help="also the scaling benchmark per scenario (minutes): social_rrt_star at K = 2000 .. 50,000 "
                        "with the shrinking radius and the fitted exponent of time ~ K^b, K = 2000 with "
                        "planner.optimize against the median of three K = 50,000 runs, and 50 people far away")
    p.add_argument("--out", type=Path, default=Path("out/bench"), metavar="DIR",
                   help="output directory (default: out/bench)")
    p.add_argument("--progress", action="store_true",
                   help="draw the progress bar on stderr even when it is not a terminal")
    p.set_defaults(run=_run_bench)


def _run_bench(args: argparse.Namespace) -> int:
    from drake_social.experiments.bench.planners import run_bench
    from drake_social.io.outputs import OutputSet

    for path in args.scenarios:
        check_regular_file(path, "scenario", "--scenarios")
    bar = ProgressBar(1, sys.stderr, label="bench", interval=0.0) if _show_progress(args) else None

    def progress(done: int, total: int, label: str) -> None:
        bar.total = total
        bar.update(done, label)

    with OutputSet(args.out, "bench", names=["bench.json", "bench.md"]) as outputs:  # held over the run: a second bench is refused at once
        try:
            run_bench(
                scenario_paths=list(args.scenarios),
                algorithms=list(args.algorithms),
                iterations=args.iterations,
                seeds=args.seeds,
                checker=args.checker,
                ompl_checker=args.ompl_checker,
                include_ompl=not args.no_ompl,
                include_checker=not args.no_checker_bench,
                sim_runs=args.sim_runs,
                scaling=args.scaling,
                repeats=args.repeats,
                out_dir=outputs.folder,
                progress=progress if bar is not None else None,
            )
        finally:
            if bar is not None:
                bar.close()
    table = args.out / "bench.md"
    if table.is_file():
        print(table.read_text().rstrip())
    print(f"wrote {args.out}/: bench.json, bench.md")
    return 0


# ---- experiment ----------------------------------------------------------------


def _add_experiment(subparsers) -> None:
    from drake_social.experiments.study.executors import EXECUTORS
    from drake_social.experiments.study import MAX_PAPER_RUNS, MAX_STUDY_TASKS, PAPER_PAIRS
    from drake_social.scenario import MAX_ITERATIONS

    p = subparsers.add_parser(
        "experiment",
        help="the paper's studies (or your own sweep) with per-body-part metrics, figures and REPORT.md",
        description="Runs a study (scenarios x algorithms x seeds x overrides) in parallel and writes, as one "
        "output set, DIR/results.csv and DIR/results.json (every run), boxplots, cost-vs-distance and best-path "
        "figures, DIR/REPORT.md (tables and each claim checked by a paired comparison over seeds) and the "
        "Planner Arena files (DIR/arena_<group>.log, DIR/arena.db).",
    )
    kinds = p.add_subparsers(dest="study", metavar="STUDY", required=True)
    paper = kinds.add_parser("paper", help="the paper's Section V: A office_bar, B generic_L, D weight study",
                             description="A: office_bar (bar) and B: generic_L (L object) with RRT*, Social "
                             "Risk-RRT* multi-point and base-only, Informed multi-point and base-only; D: generic_L "
                             "with the 1.5 m bar, Social Risk-RRT* with object, base and equal weights.")
    paper.add_argument("--runs", type=_int_at_least(1, MAX_PAPER_RUNS), default=10, metavar="N",
                       help=f"runs per algorithm, at most {MAX_PAPER_RUNS:,} (the study's {PAPER_PAIRS} group x "
                       f"algorithm pairs x N runs stay within {MAX_STUDY_TASKS:,}; default 10)")
    paper.add_argument("--iterations", type=_int_at_least(1, MAX_ITERATIONS), default=2000, metavar="K",
                       help=f"K, at most {MAX_ITERATIONS:,} (default 2000)")
    paper.add_argument("--seed", type=_nonnegative_int, default=0, metavar="S",
                       help="study seed; run seeds are drawn from it with SeedSequence (default 0)")
    paper.add_argument("--scenario-dir", type=Path, default=Path("scenarios"), metavar="DIR",
                       help="folder of office_bar.yaml and generic_L.yaml (default: scenarios)")
    paper.add_argument("--simulate", action="store_true",
                       help="also execute every path (kinematic simulation) and measure the executed trajectory")
    sweep = kinds.add_parser("sweep", help="your own study from a YAML file (see studies/example_sweep.yaml)")
    sweep.add_argument("config", type=Path, help="the sweep's YAML file")
    for q in (paper, sweep):
        q.add_argument("--out", type=Path, metavar="DIR", help="output directory (default: out/<study name>)")
        q.add_argument("--workers", type=_int_at_least(1, MAX_WORKERS), default=1, metavar="N",
                       help=f"parallel worker processes, at most {MAX_WORKERS} (each holds Drake: a few hundred MB; "
                       "default 1: in this process); results do not depend on it")
        q.add_argument("--executor", choices=EXECUTORS, default="process",
                       help="process (concurrent.futures, default) or dask (the distributed package)")
        q.add_argument("--scheduler", metavar="ADDRESS",
                       help="with --executor dask: a running scheduler, e.g. tcp://10.0.0.5:8786 "
                       "(default: a LocalCluster of --workers processes)")
        q.add_argument("--progress", action="store_true",
                       help="draw the progress bar on stderr even when it is not a terminal")
    p.set_defaults(run=_run_experiment)


def _run_experiment(args: argparse.Namespace) -> int:
    from tqdm import tqdm

    from drake_social.experiments.study import (StudyOutputError, load_sweep, output_names, paper_study,
                                                rescue_records, run_study, write_records, write_study)
    from drake_social.io.outputs import DeferredSignals, OutputSet

    if args.scheduler is not None and args.executor != "dask":
        raise ScenarioError("--scheduler needs --executor dask")
    if args.scheduler is not None:  # before anything runs
        from drake_social.experiments.study.executors import check_scheduler_address

        try:
            check_scheduler_address(args.scheduler)
        except ValueError as e:
            raise ScenarioError(f"--scheduler: {e}") from None
    if args.executor == "dask" and not args.verbose:
        try:  # distributed sets its loggers to INFO on import; keep their chatter for --verbose
            import distributed  # noqa: F401
        except ImportError:
            pass  # map_tasks says what to install
        else:
            logging.getLogger("distributed").setLevel(logging.WARNING)
    if args.study == "paper":
        for name in ("office_bar.yaml", "generic_L.yaml"):
            check_regular_file(args.scenario_dir / name, "scenario", "--scenario-dir")
        study = paper_study(runs=args.runs, iterations=args.iterations, seed=args.seed, simulate=args.simulate,
                            scenario_dir=args.scenario_dir)
    else:
        study = load_sweep(args.config)
    out = args.out if args.out is not None else Path("out") / study.name
    result = None
    failure = None  # the error of an output after the records
    interrupted = False  # Ctrl-C while writing the outputs after the runs
    try:
        # Entered first: a busy --out, or a folder in the way of any of its files, is refused before any run.
        with OutputSet(out, "experiment", names=output_names(study)) as outputs:
            bar = tqdm(total=1, desc=f"experiment {study.name}", unit="run", file=sys.stderr, dynamic_ncols=True,
                       disable=not _show_progress(args))

            def progress(done: int, total: int, record: dict) -> None:
                bar.total = total
                bar.set_postfix_str(f"{record['group']} {record['algorithm']} run {record['run']}", refresh=False)
                bar.update(done - bar.n)

            try:
                result = run_study(study, executor=args.executor, workers=args.workers, scheduler=args.scheduler,
                                   progress=progress)
            finally:
                bar.close()
            try:
                names = write_study(result, outputs.folder)
                outputs.check_names(names)  # a folder in the way of a figure or log: the records alone
            except (Exception, KeyboardInterrupt) as e:  # the finished runs are kept: the set becomes the records alone
                interrupted = isinstance(e, KeyboardInterrupt)
                failure = StudyOutputError("interrupted (Ctrl-C)" if interrupted
                                           else str(e).replace(str(outputs.folder), str(out)))
                # A (further) Ctrl-C here must not lose the finished runs: noted, and the records committed.
                with DeferredSignals() as held:
                    for entry in outputs.folder.iterdir():
                        if entry.is_dir() and not entry.is_symlink():
                            shutil.rmtree(entry)
                        else:
                            entry.unlink()
                    names = write_records(result, outputs.folder)
                interrupted = interrupted or signal.SIGINT in held.received
                for sig in dict.fromkeys(held.received):  # another signal (SIGTERM) as it would have acted
                    if sig != signal.SIGINT:
                        signal.raise_signal(sig)
    except Exception as e:
        if result is None:
            raise
        # Not even the records could be committed into --out: they go elsewhere.
        why = str(e) if failure is None else f"{failure}; then committing the records alone failed: {e}"
        cause = f"writing the study's outputs into {out} failed: {why}"
        try:
            rescued = rescue_records(result)
        except Exception as second:
            raise StudyOutputError(f"{cause}; saving the records of its {_runs(result)} into the temporary "
                                   f"directory failed too: {second}") from e
        raise StudyOutputError(f"{cause}; the records of its {_runs(result)} were saved to "
                               f"{rescued / 'results.json'} and {rescued / 'results.csv'} instead") from e
    where = (f"on the Dask scheduler at {args.scheduler}" if args.scheduler is not None
             else f"{args.workers} worker(s), {args.executor}")
    print(f"{len(result.records)} runs in {result.wall_time:.1f} s ({where})")
    if interrupted:
        print(f"drake-social: experiment interrupted after its {_runs(result)}: their records were written to "
              f"{out / 'results.json'} and {out / 'results.csv'} (the figures, REPORT.md and the arena files were "
              "not written)", file=sys.stderr)
        return 130
    if failure is not None:
        raise StudyOutputError(f"writing the study's outputs into {out} failed: {failure}; the records of its "
                               f"{_runs(result)} are in {out / 'results.json'} and {out / 'results.csv'} (the "
                               "figures, REPORT.md and the arena files were not written)") from failure
    for line in (out / "REPORT.md").read_text().splitlines():
        if line.startswith("- **"):
            print(line)
    print(f"wrote {out}/: {', '.join(names)}")
    return 0


def _runs(result) -> str:
    """"1 run", "12 runs": the number of a study's records."""
    n = len(result.records)
    return f"{n} run{'' if n == 1 else 's'}"


# ---- parser and entry point ----------------------------------------------------

_SUBCOMMANDS: list[Callable] = [_add_show, _add_plan, _add_simulate, _add_bench, _add_experiment]


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
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as e:  # --help, --version or a usage error already printed
        return int(e.code or 0)
    if args.command is None:
        parser.print_help(sys.stderr)
        return 2
    logging.basicConfig(level=logging.INFO if args.verbose else logging.WARNING, format="%(name)s: %(message)s")
    try:  # from here on, Ctrl-C (even while pydrake imports) is one line and exit 130
        if not args.verbose:
            # pydrake sets its "drake" logger to INFO on import; keep its chatter for --verbose.
            import pydrake.common  # noqa: F401  (so that our level is not overwritten later)

            logging.getLogger("drake").setLevel(logging.WARNING)
        if getattr(args, "out", None) is not None:
            _check_out_folder(args.out)
        return args.run(args)
    except (ScenarioError, PlanningInputError) as e:
        print(f"drake-social: error: {e}", file=sys.stderr)
        return 2
    except OSError as e:  # e.g. --out names a file, or a directory without write access
        print(f"drake-social: error: {e}", file=sys.stderr)
        return 1
    except KeyboardInterrupt as e:
        from drake_social.io.outputs import InterruptedAfterCommit

        if isinstance(e, InterruptedAfterCommit):  # Ctrl-C while the set was moved into place
            where = e.committed[0].parent if e.committed else "its folder"
            print(f"drake-social: {args.command} interrupted after its outputs were written to {where}",
                  file=sys.stderr)
        else:
            print(f"drake-social: {args.command} interrupted; no output of this run was written", file=sys.stderr)
        return 130


if __name__ == "__main__":
    sys.exit(main())
