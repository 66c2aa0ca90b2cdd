"""The compiled tree loop's glue: when it can run, its inputs, its loading, its chunks.

:func:`compiled_support` decides from declared capabilities whether a
configuration can run compiled: the checker declares a compiled scene
(:class:`~drake_social.collision.validity.CompiledSceneChecker`), the
objective a compiled form (:attr:`~drake_social.planning.objective.Objective.compiled_form`).
:func:`prepare` packs the inputs into a :class:`~.tree_kernel.GrowParams`
(building the people grid) and has numba load, or compile, every kernel
the run calls on a throwaway tree, so that :meth:`CompiledRun.run`, which
the planner times, is the search alone. Where numba's on-disk cache was
cold, one warning says that the kernels were compiled and how long that took
(``make install`` fills the cache: :mod:`drake_social.warmup`).

The timed mode (the replanner's: node times, the social cost against the
predicted people, their safety; :class:`~.tree_kernel.TimedParams`) is
packed by :func:`timed_params`; :meth:`CompiledRun.run` also seeds the tree
with a warm start's path and stops at a wall-clock deadline.
"""

from __future__ import annotations

import logging
import math
import time
from typing import Callable, NamedTuple

import numba
import numpy as np

from drake_social.collision import people_kernel, planar_kernel
from drake_social.collision.validity import CompiledSceneChecker
from drake_social.cost import kernel as cost_kernel
from drake_social.cost import timed_kernel
from drake_social.interrupts import DeferredSignals
from drake_social.people import prediction_kernel
from drake_social.planning.objective import Objective
from drake_social.planning.rrt_star import tree_kernel
from drake_social.planning.rrt_star.options import RrtStarOptions
from drake_social.planning.rrt_star.tree_kernel import (GrowParams, InformedParams, ObjectiveParams, PeopleGrid,
                                                       SocialParams, TimedParams)
from drake_social.planning.sampling import EllipseSampler
from drake_social.planning.space import ConfigurationSpace

__all__ = ["CHUNK", "DEADLINE_CHUNK", "PROGRESS_CHUNK", "STATIC", "CompiledRun", "CompiledTree", "cache_misses",
           "compiled_support", "kernel_dispatchers", "prepare", "timed_params"]

_log = logging.getLogger(__name__)

#: Iterations per call of the compiled loop (Ctrl-C is noticed between calls).
CHUNK = 1024
#: ... and with a progress callback (called after each call, for each of its iterations).
PROGRESS_CHUNK = 64
#: ... and with a deadline: the first call's length, and the shortest (the deadline is
#: checked after each call; later calls take about half the time left, as measured,
#: since each call costs some 0.4 ms of argument passing).
DEADLINE_CHUNK = 16

#: The timed mode off: the static loop (bit for bit as without a timed mode).
STATIC = TimedParams(False, 0.0, 1.0, np.ones(2), np.zeros((1, 0, 2)), np.zeros((1, 0)), np.zeros((1, 0), bool),
                     0.0, 1.0, np.zeros(0), np.zeros(0), 0.0, 1)

_cold_cache_reported = False


def compiled_support(checker, objective: Objective, options: RrtStarOptions) -> tuple[bool, str]:
    """Whether the compiled loop can plan this configuration, and why not.

    The checker must declare a compiled scene (the validity protocol's
    :class:`~drake_social.collision.validity.CompiledSceneChecker`), the
    objective a compiled form, and a social objective must use the
    compiled social cost; both samplers (uniform, informed) and both radius
    modes are compiled.

    Returns:
        ``(True, "")``, or ``(False, reason)`` with the reason in words.
    """
    if not options.compiled:
        return False, "RrtStarOptions.compiled is False (the Python reference loop was asked for)"
    if not tree_kernel.AVAILABLE:
        return False, "numba is not importable"
    if not isinstance(checker, CompiledSceneChecker):
        return False, (f"the checker {type(checker).__name__} declares no compiled_scene() "
                       "(the validity protocol's CompiledSceneChecker capability)")
    form = getattr(objective, "compiled_form", None)
    if form not in ("length", "social"):
        return False, f"the objective {type(objective).__name__} declares no compiled form (compiled_form = {form!r})"
    if form == "social" and objective.social.backend != "numba":
        return False, f"the social cost's backend is {objective.social.backend!r}, not 'numba'"
    return True, ""


def kernel_dispatchers() -> dict[str, object]:
    """Every compiled function of the kernels the planner calls, by
    ``module.function`` (numba dispatchers; empty without numba)."""
    out = {}
    for module in (cost_kernel, timed_kernel, prediction_kernel, planar_kernel, people_kernel, tree_kernel):
        for name, value in vars(module).items():
            if hasattr(value, "stats") and hasattr(value, "signatures"):
                out[f"{module.__name__}.{name}"] = value
    return out


