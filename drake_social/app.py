"""The application layer: each command of ``drake-social`` as a function a script can call.

Each ``run_*`` function takes keyword arguments only, does the whole job of
its command (loads the scenario with its overrides, builds the checker, plans
or simulates, verifies, writes the command's files as one output set into
``out``) and returns what a caller needs: the run record
(:mod:`drake_social.io.records`) and the objects behind it. Nothing here
prints; progress goes to an optional callback, errors are exceptions:

* :class:`~drake_social.scenario.ScenarioError`,
  :class:`~drake_social.planning.result.PlanningInputError`: invalid input
  (the message names the file and the field);
* ``OSError``: an output could not be written (another run writing the same
  ``out`` included: :class:`~drake_social.io.outputs.OutputBusyError`);
* ``KeyboardInterrupt``: interrupted; no file of the run is left;
* ``TypeError``, ``ValueError``: an argument of the wrong kind or value,
  refused before any work (the message names the function, the argument and
  what is allowed).

A path that is not found, one that Drake's check rejects, or an execution
that misses the goal, collides or passes a limit are outcomes, not errors:
they are in the returned record (and its files are written).

Example::

    from drake_social.app import run_plan

    run = run_plan(scenario="scenarios/office_bar.yaml", out="out/office_bar", overrides=["random_seed: 3"])
    print(run.record["cost"], run.record["planning_time"], run.record["drake_verified"])
"""

from __future__ import annotations

import copy
import dataclasses as dc
import shutil
import signal
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable, Sequence

import numpy as np

from drake_social.arguments import (Rule, check_arguments, real_array, require_callable, require_checker, require_choice,
                                    require_choices, require_file_name, require_file_names, require_instance,
                                    require_int, require_number, require_scenario, require_scenario_or_file,
                                    require_strings)
from drake_social.io.textfile import check_regular_file, shorten
from drake_social.limits import (ALGORITHMS, CHECKERS, EXECUTORS, MAX_BENCH_REPEATS, MAX_BENCH_REPLAN_COUNT,
                                 MAX_BENCH_RUNS, MAX_BENCH_SEEDS, MAX_ITERATIONS, MAX_PAPER_RUNS, MAX_WORKERS)
from drake_social.scenario import EXECUTIONS, SIM_MODES, Scenario, ScenarioError, compose_yaml, load_scenario

if TYPE_CHECKING:
    from drake_social.experiments.study import CrowdStudy, Study, StudyResult
    from drake_social.experiments.study.recorded import RecordedCrowdStudy
    from drake_social.planning.result import PlannerResult
    from drake_social.sim.results import SimulationResult

__all__ = ["PLAN_OUTPUTS", "SIMULATE_OUTPUTS", "PlanRun", "Progress", "SimulateRun", "StudyRun", "check_scheduler",
           "load_with_overrides", "paper_experiment", "read_path_csv", "run_bench", "run_plan", "run_show",
           "run_simulate", "run_study"]
__all__ += ["PeopleImport", "run_people_import"]
__all__ += ["run_crowd_experiment", "run_recorded_experiment"]

#: The files ``plan`` writes into ``out`` (a folder of such a name is refused before planning).
PLAN_OUTPUTS = ("path.csv", "result.json", "path.png", "cost_profile.png", "convergence.png")
#: The files ``simulate`` may write into ``out`` (replay.html when Meshcat records).
SIMULATE_OUTPUTS = ("replay.html", "executed.csv", "people.csv", "replans.csv", "replans.png", "predictions.png",
                    "path.png", "tracking.png", "motion.png", "sim.json")

#: A progress callback: ``progress(done, total, status)`` (steps done of
#: ``total``, and a short text such as ``"best 5.1"`` or ``"t = 3.2 s"``).
Progress = Callable[[int, int, str], None]


# ---- the arguments: every public function here checks its own at the door --------


def _int(minimum: int, maximum: int | None = None, *, optional: bool = False) -> Rule:
    return lambda v, who, name: require_int(v, who, name, minimum=minimum, maximum=maximum, optional=optional)


def _choice(allowed: tuple[str, ...], *, optional: bool = False) -> Rule:
    return lambda v, who, name: require_choice(v, who, name, allowed, optional=optional)


def _flag(*, optional: bool = False) -> Rule:
    allowed = "True, False" if optional else "True or False"  # the helper adds " or None"
    return lambda v, who, name: require_instance(v, (bool, np.bool_), who, name, allowed, optional=optional)


def _number(**rules) -> Rule:
    return lambda v, who, name: require_number(v, who, name, **rules)


def _file(*, optional: bool = False) -> Rule:
    return lambda v, who, name: require_file_name(v, who, name, optional=optional)


def _study(value, who: str, name: str) -> None:
    from drake_social.experiments.study import KINDS

    require_instance(value, tuple(KINDS), who, name, "a drake_social.experiments.study.Study (paper_experiment(...) "
                                                     "or load_sweep(file)), CrowdStudy or RecordedCrowdStudy")


def _layout(value, who: str, name: str) -> None:
    from drake_social.people.eth_ucy import ETH_UCY_LAYOUTS

    require_choice(value, who, name, tuple(ETH_UCY_LAYOUTS))


_RUN = {"out": _file(), "progress": require_callable}
_SCENARIO = {"scenario": require_scenario_or_file, "overrides": require_strings}
# iterations: at most MAX_ITERATIONS by the scenario's own rule, checked with the planner
# (a ScenarioError naming --iterations, as the command line reports it).
_PLANNER = {"algorithm": _choice(ALGORITHMS, optional=True), "iterations": _int(1, optional=True),
            "seed": _int(0, optional=True), "checker": _choice(CHECKERS)}
