"""The arguments of ``drake-social``: one ``_add_<name>(subparsers)`` per
subcommand declares its options, their types, bounds and help texts;
:func:`build_parser` assembles them. What each subcommand does with them is
:mod:`drake_social.cli` (and the library's :mod:`drake_social.app`).
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Callable

from drake_social import __version__
from drake_social.io.textfile import shorten
from drake_social.limits import (MAX_BENCH_REPEATS, MAX_BENCH_REPLAN_COUNT, MAX_BENCH_RUNS, MAX_BENCH_SEEDS,
                                 MAX_ITERATIONS, MAX_JITTER, MAX_TIME_LIMIT, MAX_WORKERS)
from drake_social.scenario import ALGORITHMS, CHECKERS
from drake_social.scenario.shipped import SHIPPED_SCENARIOS, shipped_scenario

# The bounds of the options (their home: drake_social.limits), named here too for scripts that read them.
__all__ = ["MAX_BENCH_REPEATS", "MAX_BENCH_SEEDS", "MAX_WORKERS", "build_parser"]


def _add_scenario_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("scenario", type=Path, help="scenario YAML file, e.g. scenarios/office_bar.yaml")
    parser.add_argument(
        "--set",
        action="append",
        metavar="YAML",
        help="override scenario fields with a YAML mapping, e.g. \"social: {sigma_h: 1.5}\" "
        "(repeatable: applied in turn, each merging into the result of the earlier ones)",
    )


def _add_show(subparsers) -> None:
    p = subparsers.add_parser(
        "show",
        help="draw the scenario: map, people, social-cost heat map, robot at start and goal",
        description="Writes DIR/scene.png: the map, obstacles, people with facing arrows, the social-cost "
        "heat map with its colour bar, and the robot with arm and object at start and goal.",
    )
    _add_scenario_arguments(p)
    p.add_argument("--out", type=Path, metavar="DIR", help="output directory (default: out/<scenario name>)")


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


def _add_simulate(subparsers) -> None:
    from drake_social.scenario import EXECUTIONS, SIM_MODES

    p = subparsers.add_parser(
        "simulate",
        help="plan (or load a path), execute it in a Drake diagram, write a Meshcat replay",
        description="Plans the scenario (or loads --path), executes the path with the waypoint sequencer, the "
        "holonomic P-controller on four mecanum wheels and Ruckig trajectories in Drake's Simulator, checks "
        "the executed trajectory for collisions, integrates its social cost and measures its deviation from "
        "the plan. Writes DIR/replay.html (a standalone Meshcat replay: open it in a browser, no server), "
        "DIR/executed.csv (t,x,y,psi1,psi2 and velocities), DIR/replans.csv (with --replan: one row per "
        "replan), DIR/people.csv (t,id,x,y,theta,v: where the "
        "people were, when the scenario has people), DIR/path.png (when people move: their tracks and the "
        "executed base track), DIR/tracking.png (references against actual "
        "over time), DIR/motion.png (speed, acceleration and jerk, the slow-down near people) and DIR/sim.json. "
        "Exit code 3 no path, 5 goal not reached "
        "within execution.time_limit, 6 the executed trajectory collides, 7 it "
        "passes a joint limit or a room bound (files are written in every case; stderr names each finding).",
    )
    _add_scenario_arguments(p)
    p.add_argument("--mode", choices=SIM_MODES,
                   help="kinematic (the base integrates its velocity, fast) or dynamic (the MultibodyPlant "
                        "driven by a computed-torque servo); default: the scenario's execution.mode")
    p.add_argument("--execution", choices=EXECUTIONS,
                   help="synchronized (one jerk-limited reference along the planned segments, at rest only "
                        "where the path turns, slowing down near people) or paper (independent base P-control "
                        "and arm trajectory, the paper's); "
                        "default: the scenario's execution.execution")
    p.add_argument("--replan", action="store_true", default=None,
                   help="replan while executing: every 1/planner.replan_rate s from the robot's configuration "
                        "among the predicted people (within planner.replan_budget s each); the robot waits when "
                        "no path is safe. Writes DIR/replans.csv (t,plan_time,cost,changed,status,searched,iterations,"
                        "deadline_hit) and sim.json's replanning summary; default: the scenario's planner.replan")
    p.add_argument("--path", type=Path, metavar="CSV",
                   help="follow this path (a path.csv of 'drake-social plan': header x,y,psi1,psi2, from the "
                        "scenario's start to its goal, at most 10,000 rows; every waypoint and segment is checked "
                        "with --checker before anything runs) instead of planning; --algorithm, --iterations and "
                        "--seed are then refused")
    _add_planner_arguments(p)
    p.add_argument("--no-replay", action="store_true", help="do not record nor write replay.html (faster)")
    _add_output_arguments(p)


#: Scenarios of ``drake-social bench``: shipped files, found beside the package whatever the working folder.
BENCH_SCENARIOS = ("office_bar.yaml", "generic_L.yaml")


def _add_bench(subparsers) -> None:
    p = subparsers.add_parser(
        "bench",
        help="benchmark the planners over seeds: wall time and social cost (JSON and Markdown)",
        description="Runs every algorithm on every scenario for N seeds and reports the median and spread "
        "of wall time and final social cost; with the ompl package importable, also OMPL's RRTstar on "
        "the same problem (same checks, same cost). Writes JSON and a Markdown table into DIR.",
    )
    p.add_argument("--scenarios", nargs="+", type=Path, metavar="YAML",
                   default=[shipped_scenario(s) for s in BENCH_SCENARIOS],
                   help=f"scenario files; --map compares its floor with the first (default: the shipped "
                        f"{' '.join(BENCH_SCENARIOS)} in {SHIPPED_SCENARIOS})")
    p.add_argument("--algorithms", nargs="+", choices=ALGORITHMS, default=list(ALGORITHMS), metavar="A",
                   help=f"planners (default: all of {', '.join(ALGORITHMS)})")
    p.add_argument("--iterations", type=_int_at_least(1, MAX_ITERATIONS), default=2000, metavar="K",
                   help=f"samples per run, at most {MAX_ITERATIONS:,} (default 2000)")
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
    p.add_argument("--sim-runs", type=_int_at_least(0, MAX_BENCH_RUNS), default=3, metavar="N",
                   help=f"timed simulations per (mode, execution) of the execution benchmark, plus one recorded, "
                        f"at most {MAX_BENCH_RUNS} (default 3; 0 leaves it out)")
    p.add_argument("--scaling", action="store_true",
                   help="also the scaling benchmark per scenario (minutes): social_rrt_star at K = 2000 .. 50,000 "
                        "with the shrinking radius and the fitted exponent of time ~ K^b, K = 2000 with "
                        "planner.optimize against the median of three K = 50,000 runs, and 50 people far away")
    p.add_argument("--replan-runs", type=_int_at_least(0, MAX_BENCH_RUNS), default=0, metavar="N",
                   help="also the replanning benchmark on the shipped office_walkers.yaml: replan times over a "
                        "kinematic rollout (--replan-count replans) and the realtime factor of N simulated "
                        f"kinematic runs with 10 Hz replanning, at most {MAX_BENCH_RUNS} (default 0: left out)")
    p.add_argument("--map", dest="map_bench", action="store_true",
                   help="also the building-map benchmark: a generated 30 x 50 m floor at 0.03 m (ragged walls, "
                        "thousands of boxes): loading, the checker, K plans against the first --scenarios file, "
                        "and the replay of the executed path")
    p.add_argument("--replan-count", type=_int_at_least(1, MAX_BENCH_REPLAN_COUNT), default=200, metavar="R",
                   help=f"replans of the replanning benchmark's rollout, at most {MAX_BENCH_REPLAN_COUNT:,} "
                        "(default 200)")
    p.add_argument("--out", type=Path, default=Path("out/bench"), metavar="DIR",
                   help="output directory (default: out/bench)")
    p.add_argument("--progress", action="store_true",
                   help="draw the progress bar on stderr even when it is not a terminal")


def _add_experiment(subparsers) -> None:
    from drake_social.limits import EXECUTORS, MAX_ITERATIONS, MAX_PAPER_RUNS, MAX_STUDY_TASKS, PAPER_PAIRS

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
    paper.add_argument("--scenario-dir", type=Path, default=SHIPPED_SCENARIOS, metavar="DIR",
                       help=f"folder of office_bar.yaml and generic_L.yaml (default: the shipped ones in "
                            f"{SHIPPED_SCENARIOS})")
    paper.add_argument("--simulate", action="store_true",
                       help="also execute every path (kinematic simulation) and measure the executed trajectory")
    sweep = kinds.add_parser("sweep", help="your own study from a YAML file (see studies/example_sweep.yaml)")
    sweep.add_argument("config", type=Path, help="the sweep's YAML file")
    crowd = kinds.add_parser(
        "crowd", help="closed loop among walking people: plan-once against 10 Hz replanning, N seeded episodes",
        description="Runs N seeded closed-loop episodes (kinematic) per scenario and variant: plan_once (the "
        "paper's Social Risk-RRT*, planned at t = 0), replan_base (replanning, base-only), replan_multi "
        "(replanning, multi-point) and replan_speed (replan_multi with speed-scaled AGF). Episode k's seed sets "
        "random_seed (planner, crowd speeds) and delays each scripted walker's start by up to --jitter seconds; "
        "the same for every variant (paired). Writes DIR/records.csv, DIR/records.json, per-part boxplots, "
        "snapshots of an episode and DIR/REPORT.md (paired claim lines and the issue's targets). With --recording "
        "FILE, the recorded-crowd benchmark instead: windows of an ETH/UCY recording with the flow turned across the "
        "robot's task, start and goal outside the flow, plan_once against replan (the replanner's defaults) paired "
        "over (window, episode); it also writes each window's scenario (DIR/window_<k>.yaml and its people file).")
    _add_crowd_arguments(crowd)
    for q in (paper, sweep, crowd):
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


def _add_crowd_arguments(crowd: argparse.ArgumentParser) -> None:
    from drake_social.limits import CROWD_SCENARIOS as DEFAULT_SCENARIOS, MAX_EPISODES, RECORDED_VARIANTS as VARIANTS

    source = crowd.add_mutually_exclusive_group()
    source.add_argument("--scenarios", type=Path, nargs="+",
                        default=[shipped_scenario(s) for s in DEFAULT_SCENARIOS],
                        metavar="FILE", help=f"scenario files with walking people (default: the shipped "
                                             f"{' '.join(DEFAULT_SCENARIOS)} in {SHIPPED_SCENARIOS})")
    source.add_argument("--recording", type=Path, metavar="FILE",
                        help="instead of scenarios: the recorded-crowd benchmark on windows of this ETH/UCY "
                             "recording (frame id x y [vx vy], as people import reads it; docs/crowd_study.md)")
    crowd.add_argument("--episodes", type=_int_at_least(1, MAX_EPISODES), metavar="N",
                       help="seeded episodes per scenario (or window) and variant (default 20; with --recording 1)")
    crowd.add_argument("--variants", nargs="+", choices=list(VARIANTS), metavar="NAME", action=_Distinct,
                       help=f"variants to run, of {', '.join(VARIANTS)} (default: all but replan; with "
                            "--recording: plan_once replan; replan, the replanner with its defaults, needs "
                            "--recording)")
    crowd.add_argument("--seed", type=_nonnegative_int, default=0, metavar="S",
                       help="study seed; episode seeds are drawn from it with SeedSequence (default 0)")
    crowd.add_argument("--jitter", type=_float_in(0.0, MAX_JITTER), metavar="SECONDS",
                       help=f"largest start delay of a scripted walker, seconds, at most {MAX_JITTER:g} (default 5; "
                            "not with --recording)")
    crowd.add_argument("--time-limit", type=_float_in(0.0, MAX_TIME_LIMIT, open_low=True), metavar="SECONDS",
                       help=f"simulated seconds per episode, at most {MAX_TIME_LIMIT:g} (default: each scenario's "
                            "execution.time_limit; with --recording the window's length)")
    _add_recorded_arguments(crowd)


def _add_recorded_arguments(crowd: argparse.ArgumentParser) -> None:
    """The options of ``experiment crowd --recording`` (each needs it)."""
    from drake_social.limits import MAX_WINDOWS, MIN_WINDOW_LENGTH
    from drake_social.scenario import PREDICTIONS

    group = crowd.add_argument_group("the recorded-crowd benchmark (with --recording)")
    group.add_argument("--layout", choices=("xy", "xzy"),
                       help="the recording's columns: xy = frame id x y [vx vy] (default), xzy = frame id x z y "
                            "[vx vz vy]")
    group.add_argument("--fps", type=_positive_float, help="frames per second, t = frame / fps (default 25)")
    group.add_argument("--windows", type=_int_at_least(1, MAX_WINDOWS), metavar="N",
                       help=f"windows to cut, at most {MAX_WINDOWS:,}: the densest first, not overlapping (default 5)")
    group.add_argument("--window-length", type=_float_in(MIN_WINDOW_LENGTH, MAX_TIME_LIMIT), metavar="SECONDS",
                       help=f"seconds of each window, in [{MIN_WINDOW_LENGTH:g}, {MAX_TIME_LIMIT:g}] (default 60)")
    group.add_argument("--min-people", type=_int_at_least(1), metavar="N",
                       help="the least number of people present in a window, on average over it (default 1)")
    group.add_argument("--prediction", choices=PREDICTIONS,
                       help="planner.prediction of the replanning variants (default: the scenario's default)")
    group.add_argument("--set", dest="sets", action="append", metavar="YAML",
                       help="override fields of every window's scenario with a YAML mapping, before the variant's, "
                            "e.g. \"planner: {replan_horizon: 2.0}\" (repeatable)")


def _finite_float(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a number, got {shorten(repr(text))}") from None
    if value != value or value in (float("inf"), float("-inf")):
        raise argparse.ArgumentTypeError(f"must be a finite number, got {shorten(text)}")
    return value


class _Distinct(argparse.Action):
    """A list option whose values may each be given once."""

    def __call__(self, parser, namespace, values, option_string=None):
        twice = [v for i, v in enumerate(values) if v in values[:i]]
        if twice:
            raise argparse.ArgumentError(self, f"{shorten(repr(twice[0]))} given twice: each at most once")
        setattr(namespace, self.dest, values)


def _float_in(low: float, high: float, *, open_low: bool = False) -> Callable[[str], float]:
    """A finite number in [low, high] (or (low, high] when ``open_low``)."""
    allowed = f"a number in {'(' if open_low else '['}{low:g}, {high:g}]"

    def parse(text: str) -> float:
        value = _finite_float(text)
        if not ((value > low if open_low else value >= low) and value <= high):
            raise argparse.ArgumentTypeError(f"must be {allowed}, got {shorten(text)}")
        return value

    return parse


def _positive_float(text: str) -> float:
    value = _finite_float(text)
    if not value > 0:
        raise argparse.ArgumentTypeError(f"must be a number > 0, got {shorten(text)}")
    return value


def _add_people(subparsers) -> None:
    p = subparsers.add_parser("people", help="people files: import a recorded pedestrian data set",
                              description="Tools for the people of a scenario (people_file).")
    actions = p.add_subparsers(dest="people_command", metavar="ACTION", required=True)
    imp = actions.add_parser(
        "import", help="convert an ETH/UCY recording (frame id x y [vx vy]) into a people CSV (t,id,x,y,theta)",
        description="Reads rows 'frame id x y [vx vy]' (tabs or spaces; --layout xzy: 'frame id x z y [vx vz vy]'), "
        "t = frame / fps; keeps --ids and the window --start .. --end (inclusive, seconds of the recording), "
        "re-bases time so that the window starts at t = 0, rotates about the origin by --rotate, then adds "
        "--offset; writes t,id,x,y,theta (theta: the direction of motion) sorted by time.")
    imp.add_argument("file", type=Path, help="the recording, e.g. biwi_eth.txt or obsmat.txt")
    imp.add_argument("--out", dest="csv_out", type=Path, required=True, metavar="CSV",
                     help="the people CSV to write (replaced atomically)")
    imp.add_argument("--layout", choices=("xy", "xzy"), default="xy",
                     help="columns: xy = frame id x y [vx vy] (default), xzy = frame id x z y [vx vz vy]")
    imp.add_argument("--fps", type=_positive_float, default=25.0,
                     help="frames per second, t = frame / fps (default 25)")
    imp.add_argument("--offset", type=_finite_float, nargs=2, default=(0.0, 0.0), metavar=("DX", "DY"),
                     help="added to every position after the rotation, metres (default 0 0)")
    imp.add_argument("--rotate", type=_finite_float, default=0.0, metavar="RAD",
                     help="rotation about the origin, radians counter-clockwise, before the offset (default 0)")
    imp.add_argument("--start", type=_finite_float, metavar="S", help="window start, seconds (default: the first row)")
    imp.add_argument("--end", type=_finite_float, metavar="S", help="window end, seconds (default: the last row)")
    imp.add_argument("--ids", nargs="+", metavar="ID", help="keep only these ids (each must be in the file)")
    imp.add_argument("--no-theta", action="store_true", help="write t,id,x,y only (no heading column)")


def _add_map(subparsers) -> None:
    p = subparsers.add_parser("map", help="occupancy-grid maps (ROS map_server YAML + image): inspect, start a scenario",
                              description="Tools for a scenario's world.map: a ROS map_server map (a YAML file "
                              "naming a PGM, PNG or BMP image, its resolution, origin and thresholds).")
    actions = p.add_subparsers(dest="map_command", metavar="ACTION", required=True)
    inspect = actions.add_parser(
        "inspect", help="print a map's size, extent, cells and boxes, and draw it (DIR/map.png)",
        description="Reads the map as map_server does, decomposes its occupied (and unknown) cells into boxes, "
        "prints the grid's size, extent, cell counts and box count, and writes DIR/map.png: the cells under "
        "the boxes' outlines.")
    inspect.add_argument("map", type=Path, help="the map's YAML file, e.g. scenarios/maps/office_floor.yaml")
    inspect.add_argument("--out", type=Path, metavar="DIR", help="output directory (default: out/<map name>)")
    inspect.add_argument("--unknown", choices=("obstacle", "free"), default="obstacle",
                         help="unknown cells are obstacles (default, as in a scenario) or free")
    scenario = actions.add_parser(
        "scenario", help="write a scenario around a map: the bar carried from --start to --goal",
        description="Writes a scenario YAML naming the map (relative to the scenario file), with the robot "
        "carrying the 1.5 m bar from --start to --goal and no people yet. It is loaded and checked first: a "
        "start or goal in an occupied or unknown cell, or with the arm or bar in a box, is refused. Then: "
        "drake-social plan FILE.")
    scenario.add_argument("map", type=Path, help="the map's YAML file")
    scenario.add_argument("--start", type=_finite_float, nargs=2, required=True, metavar=("X", "Y"),
                          help="the base's start position, metres (world frame)")
    scenario.add_argument("--goal", type=_finite_float, nargs=2, required=True, metavar=("X", "Y"),
                          help="the base's goal position, metres")
    scenario.add_argument("--arm", type=_finite_float, nargs=2, default=(-1.2292, 2.8), metavar=("PSI1", "PSI2"),
                          help="the arm's joints at start and goal, radians (default -1.2292 2.8: the carrying "
                          "pose, the bar along x beside the base)")
    scenario.add_argument("--unknown", choices=("obstacle", "free"), default="obstacle",
                          help="world.unknown: unknown cells are obstacles (default) or free")
    scenario.add_argument("--seed", type=_int_at_least(0), default=0, help="random_seed (default 0)")
    scenario.add_argument("--out", dest="scenario_out", type=Path, required=True, metavar="FILE",
                          help="the scenario file to write (.yaml; written atomically)")
    scenario.add_argument("--force", action="store_true", help="replace FILE when it exists")


def build_parser() -> argparse.ArgumentParser:
    """The argument parser with every subcommand; ``args.command`` names the one chosen."""
    parser = argparse.ArgumentParser(
        prog="drake-social",
        description="Socially-aware object transport by a planar mobile manipulator, built on Drake.",
    )
    parser.add_argument("--version", action="version", version=f"%(prog)s {__version__}")
    parser.add_argument("-v", "--verbose", action="store_true", help="log progress (INFO level)")
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND")
    for add in (_add_show, _add_plan, _add_simulate, _add_bench, _add_experiment, _add_people, _add_map):
        add(subparsers)
    return parser