def cache_misses() -> int:
    """How many compilations this process made because numba's on-disk cache
    lacked them (summed over :func:`kernel_dispatchers`)."""
    return sum(sum(d.stats.cache_misses.values()) for d in kernel_dispatchers().values())


def _social_params(objective: Objective) -> tuple[int, SocialParams, PeopleGrid]:
    """The objective's kind (0 length, 1 social), its social inputs and people grid."""
    f = np.ascontiguousarray
    if objective.compiled_form == "social":
        sc = objective.social
        social = SocialParams(f(sc.people), *map(float, sc.geometry.link_lengths), f(sc.geometry.object_interest, float),
                              f(sc._active, np.int64), f(sc._active_weights), f(sc._lever, float), sc.resolution,
                              *(f(v, float) for v in sc.person_parameters()), float(sc.space.threshold))
        g = sc._people_grid()
        grid = PeopleGrid(float(g[0]), float(g[1]), float(g[2]), float(g[3]), int(g[4]), int(g[5]),
                          f(g[6], np.int64), f(g[7], np.int64))
        return 1, social, grid
    social = SocialParams(np.zeros((0, 3)), 0.0, 0.0, np.zeros((0, 2)), np.zeros(0, np.int64), np.zeros(0),
                          np.zeros(2), 1.0, np.zeros(0), np.zeros(0), np.zeros(0), np.zeros(0), 0.0)
    grid = PeopleGrid(0.0, 1.0, 0.0, 0.0, 1, 1, np.zeros(2, np.int64), np.zeros(0, np.int64))
    return 0, social, grid


def timed_params(prediction, execution_options, t_root: float, safety: float,
                 safety_horizon: float = math.inf) -> TimedParams:
    """The timed mode's inputs (:class:`~.tree_kernel.TimedParams`, enabled).

    Args:
        prediction: the people over the horizon
            (:class:`drake_social.people.prediction.Prediction`).
        execution_options: the scenario's ``execution``
            (:class:`~drake_social.scenario.schema.ExecutionOptions`): its
            ``max_base_speed`` and ``arm_max_velocity`` give the node times
            (:func:`drake_social.kinematics.nominal_durations`).
        t_root: the root's time (the replan's time), seconds.
        safety: a motion is invalid where the robot comes within this many
            metres of a considered person (``execution.safety_distance``);
            a negative value relaxes the check (tests use it to compare with
            the static loop).
        safety_horizon: seconds of the prediction the safety check considers
            (:meth:`~drake_social.people.prediction.Prediction.until`; the
            cost looks at all of it).

    Raises:
        ValueError: a non-finite ``t_root`` or ``safety``, or speeds not > 0, named.
    """
    if not math.isfinite(t_root):
        raise ValueError(f"timed_params: t_root must be a finite time in seconds, got {t_root!r}")
    if not math.isfinite(safety):
        raise ValueError(f"timed_params: safety must be a finite distance in metres, got {safety!r}")
    base_speed = float(execution_options.max_base_speed)
    arm_speed = np.ascontiguousarray(execution_options.arm_max_velocity, dtype=float).reshape(-1)
    if not (base_speed > 0 and arm_speed.shape == (2,) and np.all(arm_speed > 0)):
        raise ValueError(f"timed_params: execution_options need max_base_speed > 0 and two arm_max_velocity > 0, "
                         f"got {base_speed!r} and {execution_options.arm_max_velocity!r}")
    def f(values, dtype):  # writable, as STATIC's: one compiled loop for both modes (numba types read-only apart)
        return np.require(values, dtype, ["C_CONTIGUOUS", "WRITEABLE"])

    return TimedParams(True, float(t_root), base_speed, arm_speed, f(prediction.positions, float),
                       f(prediction.headings, float), f(prediction.present, bool), float(prediction.t0),
                       float(prediction.dt), f(prediction.radii, float), f(prediction.max_speeds, float), float(safety),
                       prediction.until(safety_horizon).samples)