_WORKERS = {"executor": _choice(EXECUTORS), "workers": _int(1, MAX_WORKERS),
            "scheduler": lambda v, who, name: require_instance(v, str, who, name, "a scheduler's address, e.g. "
                                                                                  "'tcp://10.0.0.5:8786'", optional=True)}
#: The rule of each argument of each public function of this module (its keyword arguments, run_bench's options).
_ARGUMENTS: dict[str, dict[str, Rule]] = {
    "load_with_overrides": {"path": _file(), "sets": lambda v, who, name: require_strings(v, who, name, optional=True)},
    "read_path_csv": {"path": _file(), "scenario": require_scenario,
                      "checker": lambda v, who, name: require_checker(v, who, name, optional=True),
                      "option": lambda v, who, name: require_instance(v, str, who, name, "a string such as '--path'")},
    "run_show": {**_SCENARIO, "out": _file()},
    "run_plan": {**_SCENARIO, **_RUN, **_PLANNER},
    "run_simulate": {**_SCENARIO, **_RUN, **_PLANNER, "path": _file(optional=True),
                     "mode": _choice(SIM_MODES, optional=True), "execution": _choice(EXECUTIONS, optional=True),
                     "replay": _flag(), "replan": _flag(optional=True)},
    "run_bench": {
        "scenario_paths": require_file_names, **_RUN,
        "algorithms": lambda v, who, name: require_choices(v, who, name, ALGORITHMS, optional=True, distinct=False),
        "iterations": _int(1, MAX_ITERATIONS), "seeds": _int(1, MAX_BENCH_SEEDS), "checker": _choice(CHECKERS),
        "ompl_checker": _choice(CHECKERS), "include_ompl": _flag(), "include_checker": _flag(),
        "sim_runs": _int(0, MAX_BENCH_RUNS), "scaling": _flag(), "repeats": _int(1, MAX_BENCH_REPEATS),
        "replan_runs": _int(0, MAX_BENCH_RUNS), "replan_count": _int(1, MAX_BENCH_REPLAN_COUNT),
        "replan_scenario": _file(optional=True), "map_bench": _flag()},
    "paper_experiment": {"runs": _int(1, MAX_PAPER_RUNS), "iterations": _int(1, MAX_ITERATIONS), "seed": _int(0),
                         "simulate": _flag(), "scenario_dir": _file()},
    "check_scheduler": {"executor": _choice(EXECUTORS), "scheduler": _WORKERS["scheduler"]},
    "run_study": {"study": _study, **_RUN, **_WORKERS},
    "run_people_import": {
        "file": _file(), "out": _file(), "layout": _layout, "fps": _number(positive=True, unit="frames per second"),
        "offset": lambda v, who, name: real_array(v, who, name, (2,), layout="[dx, dy], metres"),
        "rotate": _number(unit="radians"), "start": _number(optional=True, unit="seconds"),
        "end": _number(optional=True, unit="seconds"),
        "ids": lambda v, who, name: require_strings(v, who, name, optional=True), "theta": _flag()},
    "run_crowd_experiment": {**_RUN, **_WORKERS},
    "run_recorded_experiment": {**_RUN, **_WORKERS},
}


def _door(who: str, arguments: dict[str, Any]) -> None:
    """Checks the arguments of the public function ``who`` by :data:`_ARGUMENTS`
    (each calls it first, with ``locals()``: its arguments alone).

    Raises:
        TypeError, ValueError: naming ``who``, the argument and what is allowed.
    """
    check_arguments(who, _ARGUMENTS[who], arguments)


def load_with_overrides(path: str | Path, sets: Sequence[str] | None = None) -> Scenario:
    """Loads a scenario with overrides, as ``--set`` gives them.

    Each text is a YAML mapping applied over the file in turn, e.g.
    ``"random_seed: 3"`` or ``"social: {sigma_h: 1.5}"``; a later one merges
    into what the earlier ones left (``"social: {sigma_h: 1.5}"`` then
    ``"social: {threshold: 0.1}"`` sets both).

    Raises:
        ScenarioError: the file, an override or a value is invalid; the
            message names the ``--set`` at fault.
    """
    _door("load_with_overrides", locals())
    import yaml  # to name the --set at fault before Drake's loader sees it

    texts = list(sets or [])
    for text in texts:
        node = compose_yaml(text, f"{path} (--set {shorten(repr(text))})")
        if not isinstance(node, yaml.MappingNode):
            raise ScenarioError(f"{path} (--set {shorten(repr(text))}): must be a YAML mapping such as "
                                f"'random_seed: 3'")
    return load_scenario(path, texts, overrides_name="--set")


def read_path_csv(path: str | Path, scenario: Scenario, checker=None, option: str = "--path") -> np.ndarray:
    """Reads a path CSV (:func:`drake_social.io.paths.parse_path_csv`) for
    ``scenario`` and checks it as every path to execute is checked
    (:func:`drake_social.waypoints.check_waypoints`).

    Args:
        path: the CSV file (header ``x,y,psi1,psi2``).
        scenario: the scenario the path is for.
        checker: the validity checker of the run; None = the exact planar checker.
        option: the command-line option that named the file, for the messages.

    Returns:
        The waypoints, an (N, 4) float array (metres, radians).

    Raises:
        ScenarioError: the file is missing or malformed, a waypoint is
            outside the room or the joint limits or in collision, a segment
            collides, or its first and last rows are not the scenario's start
            and goal (to ``waypoints.ENDPOINT_TOLERANCE``); the message names
            the file and the line.
    """
    _door("read_path_csv", locals())
    from drake_social.io.paths import parse_path_csv

    return _checked_rows(path, parse_path_csv(path, option), scenario, checker, option)


