"""The ``drake-social`` command: argument parsing over :mod:`drake_social.app`.

Each subcommand is a pair of functions: ``_add_<name>(subparsers)`` declares
its arguments and sets ``run`` to ``_run_<name>(args) -> int``, which calls
the app function of the same name, prints its outcome and returns the exit
code. Add a subcommand by writing such a pair and listing ``_add_<name>`` in
:data:`_SUBCOMMANDS`.

Usage::

    drake-social show scenarios/office_bar.yaml --out out/office_bar
    drake-social show scenarios/tiny.yaml --set "social: {sigma_h: 1.5}"
    drake-social plan scenarios/office_bar.yaml --algorithm social_rrt_star --out out/office_bar
    drake-social simulate scenarios/tiny.yaml --mode dynamic --execution paper --path out/tiny/path.csv
    drake-social bench --seeds 10 --out out/bench

Exit codes: 0 success; 1 an output could not be written (also when another
run of the same command is writing into the same ``--out``: refused at once,
writing nothing); 2 bad command line or invalid input (the message names the
file and the field); 3 no path (``plan``, ``simulate``); 4 ``plan``'s path is
rejected by Drake's independent check (a bug of the checker that planned it;
stderr names the segment); 5 ``simulate`` did not reach the goal within
``execution.time_limit``; 6 its executed trajectory collides; 7 it passes a
joint limit or a room bound (the first of 5, 6, 7 that holds; stderr names
each); 130 interrupted (Ctrl-C): one line says what, and no file of the
interrupted run is left (outputs are written as one set, see
:mod:`drake_social.io.outputs`). ``plan`` and ``simulate`` write their files
in every case but 1, 2 and 130.
"""

from __future__ import annotations

import argparse
import logging
import sys
from pathlib import Path
from typing import Callable, Sequence

import matplotlib

from drake_social import __version__, app
from drake_social.app import load_with_overrides  # noqa: F401  (the library's --set loader, for scripts)
from drake_social.cli_progress import BarProgress, ProgressBar  # noqa: F401  (ProgressBar: the bar itself)
from drake_social.io.paths import read_path_csv  # noqa: F401  (the --path reader)
from drake_social.io.textfile import shorten
from drake_social.planning.result import PlanningInputError
from drake_social.scenario import ALGORITHMS, CHECKERS, ScenarioError

__all__ = ["EXIT_NO_PATH", "ProgressBar", "main", "build_parser", "load_with_overrides"]

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
#: Exit code when no path reaches the goal.
EXIT_NO_PATH = 3
#: Exit code of ``plan`` when Drake's verification rejects the returned path (a bug, not bad input).
EXIT_UNVERIFIED = 4
#: Exit code of ``simulate`` when the robot did not reach the goal within the time limit.
EXIT_NOT_REACHED = 5
#: Exit code of ``simulate`` when the executed trajectory collides.
EXIT_COLLISION = 6
#: Exit code of ``simulate`` when the executed trajectory, collision-free, passes a joint limit (or a room bound).
EXIT_LIMIT = 7


def _add_scenario_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("scenario", type=Path, help="scenario YAML file, e.g. scenarios/office_bar.yaml")
    parser.add_argument(
        "--set",
        action="append",
        metavar="YAML",
        help="override scenario fields with a YAML mapping, e.g. \"social: {sigma_h: 1.5}\" "
        "(repeatable: applied in turn, each merging into the result of the earlier ones)",
    )


def _out(args: argparse.Namespace) -> Path:
    """``--out``, or ``out/<scenario name>``."""
    return args.out if args.out is not None else Path("out") / args.scenario.stem


def _bar(args: argparse.Namespace, label: str, interval: float = 0.1) -> BarProgress | None:
    """The progress bar on stderr, with ``--progress`` or on a terminal."""
    return BarProgress(sys.stderr, label, interval) if args.progress or sys.stderr.isatty() else None


def _with_bar(bar: BarProgress | None, call: Callable, **kwargs):
    """``call(progress=bar, **kwargs)``, the bar's line ended afterwards (also on an error or Ctrl-C)."""
    try:
        return call(progress=bar, **kwargs)
    finally:
        if bar is not None:
            bar.close()


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
    print(f"wrote {app.run_show(scenario=args.scenario, out=_out(args), overrides=args.set or ())}")
    return 0


# ---- plan --------------------------------------------------------------------


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
    p.set_defaults(run=_run_plan)


def _run_plan(args: argparse.Namespace) -> int:
    out = _out(args)
    run = _with_bar(_bar(args, "planning"), app.run_plan, scenario=args.scenario, out=out, overrides=args.set or (),
                    algorithm=args.algorithm, iterations=args.iterations, seed=args.seed, checker=args.checker)
    print(run.result.summary())
    print(f"wrote {out}/: {', '.join(run.files)}")
    if run.rejected_segment is not None:
        print(f"drake-social: Drake's check rejects segment {run.rejected_segment} of the path the {args.checker} "
              f"checker accepted (a bug; exit code {EXIT_UNVERIFIED}); the path is in {out / 'path.csv'}",
              file=sys.stderr)
        return EXIT_UNVERIFIED
    if not run.result.success:
        print(f"drake-social: no path from start to goal in {run.record['iterations']} iterations (closest tree "
              f"node {run.result.closest_distance_to_goal:.3g} from the goal); {out / 'result.json'} has success: "
              "false", file=sys.stderr)
        return EXIT_NO_PATH
    return 0