def grow_params(space: ConfigurationSpace, checker: CompiledSceneChecker, objective: Objective,
                options: RrtStarOptions, gamma: float, start: np.ndarray, goal: np.ndarray,
                timed: TimedParams = STATIC) -> GrowParams:
    """The compiled loop's inputs for one run from start (4,) to goal (4,)
    (``timed``: the timed mode's, :func:`timed_params`; default off).

    Raises:
        ValueError: in timed mode, a social objective whose per-person
            parameters are not for the prediction's people (their count differs).
    """
    f = np.ascontiguousarray
    kind, social, grid = _social_params(objective)
    if timed.enabled and kind == 1 and len(social.reaches) != timed.xy.shape[1]:
        raise ValueError(f"the timed mode's social objective has {len(social.reaches)} people but the prediction "
                         f"{timed.xy.shape[1]}: build its SocialCost for the prediction (SocialCost.for_prediction)")
    if options.informed:
        sampler = EllipseSampler(space, start[:2], goal[:2])
        xy_scale = float(objective.length_weight * min(objective.distance_weights[0], objective.distance_weights[1]))
        informed = InformedParams(True, 0 if options.informed_mode == "paper" else 1, f(sampler.f1), f(sampler.f2),
                                  f(sampler.centre), f(sampler.rotation), float(sampler.focal_distance), xy_scale)
    else:
        z = np.zeros(2)
        informed = InformedParams(False, 0, z, z, z, np.eye(2), 0.0, 0.0)
    return GrowParams(
        f(goal), f(space.lower), f(space.upper), f(space.weights), float(options.planning_range),
        float(options.near_radius), float(options.goal_bias), options.near_radius_mode == "shrinking",
        float(gamma), ObjectiveParams(kind, float(objective.length_weight), f(objective.distance_weights, float), social,
                                      grid),
        bool(options.lazy_costs), checker.compiled_scene(), informed, timed,
    )


class CompiledTree(NamedTuple):
    """What a compiled run returns to the planner."""

    nodes: np.ndarray  #: (n, 4) configurations
    parents: np.ndarray  #: (n,) int64, -1 for the start
    costs: np.ndarray  #: (n,) cost from the start
    best_node: int  #: the node of the best goal connection, -1 when none
    best_cost: float  #: its cost (inf when none)
    first_iteration: int | None  #: the iteration of the first solution
    history: np.ndarray  #: (K,) best cost after each iteration
    diameters: np.ndarray  #: (K,) or (0,) informed ellipse diameters
    counts: tuple[int, int, int]  #: configurations checked, motions checked, motions costed
    tnode: np.ndarray  #: (n,) node times, seconds (timed mode; zeros otherwise)
    iterations: int  #: samples drawn (K, or fewer when the deadline stopped the run)
    deadline_hit: bool  #: the deadline stopped the run before K samples
    goal_nodes: np.ndarray  #: (G,) int64 nodes with a valid motion to the goal (the goal's own node: cost 0)
    goal_edges: np.ndarray  #: (G,) those motions' costs (at the node's time when connected, in timed mode)

    def path_to(self, node: int) -> np.ndarray:
        """The node indices (k,) int64 from the start (0) to ``node`` along the parents."""
        path = []
        i = int(node)
        while i >= 0:
            path.append(i)
            i = int(self.parents[i])
        return np.asarray(path[::-1], dtype=np.int64)