def _checked_rows(path, parsed, scenario: Scenario, checker=None, option: str = "--path") -> np.ndarray:
    """The ``(rows, lines)`` of :func:`~drake_social.io.paths.parse_path_csv` checked by
    :func:`~drake_social.waypoints.check_waypoints` (None = the planar checker)."""
    from drake_social.waypoints import check_waypoints

    if checker is None:
        from drake_social.collision.drake_checker import make_checker

        checker = make_checker(scenario, "planar")
    rows, lines = parsed
    return check_waypoints(scenario, rows, checker, source=f"{path} ({option})", lines=lines)


def _listed(names: Sequence[str]) -> str:
    """``a``, ``a and b``, ``a, b and c``."""
    return names[0] if len(names) == 1 else f"{', '.join(names[:-1])} and {names[-1]}"


def _scenario(scenario: Scenario | str | Path, overrides: Sequence[str], who: str) -> tuple[Scenario, str, str | None]:
    """The scenario of a ``run_*`` call, its name in messages and its file (None: given as an object).

    Raises:
        ValueError: ``overrides`` with a Scenario object (they apply to a file).
        ScenarioError: the file, an override or a value is invalid.
    """
    from drake_social.scenario import validate_scenario

    if isinstance(scenario, Scenario):
        if overrides:
            raise ValueError(f"{who}: overrides apply to a scenario file; change the Scenario object instead")
        validate_scenario(scenario, source=f"{who}: scenario")
        return scenario, f"{who}: scenario", None
    return load_with_overrides(scenario, overrides), str(scenario), str(scenario)


def _title(scenario: Scenario, file: str | None) -> str:
    return scenario.description or (Path(file).name if file else "scenario")


# ---- show --------------------------------------------------------------------


def run_show(*, scenario: Scenario | str | Path, out: str | Path, overrides: Sequence[str] = ()) -> Path:
    """Draws the scenario (map, people, social-cost heat map, robot at start
    and goal) as ``out/scene.png``; returns that file.

    Args:
        scenario: the scenario YAML file, or a :class:`~drake_social.scenario.Scenario`.
        out: the output folder.
        overrides: ``--set`` texts applied over the file.
    """
    _door("run_show", locals())
    from drake_social.io.outputs import OutputSet
    from drake_social.viz import write_show  # matplotlib figures: only when drawing

    loaded, _, file = _scenario(scenario, overrides, "run_show")
    out = Path(out)
    with OutputSet(out, "show", names=["scene.png"]) as outputs:
        write_show(loaded, outputs.folder, title=_title(loaded, file))
    return out / "scene.png"


# ---- plan --------------------------------------------------------------------


@dc.dataclass
class PlanRun:
    """What :func:`run_plan` did.

    Attributes:
        record: the run record written as ``result.json``
            (:data:`drake_social.io.records.RUN_FIELDS`).
        result: the planner's result (waypoints, tree, anytime curve).
        files: the names of the files written into ``out``, in order.
        rejected_segment: the first segment of the path that Drake's
            independent check rejects (a bug of the checker that planned);
            None when it accepts them all or there is no path.
    """

    record: dict[str, Any]
    result: PlannerResult
    files: list[str]
    rejected_segment: int | None


def _planner_progress(progress: Progress | None, total: int) -> Callable[[int, float], None] | None:
    """The planners' ``progress(iteration, best_cost)`` as a :data:`Progress`."""
    if progress is None:
        return None

    def report(iteration: int, best_cost: float) -> None:
        progress(iteration, total, f"best {best_cost:.4g}" if best_cost < float("inf") else "no path yet")

    return report