# ---- simulate ------------------------------------------------------------------


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


def _run_simulate(args: argparse.Namespace) -> int:
    out = _out(args)
    done = _with_bar(_bar(args, "simulating"), app.run_simulate, scenario=args.scenario, out=out,
                     overrides=args.set or (), path=args.path, mode=args.mode, execution=args.execution,
                     algorithm=args.algorithm, iterations=args.iterations, seed=args.seed, checker=args.checker,
                     replay=not args.no_replay)
    run = done.run
    if run.planner is not None:
        print(run.planner.summary())
    print(run.summary())
    names = [f"{n} ({done.replay_bytes / 1e6:.2f} MB)" if n == "replay.html" else n for n in done.files]
    print(f"wrote {out}/: {', '.join(names)}")
    if done.replay_bytes is not None:
        # The folder resolved, not the link: the link outlives this run's generation folder.
        print(f"open {(out.resolve() / 'replay.html').as_uri()} in a browser to watch the replay")
    if run.planner is not None and not run.planner.success:
        print(f"drake-social: no path from start to goal ({run.planner.message}); nothing was executed",
              file=sys.stderr)
        return EXIT_NO_PATH
    codes = []  # every finding is named; the exit code is the first of: not reached, collision, limit
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
    _with_bar(_bar(args, "bench", interval=0.0), app.run_bench, scenario_paths=list(args.scenarios), out=args.out,
              algorithms=list(args.algorithms), iterations=args.iterations, seeds=args.seeds, checker=args.checker,
              ompl_checker=args.ompl_checker, include_ompl=not args.no_ompl,
              include_checker=not args.no_checker_bench, sim_runs=args.sim_runs, scaling=args.scaling,
              repeats=args.repeats)
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
    from drake_social.experiments.study import StudyOutputError, load_sweep

    app.check_scheduler(args.executor, args.scheduler)  # before anything is read or run
    if args.executor == "dask" and not args.verbose:
        try:  # distributed sets its loggers to INFO on import; keep their chatter for --verbose
            import distributed  # noqa: F401
        except ImportError:
            pass  # map_tasks says what to install
        else:
            logging.getLogger("distributed").setLevel(logging.WARNING)
    if args.study == "paper":
        study = app.paper_experiment(runs=args.runs, iterations=args.iterations, seed=args.seed,
                                     simulate=args.simulate, scenario_dir=args.scenario_dir)
    else:
        study = load_sweep(args.config)
    out = args.out if args.out is not None else Path("out") / study.name
    bar = None

    def progress(done: int, total: int, record: dict) -> None:
        nonlocal bar
        if bar is None:  # drawn from the first finished run: a refused --out draws nothing
            from tqdm import tqdm

            bar = tqdm(total=total, desc=f"experiment {study.name}", unit="run", file=sys.stderr, dynamic_ncols=True)
        bar.total = total
        bar.set_postfix_str(f"{record['group']} {record['algorithm']} run {record['run']}", refresh=False)
        bar.update(done - bar.n)

    try:
        done = app.run_study(study=study, out=out, executor=args.executor, workers=args.workers,
                             scheduler=args.scheduler, progress=progress if args.progress or sys.stderr.isatty() else None)
    finally:
        if bar is not None:
            bar.close()
    where = (f"on the Dask scheduler at {args.scheduler}" if args.scheduler is not None
             else f"{args.workers} worker(s), {args.executor}")
    print(f"{len(done.result.records)} runs in {done.result.wall_time:.1f} s ({where})")
    if done.interrupted:
        print(f"drake-social: experiment interrupted after its {done.runs}: their records were written to "
              f"{out / 'results.json'} and {out / 'results.csv'} (the figures, REPORT.md and the arena files were "
              "not written)", file=sys.stderr)
        return 130
    if done.failure is not None:
        raise StudyOutputError(f"writing the study's outputs into {out} failed: {done.failure}; the records of its "
                               f"{done.runs} are in {out / 'results.json'} and {out / 'results.csv'} (the figures, "
                               "REPORT.md and the arena files were not written)") from done.failure
    for line in (out / "REPORT.md").read_text().splitlines():
        if line.startswith("- **"):
            print(line)
    print(f"wrote {out}/: {', '.join(done.files)}")
    return 0


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
    try:  # from here on, Ctrl-C (even while pydrake imports) is one line and exit 130
        if not args.verbose:
            # pydrake sets its "drake" logger to INFO on import; keep its chatter for --verbose.
            import pydrake.common  # noqa: F401  (so that our level is not overwritten later)

            logging.getLogger("drake").setLevel(logging.WARNING)
        if getattr(args, "out", None) is not None:
            from drake_social.io.outputs import check_out_folder

            check_out_folder(args.out)
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