class CompiledRun:
    """A run ready to start: inputs packed, kernels loaded (see :func:`prepare`)."""

    def __init__(self, start: np.ndarray, params: GrowParams, iterations: int):
        self.start = np.ascontiguousarray(start)
        self.params = params
        self.iterations = int(iterations)

    def run(self, rng: np.random.Generator, progress: Callable[[int, float], None] | None = None, *,
            deadline: float | None = None, seed_path: np.ndarray | None = None) -> CompiledTree:
        """All iterations, in chunks: between them Python runs (a Ctrl-C
        during a chunk is raised after it, ``progress`` is called for each
        iteration of the chunk).

        Args:
            deadline: a ``time.perf_counter()`` value: the run stops at the
                first chunk boundary past it (at least one chunk runs). The
                first chunk is ``DEADLINE_CHUNK`` iterations, each later one
                about half the time left at the measured pace (at least
                ``DEADLINE_CHUNK``), so a run overshoots by at most a
                ``DEADLINE_CHUNK`` or half the time left;
                ``history`` and ``diameters`` are cut to the samples drawn.
                Where the run stops depends on the machine; the tree up to
                there does not.
            seed_path: (M, 4) a warm start's path from the start
                (``seed_path[0]`` must be the start): inserted as a chain
                before the first sample (:func:`~.tree_kernel.seed_chain`).

        Raises:
            ValueError: ``seed_path`` not (M, 4) finite values from the start, named.
        """
        k = self.iterations
        state = _held(tree_kernel.init_state, self.start, k, self.params)
        if seed_path is not None:
            seed = np.ascontiguousarray(seed_path, dtype=float)
            if seed.ndim != 2 or seed.shape[1] != 4 or len(seed) < 1 or not np.all(np.isfinite(seed)):
                raise ValueError(f"seed_path must be (M, 4) finite configurations, got shape {seed.shape}")
            if not np.array_equal(seed[0], self.start):
                raise ValueError(f"seed_path must start at the start {self.start.tolist()}, got {seed[0].tolist()}")
            state = _held(tree_kernel.seed_chain, seed, self.params, state)
        chunk = PROGRESS_CHUNK if progress is not None else (DEADLINE_CHUNK if deadline is not None else CHUNK)
        done = -1
        hit = False
        t_start = time.perf_counter()
        while done < k:
            stop = min(k, done + chunk)
            state = _held(tree_kernel.grow, rng, done, stop, self.params, state)
            if progress is not None:
                for it in range(max(done, 0), stop):
                    progress(it + 1, float(state.history[it]))
            done = stop
            if deadline is not None and done < k:
                now = time.perf_counter()
                if now > deadline:
                    hit = True
                    break
                if progress is None:
                    pace = (now - t_start) / (done + 1)  # seconds per iteration so far
                    chunk = max(DEADLINE_CHUNK, int(0.5 * (deadline - now) / max(pace, 1e-9)))
        drawn = max(done, 0)
        n, n_goal, best_node, first = int(state.ints[0]), int(state.ints[1]), int(state.ints[2]), int(state.ints[3])
        history = state.history[:drawn] if hit else state.history
        diameters = state.diameters[:drawn] if hit and len(state.diameters) else state.diameters
        # Views of the run's own arrays: nobody else holds the state.
        return CompiledTree(state.q[:n], state.parent[:n], state.cost[:n], best_node, float(state.floats[0]),
                            None if first < 0 else first, history, diameters,
                            tuple(int(c) for c in state.counts), state.tnode[:n], drawn, hit,
                            state.goal_nodes[:n_goal], state.goal_edges[:n_goal])


def _held(kernel, *args):
    """``kernel(*args)`` (a kernel of :mod:`~.tree_kernel`) with SIGINT and
    SIGTERM held back over the call and raised once it is back: numba's
    passing of a ``numpy.random.Generator`` and its boxing of a ``NamedTuple``
    result (the tree's state) run Python code that a ``KeyboardInterrupt``
    raised inside turns into a segmentation fault
    (:mod:`drake_social.interrupts`). The first call of a kernel in a process
    compiles, or loads, it before the hold, so that Ctrl-C stays live while
    it does."""
    if hasattr(kernel, "compile") and not kernel.signatures:  # a numba dispatcher with nothing loaded yet
        kernel.compile(tuple(numba.typeof(a) for a in args))
    held = DeferredSignals()
    try:
        with held:
            return kernel(*args)
    finally:  # also when the kernel raised: a Ctrl-C is not lost
        held.reraise()


def prepare(space: ConfigurationSpace, checker: CompiledSceneChecker, objective: Objective, options: RrtStarOptions,
            gamma: float, start: np.ndarray, goal: np.ndarray, timed: TimedParams = STATIC,
            iterations: int | None = None) -> CompiledRun:
    """Packs a run's inputs and has numba load (or, with a cold cache,
    compile) every kernel it calls, before anyone starts a clock.

    numba loads a kernel's cached machine code at its first call in a
    process (about 0.1 s for the tree loop and all it calls): here, once per
    process, on a throwaway tree with only the start's goal connection and
    its own generator (and :func:`~.tree_kernel.seed_chain` on a one-row
    seed). When that had to compile (numba's cache was cold), one warning per
    process says so and how long it took. ``timed``: the timed mode's inputs
    (:func:`timed_params`); ``iterations``: K in place of ``options.iterations``.
    """
    global _cold_cache_reported
    t_load = time.perf_counter()
    loading = not tree_kernel.grow.signatures  # nothing loaded or compiled yet in this process
    misses = cache_misses() if loading else 0
    params = grow_params(space, checker, objective, options, gamma, start, goal, timed)  # the people grid's kernel too
    run = CompiledRun(start, params, options.iterations if iterations is None else iterations)
    if loading:
        state = _held(tree_kernel.init_state, run.start, 1, params)
        state = _held(tree_kernel.seed_chain, run.start[None], params, state)
        _held(tree_kernel.grow, np.random.default_rng(0), -1, 0, params, state)
    if loading and cache_misses() > misses and not _cold_cache_reported:
        _cold_cache_reported = True
        _log.warning("numba's cache of the planning kernels was cold: compiled them once in %.1f s, outside the "
                     "plan time (`make install` or `python -m drake_social.warmup` fills the cache)",
                     time.perf_counter() - t_load)
    return run