def run_plan(*, scenario: Scenario | str | Path, out: str | Path, overrides: Sequence[str] = (), algorithm: str | None = None,
             iterations: int | None = None, seed: int | None = None, checker: str = "planar",
             progress: Progress | None = None) -> PlanRun:
    """Plans the scenario and writes ``out``: path.csv, result.json, path.png,
    cost_profile.png and convergence.png (:data:`PLAN_OUTPUTS`).

    A path the planner returns is checked again by Drake's
    SceneGraphCollisionChecker before anything is written (``drake_verified``).

    Args:
        scenario: the scenario YAML file, or a :class:`~drake_social.scenario.Scenario`
            (validated here; the record's ``scenario`` is then null).
        out: the output folder (created; the files appear together or not at all).
        overrides: ``--set`` texts applied over the file (:func:`load_with_overrides`).
        algorithm, iterations, seed: override the scenario's ``planner.algorithm``,
            ``planner.iterations`` and ``random_seed``.
        checker: the validity checker that plans: planar, drake or numpy.
        progress: optional :data:`Progress` over the iterations.

    Returns:
        A :class:`PlanRun`; ``record["success"]`` is False when no path was found.

    Raises:
        ScenarioError, PlanningInputError: invalid input, named.
        OSError: an output could not be written.
    """
    _door("run_plan", locals())
    from drake_social.collision.drake_checker import make_checker, verify_path
    from drake_social.evaluation.records import run_record
    from drake_social.io.outputs import OutputSet
    from drake_social.io.paths import write_path_csv
    from drake_social.io.records import json_lines
    from drake_social.planning.algorithms import make_objective, plan
    from drake_social.planning.result import PlanningInputError
    from drake_social.scenario import validate_planner_choice
    from drake_social.viz.path import planned_people, write_plan_figures  # matplotlib figures: only when drawing

    loaded, path, file = _scenario(scenario, overrides, "run_plan")
    out = Path(out)
    k = iterations or loaded.planner.iterations
    chosen = [f"--{name}" for name, value in (("algorithm", algorithm), ("iterations", iterations)) if value is not None]
    if chosen:  # the scenario was validated with its own planner options
        validate_planner_choice(loaded, algorithm or loaded.planner.algorithm, k, source=f"{path} ({_listed(chosen)})")
    chk = make_checker(loaded, checker, source=file)
    # Entered before planning: an unwritable or busy out fails early, and
    # nothing of this run lands in out unless all of it does.
    with OutputSet(out, "plan", names=PLAN_OUTPUTS) as outputs:
        try:
            result = plan(loaded, chk, algorithm=algorithm, iterations=k, seed=seed,
                          progress=_planner_progress(progress, k))
        except PlanningInputError as e:
            raise PlanningInputError(f"{path}: {e}") from e
        bad = verify_path(chk, result.waypoints) if result.success else None  # Drake's second opinion
        write_path_csv(outputs.path("path.csv"), result.waypoints)
        record = {
            "scenario": file,
            "overrides": list(overrides or []),
            "checker": checker,
            "iterations": k,
            "drake_verified": (bad is None) if result.success else None,
            **run_record(loaded, result, make_objective(loaded, result.algorithm), history=True),
        }
        outputs.write_text("result.json", json_lines(record))
        # Walkers' tracks over the plan's nominal duration (the path at the execution's speed limits).
        figures = write_plan_figures(loaded, result, outputs.folder, title=_title(loaded, file),
                                     people=planned_people(loaded, result.waypoints))
    return PlanRun(record, result, ["path.csv", "result.json"] + [p.name for p in figures.values()], bad)


# ---- simulate ------------------------------------------------------------------


@dc.dataclass
class SimulateRun:
    """What :func:`run_simulate` did.

    Attributes:
        record: the record written as ``sim.json`` (the execution's summary
            and report, the planner's record under ``planner`` when it planned).
        run: the :class:`~drake_social.sim.results.SimulationResult` (logs, report).
        files: the names of the files written into ``out``, in order.
        replay_bytes: the size of replay.html, bytes (None: no replay).
    """

    record: dict[str, Any]
    run: SimulationResult
    files: list[str]
    replay_bytes: int | None


