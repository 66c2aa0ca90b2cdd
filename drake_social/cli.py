"""The ``drake-social`` command: the arguments (:mod:`drake_social.cli_parser`) to :mod:`drake_social.app`.

Each subcommand ``<name>`` is ``_add_<name>(subparsers)`` in
:mod:`drake_social.cli_parser` (its options) and ``_run_<name>(args) -> int``
here, which calls the app function, prints the outcome and returns the exit
code. Add a subcommand by writing such a pair and listing it in
``cli_parser.build_parser`` and :data:`_RUNS`.

Usage::

    drake-social show scenarios/office_bar.yaml --out out/office_bar
    drake-social show scenarios/tiny.yaml --set "social: {sigma_h: 1.5}"
    drake-social plan scenarios/office_bar.yaml --algorithm social_rrt_star --out out/office_bar
    drake-social simulate scenarios/tiny.yaml --mode dynamic --execution paper --path out/tiny/path.csv
    drake-social bench --seeds 10 --out out/bench
    drake-social people import biwi_eth.txt --out people.csv --rotate 1.5708 --offset 2 1 --start 0 --end 60
    drake-social map inspect scenarios/maps/office_floor.yaml
    drake-social map scenario lab_map.yaml --start 1 2 --goal 14 6 --out lab.yaml

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
import atexit
import gc
import logging
import sys
from pathlib import Path
from typing import Callable, Sequence

from drake_social import app
from drake_social.app import load_with_overrides, read_path_csv  # noqa: F401  (where scripts found them)
from drake_social.cli_parser import MAX_BENCH_REPEATS, MAX_BENCH_SEEDS, MAX_WORKERS, build_parser  # noqa: F401
from drake_social.cli_progress import BarProgress, ProgressBar  # noqa: F401  (ProgressBar: the bar itself)
from drake_social.planning.result import PlanningInputError
from drake_social.scenario import CHECKERS, ScenarioError  # noqa: F401  (CHECKERS: the --checker choices)

__all__ = ["EXIT_NO_PATH", "ProgressBar", "main", "build_parser", "load_with_overrides"]


def _skip_the_last_collection() -> None:
    """A command's process would end with a garbage collection over every
    object that numba, Drake and matplotlib made (about 1 s); the OS frees
    them anyway. Not when OMPL is loaded: its nanobind bindings would report
    the objects left as leaks."""
    if "ompl" not in sys.modules:
        gc.freeze()


atexit.register(_skip_the_last_collection)

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


def _run_show(args: argparse.Namespace) -> int:
    print(f"wrote {app.run_show(scenario=args.scenario, out=_out(args), overrides=args.set or ())}")
    return 0


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


def _run_simulate(args: argparse.Namespace) -> int:
    out = _out(args)
    done = _with_bar(_bar(args, "simulating"), app.run_simulate, scenario=args.scenario, out=out,
                     overrides=args.set or (), path=args.path, mode=args.mode, execution=args.execution,
                     algorithm=args.algorithm, iterations=args.iterations, seed=args.seed, checker=args.checker,
                     replay=not args.no_replay, replan=args.replan)
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


def _run_bench(args: argparse.Namespace) -> int:
    _with_bar(_bar(args, "bench", interval=0.0), app.run_bench, scenario_paths=list(args.scenarios), out=args.out,
              algorithms=list(args.algorithms), iterations=args.iterations, seeds=args.seeds, checker=args.checker,
              ompl_checker=args.ompl_checker, include_ompl=not args.no_ompl,
              include_checker=not args.no_checker_bench, sim_runs=args.sim_runs, scaling=args.scaling,
              repeats=args.repeats, replan_runs=args.replan_runs, replan_count=args.replan_count,
              map_bench=args.map_bench)
    table = args.out / "bench.md"
    if table.is_file():
        print(table.read_text().rstrip())
    print(f"wrote {args.out}/: bench.json, bench.md")
    return 0


#: ``experiment crowd``'s options of the recorded-crowd benchmark: argument name -> option.
_RECORDED_OPTIONS = {"layout": "--layout", "fps": "--fps", "windows": "--windows", "window_length": "--window-length",
                     "min_people": "--min-people", "prediction": "--prediction", "sets": "--set"}


def _crowd_settings(args: argparse.Namespace) -> dict:
    """``experiment crowd``'s study settings: those of a crowd study over
    scenario files, or with ``--recording`` those of the recorded-crowd benchmark.

    Raises:
        ScenarioError: an option of the one given with the other.
    """
    from drake_social.limits import CROWD_VARIANTS

    if args.recording is None:
        given = [option for name, option in _RECORDED_OPTIONS.items() if getattr(args, name) is not None]
        if given:
            raise ScenarioError(f"{given[0]}: needs --recording (the recorded-crowd benchmark)")
        if args.variants is not None and "replan" in args.variants:
            raise ScenarioError(f"--variants: replan needs --recording; a crowd study over --scenarios runs "
                                f"{', '.join(CROWD_VARIANTS)}")
        return {"scenarios": tuple(str(s) for s in args.scenarios),
                "variants": tuple(args.variants) if args.variants is not None else CROWD_VARIANTS,
                "episodes": 20 if args.episodes is None else args.episodes, "seed": args.seed,
                "jitter": 5.0 if args.jitter is None else args.jitter, "time_limit": args.time_limit}
    if args.jitter is not None:
        raise ScenarioError("--jitter: not with --recording (a recording has no scripted walkers to delay)")
    settings = {"recording": str(args.recording), "name": f"crowd_{args.recording.stem}", "seed": args.seed,
                "time_limit": args.time_limit}
    for name, value in (("variants", args.variants), ("episodes", args.episodes),
                        *((n, getattr(args, n)) for n in _RECORDED_OPTIONS)):
        if value is not None:
            settings[name] = tuple(value) if isinstance(value, list) else value
    return settings


def _run_experiment(args: argparse.Namespace) -> int:
    from drake_social.experiments.study import KINDS, CrowdStudy, StudyOutputError, kind_of, load_sweep
    from drake_social.experiments.study.recorded import RecordedCrowdStudy

    app.check_scheduler(args.executor, args.scheduler)  # before anything is read or run
    if args.executor == "dask" and not args.verbose:
        try:  # distributed sets its loggers to INFO on import; keep their chatter for --verbose
            import distributed  # noqa: F401
        except ImportError:
            pass  # map_tasks says what to install
        else:
            logging.getLogger("distributed").setLevel(logging.WARNING)
    if args.study == "crowd":  # the study is made of the options by run_crowd_experiment or run_recorded_experiment
        settings = _crowd_settings(args)
        recorded = "recording" in settings
        study_name = settings["name"] if recorded else CrowdStudy.name
        kind = KINDS[RecordedCrowdStudy if recorded else CrowdStudy]
    else:
        if args.study == "paper":
            study = app.paper_experiment(runs=args.runs, iterations=args.iterations, seed=args.seed,
                                         simulate=args.simulate, scenario_dir=args.scenario_dir)
        else:
            study = load_sweep(args.config)
        study_name, kind = study.name, kind_of(study)
    out = args.out if args.out is not None else Path("out") / study_name
    bar = None

    def progress(done: int, total: int, record: dict) -> None:
        nonlocal bar
        if bar is None:  # drawn from the first finished task: a refused --out draws nothing
            from tqdm import tqdm

            bar = tqdm(total=total, desc=f"experiment {study_name}", unit=kind.unit, file=sys.stderr,
                       dynamic_ncols=True)
        bar.total = total
        bar.set_postfix_str(kind.describe(record), refresh=False)
        bar.update(done - bar.n)

    where = {"out": out, "executor": args.executor, "workers": args.workers, "scheduler": args.scheduler,
             "progress": progress if args.progress or sys.stderr.isatty() else None}
    try:
        if args.study == "crowd":
            run = app.run_recorded_experiment if recorded else app.run_crowd_experiment
            done = run(**where, **settings)
        else:
            done = app.run_study(study=study, **where)
    finally:
        if bar is not None:
            bar.close()
    on = (f"on the Dask scheduler at {args.scheduler}" if args.scheduler is not None
          else f"{args.workers} worker(s), {args.executor}")
    print(f"{done.runs} in {done.result.wall_time:.1f} s ({on})")
    csv_name, json_name = done.record_files
    if done.interrupted:
        print(f"drake-social: experiment interrupted after its {done.runs}: their records were written to "
              f"{out / json_name} and {out / csv_name} ({kind.later_outputs} were not written)", file=sys.stderr)
        return 130
    if done.failure is not None:
        raise StudyOutputError(f"writing the study's outputs into {out} failed: {done.failure}; the records of its "
                               f"{done.runs} are in {out / json_name} and {out / csv_name} ({kind.later_outputs} were "
                               "not written)") from done.failure
    for line in (out / "REPORT.md").read_text().splitlines():
        if line.startswith("- **"):
            print(line)
    print(f"wrote {out}/: {', '.join(done.files)}")
    return 0


_RUNS: dict[str, Callable[[argparse.Namespace], int]] = {
    "show": _run_show, "plan": _run_plan, "simulate": _run_simulate, "bench": _run_bench, "experiment": _run_experiment}


def _run_people(args: argparse.Namespace) -> int:
    done = app.run_people_import(file=args.file, out=args.csv_out, layout=args.layout, fps=args.fps,
                                 offset=tuple(args.offset), rotate=args.rotate, start=args.start, end=args.end,
                                 ids=args.ids, theta=not args.no_theta)
    print(f"wrote {done.out}: {done.rows} rows, {done.id_count} people, {done.duration:g} s "
          f"(t = {done.first:g} .. {done.last:g} s)")
    return 0


_RUNS["people"] = _run_people


def _run_map(args: argparse.Namespace) -> int:
    from drake_social import map_tools

    if args.map_command == "inspect":
        out = args.out if args.out is not None else Path("out") / args.map.stem
        summary = map_tools.inspect_map(args.map, out, unknown=args.unknown)
        print("\n".join(summary.lines()))
        return 0
    written = map_tools.write_map_scenario(args.map, args.scenario_out, args.start, args.goal, unknown=args.unknown,
                                           arm=args.arm, seed=args.seed, force=args.force)
    print(f"wrote {written.path}: the bar carried from ({args.start[0]:g}, {args.start[1]:g}) to "
          f"({args.goal[0]:g}, {args.goal[1]:g}) through {args.map}; next: drake-social plan {written.path}")
    print("\n".join(written.lines()))
    return 0


_RUNS["map"] = _run_map


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
            from drake_social.io.outputs import check_out_folder

            check_out_folder(args.out)
        return _RUNS[args.command](args)
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