def run_simulate(*, scenario: Scenario | str | Path, out: str | Path, overrides: Sequence[str] = (),
                 path: str | Path | None = None, mode: str | None = None, execution: str | None = None,
                 algorithm: str | None = None, iterations: int | None = None, seed: int | None = None,
                 checker: str = "planar", replay: bool = True, progress: Progress | None = None,
                 replan: bool | None = None) -> SimulateRun:
    """Plans the scenario (or reads ``path``), executes the path in Drake's
    Simulator and writes ``out``: replay.html (with ``replay``),
    executed.csv, people.csv (when the scenario has people: where they were
    at the logged times), replans.csv (when replanning: one row per replan,
    :func:`~drake_social.io.paths.write_replans_csv`, and replans.png;
    with people too, predictions.png: what the robot predicted,
    :mod:`drake_social.viz.predictions`), tracking.png and
    sim.json (with replanning its ``replanning`` summary).

    Args:
        scenario: the scenario YAML file, or a :class:`~drake_social.scenario.Scenario`.
        out: the output folder.
        overrides: ``--set`` texts applied over the file.
        path: a path CSV to follow instead of planning (checked with
            ``checker`` before anything runs); then ``algorithm``,
            ``iterations`` and ``seed`` are refused.
        mode, execution: override ``execution.mode`` and ``execution.execution``.
        algorithm, iterations, seed: override the planner's, as in :func:`run_plan`.
        checker: the validity checker: planar, drake or numpy.
        replay: record the run in Meshcat and write replay.html.
        progress: optional :data:`Progress` over simulated time (tenths of a second).
        replan: replan while executing (``--replan``); None =
            ``planner.replan`` of the scenario; True with ``path`` is refused.

    Returns:
        A :class:`SimulateRun`: ``run.planner`` failed (no path),
        ``record["reached"]``, ``record["collision_free"]`` and
        ``record["within_limits"]`` are the outcomes.

    Raises:
        ScenarioError, PlanningInputError: invalid input, named.
        OSError: an output could not be written.
    """
    _door("run_simulate", locals())
    import numpy as np

    from drake_social.collision.drake_checker import make_checker
    from drake_social.evaluation.metrics import execution_metrics
    from drake_social.io.json_numbers import finite_or_none
    from drake_social.io.outputs import OutputSet
    from drake_social.io.paths import parse_path_csv, write_executed_csv, write_people_csv, write_replans_csv
    from drake_social.io.records import json_lines
    from drake_social.planning.result import PlanningInputError
    from drake_social.scenario import plant_time_step_problem, replan_rate_problem, validate_scenario
    from drake_social.scenario.geometry import arm_geometry
    from drake_social.sim.run import run_checked
    from drake_social.viz.tracking import tracking_figure

    out = Path(out)
    planning_only = [f"--{name}" for name, value in (("algorithm", algorithm), ("iterations", iterations),
                                                      ("seed", seed)) if value is not None]
    if path is not None and replan:
        raise ScenarioError(f"--replan: replans the path; with --path {path} nothing is planned (the path is "
                            "executed as given): leave out one of them")
    if path is not None and planning_only:
        pronoun = "it" if len(planning_only) == 1 else "them"
        raise ScenarioError(f"{_listed(planning_only)}: only for planning; with --path {path} nothing is "
                            f"planned (the path is executed as given): leave {pronoun} out, or leave out --path to plan")
    loaded, source, file = _scenario(scenario, overrides, "run_simulate")
    if planning_only:
        loaded = copy.deepcopy(loaded)
        loaded.planner.iterations = iterations or loaded.planner.iterations
        loaded.planner.algorithm = algorithm or loaded.planner.algorithm
        loaded.random_seed = loaded.random_seed if seed is None else seed
        validate_scenario(loaded, source=f"{source} ({_listed(planning_only)})")
    if replan and not loaded.planner.replan:  # a scenario that replans was checked as one when it was loaded
        problem = replan_rate_problem(loaded.planner.replan_rate, loaded.execution)
        if problem:
            raise ScenarioError(f"{source} (--replan): planner.replan_rate: {problem}")
    if mode is not None:  # the scenario's own mode was checked when it was loaded
        problem = plant_time_step_problem(loaded.execution, mode)
        if problem:
            raise ScenarioError(f"{source} (--mode {mode}): {problem[0]}: {problem[1]}")
    parsed = parse_path_csv(path) if path is not None else None  # a malformed file before the checker
    chk = make_checker(loaded, checker, source=file)
    waypoints = _checked_rows(path, parsed, loaded, chk) if parsed is not None else None
    meshcat = None
    if replay:
        from drake_social.sim.replay import make_meshcat

        meshcat = make_meshcat()
    opts = loaded.execution
    steps = int(round(opts.time_limit * 10))
    report = None if progress is None else (lambda t: progress(int(t * 10), steps, f"t = {t:.1f} s"))
    with OutputSet(out, "simulate", names=SIMULATE_OUTPUTS) as outputs:
        try:
            # The scenario is validated (loaded) and the path checked with the checker above: once.
            run = run_checked(loaded, mode=mode or opts.mode, execution=execution or opts.execution,
                              waypoints=waypoints, checker=chk, meshcat=meshcat, time_limit=float(opts.time_limit),
                              analyze=True, analysis_checker=None, progress=report,
                              replan=bool(loaded.planner.replan if replan is None else replan) and waypoints is None)
        except PlanningInputError as e:
            raise PlanningInputError(f"{source}: {e}") from e
        files, size = [], None
        if meshcat is not None:
            from drake_social.sim.replay import draw_overlays, set_top_view, write_replay_html

            # Walking people (SimulationResult.people, a PeopleLog) get animated arrows and heat-map quads.
            # With replanning (run.replans not empty) each distinct plan and wait is drawn over its time,
            # with the people its replan predicted and why it began (run.predicted).
            draw_overlays(meshcat, loaded, run.waypoints if len(run.waypoints) else None,
                          people=getattr(run, "people", None), replans=run.replans,
                          predicted=getattr(run, "predicted", ()))
            from drake_social.sim.replay_speed import animate_slow_down

            animate_slow_down(meshcat, run, float(loaded.execution.replay_fps))  # the base's colour: limited, held
            fit = set_top_view(meshcat, loaded)
            size = write_replay_html(meshcat, outputs.path("replay.html"), fit=fit)
            files.append("replay.html")
        write_executed_csv(outputs.path("executed.csv"), run.times, run.q, run.v)
        files.append("executed.csv")
        if run.replanning is not None:
            from drake_social.viz.replans import write_replan_figure

            write_replans_csv(outputs.path("replans.csv"), run.replans)
            write_replan_figure(run, outputs.folder, budget=float(loaded.planner.replan_budget),
                                title=f"{_title(loaded, file)}: replans")
            files += ["replans.csv", "replans.png"]
            if run.people is not None and len(getattr(run, "predicted", ())):
                from drake_social.viz.predictions import write_predictions_figure

                write_predictions_figure(run, loaded, outputs.folder,
                                         title=f"{_title(loaded, file)}: what the robot predicted")
                files.append("predictions.png")
        if run.people is not None:
            write_people_csv(outputs.path("people.csv"), run.people)
            files.append("people.csv")
            if not run.people.static:  # the walkers' tracks with the executed base track
                _write_path_figure(outputs.path("path.png"), loaded, run, _title(loaded, file))
                files.append("path.png")
        fig = tracking_figure(run, max_base_speed=opts.max_base_speed, max_wheel_speed=opts.max_wheel_speed,
                              geometry=arm_geometry(loaded), safety_distance=opts.safety_distance,
                              title=f"{_title(loaded, file)}\n{run.mode} / {run.execution}: {run.message}")
        fig.savefig(outputs.path("tracking.png"), dpi=130)
        _write_motion_figure(outputs.path("motion.png"), loaded, run, _title(loaded, file))
        record = {"scenario": file, "overrides": list(overrides or []),
                  "path": None if path is None else str(path), "checker": checker,
                  **run.to_json_dict(), **finite_or_none(execution_metrics(loaded, run)),
                  "waypoints": np.asarray(run.waypoints).tolist()}
        outputs.write_text("sim.json", json_lines(record))
        files += ["tracking.png", "motion.png", "sim.json"]
    return SimulateRun(record, run, files, size)


def _write_motion_figure(path: Path, scenario: Scenario, run: SimulationResult, title: str) -> None:
    """Writes ``motion.png``: the speed, acceleration and jerk of the base and of the
    object's fastest point over time, with the slow-down's limit and the stops."""
    from drake_social.evaluation.time_series import motion_profile
    from drake_social.scenario.geometry import arm_geometry
    from drake_social.viz.motion import motion_figure

    profiles = {}
    if len(run.times) > 1:
        profiles = {"base": motion_profile(run.times, run.q[:, :2]),
                    "object (fastest point)": motion_profile(
                        run.times, arm_geometry(scenario).interest_points(run.q)[:, 3:])}
    e = scenario.execution
    fig = motion_figure(run.times, profiles, speed_limit=run.speed_limit, stops=run.stops, slow_stops=run.slow_stops,
                        limits=(e.max_base_speed, e.max_base_acceleration, e.max_base_jerk),
                        title=f"{title}\n{run.mode} / {run.execution}: speed, acceleration and jerk")
    fig.savefig(path, dpi=130)


def _write_path_figure(path: Path, scenario: Scenario, run: SimulationResult, title: str) -> None:
    """Writes ``path.png`` of a run among walking people: the path followed (the
    planner's result, or the given path's measures), the people's tracks and
    the executed base track, with common time marks."""
    import numpy as np

    from drake_social.cost import SocialCost
    from drake_social.kinematics import config_distance
    from drake_social.planning.result import PlannerResult
    from drake_social.viz.path import path_figure
    from drake_social.viz.show import MAP_DPI

    result = run.planner
    if result is None:  # the path given with --path, or the path followed while replanning
        wp = np.asarray(run.waypoints, float).reshape(-1, 4)
        cost = float(SocialCost.from_scenario(scenario).motion_cost(wp[:-1], wp[1:]).sum()) if len(wp) > 1 else 0.0
        replanned = run.replanning is not None
        result = PlannerResult(algorithm="replanned path" if replanned else "given path", success=len(wp) >= 2,
                               message="the path followed, replanned" if replanned else "the path given with --path",
                               waypoints=wp, cost=cost, social_cost_full=cost, social_cost_planner=cost,
                               path_length=float(config_distance(wp[:-1], wp[1:]).sum()),
                               base_length=float(np.hypot(*np.diff(wp[:, :2], axis=0).T).sum()))
    fig = path_figure(scenario, result, title=title, people=run.people, executed=(run.times, run.q))
    fig.savefig(path, dpi=MAP_DPI)


# ---- bench -------------------------------------------------------------------


def run_bench(*, scenario_paths: Sequence[str | Path], out: str | Path, progress: Progress | None = None,
              **options: Any) -> dict:
    """Benchmarks the planners (:func:`drake_social.experiments.bench.planners.run_bench`)
    and writes ``out/bench.json`` and ``out/bench.md`` as one output set.

    Args:
        scenario_paths: scenario YAML files (each checked to be a regular file
            first; ``map_bench`` compares the floor with the first).
        out: the output folder.
        progress: optional :data:`Progress` over the runs.
        **options: the other keyword arguments of the bench's ``run_bench``
            (algorithms, iterations, seeds, checker, ompl_checker, include_ompl,
            include_checker, sim_runs, scaling, repeats).

    Returns:
        The bench's dictionary (as ``bench.json`` holds it); its runs are run
        records (:data:`drake_social.io.records.RUN_FIELDS`).
    """
    _door("run_bench", {"scenario_paths": scenario_paths, "out": out, "progress": progress, **options})
    for path in scenario_paths:
        check_regular_file(path, "scenario", "--scenarios")
    if options.get("replan_runs", 0) > 0 and options.get("replan_scenario") is None:
        from drake_social.experiments.bench.replanning import REPLAN_SCENARIO

        check_regular_file(REPLAN_SCENARIO, "scenario", "--replan-runs")  # shipped: absent from a wheel install
    from drake_social.experiments.bench.planners import run_bench as bench
    from drake_social.io.outputs import OutputSet

    # Held over the run: a second bench into the same folder is refused at once.
    with OutputSet(out, "bench", names=["bench.json", "bench.md"]) as outputs:
        result = bench(scenario_paths=list(scenario_paths), **options, out_dir=outputs.folder,
                                 progress=progress)
    return result


# ---- experiment ----------------------------------------------------------------


@dc.dataclass
class StudyRun:
    """What :func:`run_study` did.

    Attributes:
        result: the :class:`~drake_social.experiments.study.StudyResult` (every run's or episode's record).
        files: the names of the files written into ``out``.
        interrupted: Ctrl-C came while the outputs after the records were
            written: only the records were committed.
        failure: the error of an output after the records (then only the
            records were committed), or None.
    """

    result: StudyResult | None
    files: list[str]
    interrupted: bool = False
    failure: Exception | None = None

    @property
    def runs(self) -> str:
        """"1 run", "12 runs", "40 episodes": the number of the study's records."""
        from drake_social.experiments.study import count

        return count(self.result.study, len(self.result.records))

    @property
    def record_files(self) -> tuple[str, str]:
        """The names of the records' CSV and JSON files (results.csv and
        results.json; a crowd study's records.csv and records.json)."""
        from drake_social.experiments.study import record_files

        return record_files(self.result.study)


def paper_experiment(*, runs: int, iterations: int, seed: int, simulate: bool, scenario_dir: str | Path) -> Study:
    """The paper's study (:func:`drake_social.experiments.study.paper_study`),
    its two scenario files checked first."""
    _door("paper_experiment", locals())
    from drake_social.experiments.study import paper_study

    for name in ("office_bar.yaml", "generic_L.yaml"):
        check_regular_file(Path(scenario_dir) / name, "scenario", "--scenario-dir")
    return paper_study(runs=runs, iterations=iterations, seed=seed, simulate=simulate, scenario_dir=scenario_dir)


def check_scheduler(executor: str, scheduler: str | None) -> None:
    """Refuses a Dask scheduler address without the dask executor, or a malformed one.

    Raises:
        ScenarioError: ``--scheduler: ...`` naming what is wrong.
    """
    _door("check_scheduler", locals())
    if scheduler is not None and executor != "dask":
        raise ScenarioError("--scheduler needs --executor dask")
    if scheduler is not None:
        from drake_social.experiments.study.executors import check_scheduler_address

        try:
            check_scheduler_address(scheduler)
        except ValueError as e:
            raise ScenarioError(f"--scheduler: {e}") from None


def run_study(*, study: Study | CrowdStudy | RecordedCrowdStudy, out: str | Path, executor: str = "process", workers: int = 1,
              scheduler: str | None = None, progress: Callable[[int, int, dict], None] | None = None) -> StudyRun:
    """Runs a study and writes its outputs into ``out`` as one output set:
    for a planning study results.csv and results.json (every run's record),
    the figures, REPORT.md and the Planner Arena files; for a crowd study
    records.csv and records.json (every episode's), the figures and REPORT.md.

    When an output after the records fails (or Ctrl-C comes while they are
    written), the records alone are committed and the returned
    :class:`StudyRun` says so (``failure``, ``interrupted``).

    Args:
        study: a :class:`~drake_social.experiments.study.Study`
            (:func:`paper_experiment`, ``load_sweep(file)``) or a
            :class:`~drake_social.experiments.study.crowd.CrowdStudy`.
        out: the output folder.
        executor, workers, scheduler: where the runs go
            (:func:`~drake_social.experiments.study.executors.map_tasks`).
        progress: optional ``progress(done, total, record)`` after each run.

    Raises:
        ScenarioError: ``scheduler`` without the dask executor, or a
            malformed address; the study or one of its scenarios is invalid
            (before ``out`` is taken).
        StudyOutputError: not even the records could be committed into
            ``out`` (the message says where they were saved instead).
    """
    _door("run_study", locals())
    from drake_social.experiments.study import (StudyOutputError, kind_of, output_names, rescue_records,
                                                write_records, write_study)
    from drake_social.experiments.study import run_study as run_tasks
    from drake_social.io.outputs import DeferredSignals, OutputSet

    check_scheduler(executor, scheduler)
    out = Path(out)
    done = StudyRun(None, [])
    tasks = kind_of(study).tasks(study)  # every scenario loaded and checked before out is taken
    try:
        # Entered before any run: a busy out, or a folder in the way of any of its files, is refused first.
        with OutputSet(out, "experiment", names=output_names(study)) as outputs:
            done.result = run_tasks(study, tasks=tasks, executor=executor, workers=workers, scheduler=scheduler,
                                    progress=progress)
            try:
                done.files = write_study(done.result, outputs.folder)
                outputs.check_names(done.files)  # a folder in the way of a figure or log: the records alone
            except (Exception, KeyboardInterrupt) as e:  # the finished runs are kept: the set becomes the records
                done.interrupted = isinstance(e, KeyboardInterrupt)
                done.failure = StudyOutputError("interrupted (Ctrl-C)" if done.interrupted
                                                else str(e).replace(str(outputs.folder), str(out)))
                # A (further) Ctrl-C here must not lose the finished runs: noted, and the records committed.
                with DeferredSignals() as held:
                    for entry in outputs.folder.iterdir():
                        if entry.is_dir() and not entry.is_symlink():
                            shutil.rmtree(entry)
                        else:
                            entry.unlink()
                    done.files = write_records(done.result, outputs.folder)
                done.interrupted = done.interrupted or signal.SIGINT in held.received
                for sig in dict.fromkeys(held.received):  # another signal (SIGTERM) as it would have acted
                    if sig != signal.SIGINT:
                        signal.raise_signal(sig)
    except Exception as e:
        if done.result is None:
            raise
        # Not even the records could be committed into out: they go elsewhere.
        why = str(e) if done.failure is None else f"{done.failure}; then committing the records alone failed: {e}"
        cause = f"writing the study's outputs into {out} failed: {why}"
        try:
            rescued = rescue_records(done.result)
        except Exception as second:
            raise StudyOutputError(f"{cause}; saving the records of its {done.runs} into the temporary "
                                   f"directory failed too: {second}") from e
        csv_name, json_name = done.record_files
        raise StudyOutputError(f"{cause}; the records of its {done.runs} were saved to "
                               f"{rescued / json_name} and {rescued / csv_name} instead") from e
    if done.interrupted:
        done.failure = None
    return done


@dc.dataclass(frozen=True)
class PeopleImport:
    """What ``people import`` wrote."""

    out: Path  #: the people CSV
    rows: int  #: data rows written
    id_count: int  #: distinct ids (people)
    duration: float  #: the time the rows span, seconds: last row's t minus first row's t
    first: float  #: t of the first row, seconds (0 unless --start is before the first kept row)
    last: float  #: t of the last row, seconds


def run_people_import(*, file: str | Path, out: str | Path, layout: str = "xy", fps: float = 25.0,
                      offset: Sequence[float] = (0.0, 0.0), rotate: float = 0.0, start: float | None = None,
                      end: float | None = None, ids: Sequence[str] | None = None, theta: bool = True) -> PeopleImport:
    """Converts an ETH/UCY recording into a people CSV (``people import``);
    the conversion and its options: :mod:`drake_social.people.eth_ucy`.

    The CSV is written atomically: into a temporary file beside ``out``,
    then renamed over it (a reader sees the old file or the whole new one).

    Raises:
        ScenarioError: the recording or an option is invalid (the message
            names the file and the line), or ``out`` exists and is not a
            regular file (a directory, FIFO, device: never replaced).
        OSError: ``out`` could not be written.
    """
    _door("run_people_import", locals())
    from drake_social.io.textfile import check_out_file, read_text_file, replace_file
    from drake_social.people import eth_ucy

    check_out_file(out, "--out")  # before any work: a directory, FIFO or device there is not replaced
    text = read_text_file(file, "recording", limit=eth_ucy.MAX_RECORDING_BYTES)
    recording = eth_ucy.parse_eth_ucy(text, str(file), layout)
    rows = eth_ucy.convert(recording, fps=fps, offset=offset, rotate=rotate, start=start, end=end, ids=ids)
    data = eth_ucy.people_csv_text(rows, theta=theta).encode()
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    replace_file(out, lambda f: f.write(data), "--out")
    first, last = rows[0][0], rows[-1][0]  # the rows are sorted by time
    return PeopleImport(out, len(rows), len({r[1] for r in rows}), last - first, first, last)


# ---- experiment crowd ---------------------------------------------------------------


def run_crowd_experiment(*, out: str | Path, executor: str = "process", workers: int = 1,
                         scheduler: str | None = None, progress: Callable[[int, int, dict], None] | None = None,
                         **settings) -> StudyRun:
    """The closed-loop crowd study (``drake-social experiment crowd``): a
    :class:`~drake_social.experiments.study.crowd.CrowdStudy` of ``settings``
    (scenarios, variants, episodes, seed, jitter, time_limit), run and
    written into ``out`` as :func:`run_study` runs and writes any study:
    records.csv and records.json (every episode's record), the per-part
    boxplots and snapshots of every scenario, and REPORT.md.

    Returns:
        A :class:`StudyRun`: ``failure`` and ``interrupted`` say when the
        records alone were committed.

    Raises:
        TypeError, ValueError: an argument or setting of the wrong kind or
            out of range (:data:`~drake_social.experiments.study.crowd.CROWD_SETTINGS`), named.
        ScenarioError: a scenario file, or the time limit for it, is invalid.
        StudyOutputError: as :func:`run_study`.
    """
    _door("run_crowd_experiment", {"out": out, "executor": executor, "workers": workers, "scheduler": scheduler,
                                   "progress": progress})
    from drake_social.experiments.study.crowd import DEFAULT_SCENARIOS, CrowdStudy, check_crowd_settings

    check_crowd_settings("run_crowd_experiment", settings)
    check_scheduler(executor, scheduler)
    for i, s in enumerate(settings.get("scenarios", DEFAULT_SCENARIOS)):  # the shipped ones: absent from a wheel
        check_regular_file(s, "scenario", f"--scenarios[{i}]")
    study = CrowdStudy(**settings)
    return run_study(study=study, out=out, executor=executor, workers=workers, scheduler=scheduler, progress=progress)


def run_recorded_experiment(*, out: str | Path, executor: str = "process", workers: int = 1,
                            scheduler: str | None = None, progress: Callable[[int, int, dict], None] | None = None,
                            **settings) -> StudyRun:
    """The recorded-crowd benchmark (``drake-social experiment crowd
    --recording``): a
    :class:`~drake_social.experiments.study.recorded.RecordedCrowdStudy` of
    ``settings`` (recording, layout, fps, windows, window_length,
    min_people, variants, prediction, sets, episodes, seed, time_limit),
    run and written into ``out`` as :func:`run_study` runs and writes any
    study: records.csv and records.json, each window's scenario and people
    file, the boxplots, each window's snapshots and REPORT.md.

    Returns:
        A :class:`StudyRun`: ``failure`` and ``interrupted`` say when the
        records alone were committed.

    Raises:
        TypeError, ValueError: an argument or setting of the wrong kind or
            out of range (:data:`~drake_social.experiments.study.recorded.RECORDED_SETTINGS`), named.
        ScenarioError: the recording cannot be read or is too short, has
            too few windows dense enough, or a window's scenario with the
            overrides is invalid (before ``out`` is taken).
        StudyOutputError: as :func:`run_study`.
    """
    _door("run_recorded_experiment", {"out": out, "executor": executor, "workers": workers, "scheduler": scheduler,
                                      "progress": progress})
    from drake_social.experiments.study.recorded import RecordedCrowdStudy, check_recorded_settings

    check_recorded_settings("run_recorded_experiment", settings)
    check_scheduler(executor, scheduler)
    if "recording" not in settings:
        raise TypeError("run_recorded_experiment: recording (the ETH/UCY file) is required")
    check_regular_file(settings["recording"], "recording", "--recording")
    study = RecordedCrowdStudy(**settings)
    return run_study(study=study, out=out, executor=executor, workers=workers, scheduler=scheduler, progress=progress)
