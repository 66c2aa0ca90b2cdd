"""Fills numba's on-disk cache of every compiled kernel, with the argument types the commands use.

numba compiles a kernel at its first call with new argument types and keeps
the machine code on disk (``cache=True``); a later process loads it in a
fraction of a second. Compiling the social cost, the planar checker and the
tree loop takes a minute or more of CPU, so ``make install`` runs
``python -m drake_social.warmup`` once: the user's first ``plan`` then loads
instead of compiling. The warm-up goes through the same code as the commands
(the planar checker of a small built-in room, :func:`~drake_social.planning.algorithms.plan`
with every algorithm and both near-radius modes, the optimiser, every checker
query and the social cost), so numba sees exactly their argument types; the
execution analysis's searches are called with the types it passes, and the
replanner's search (the tree loop's timed mode, seeded, with a deadline) runs
once on a tiny prediction.
"""

from __future__ import annotations

import argparse
import dataclasses as dc
import logging
import time

import numpy as np

__all__ = ["WARMUP_SCENARIO", "warm_up"]

#: One room, one person, one desk: small enough to plan in milliseconds, with
#: every kind of input the kernels take (people, boxes, the arm and a bar).
WARMUP_SCENARIO = """
description: "warm-up: one 8 x 5 m room, one person, a desk, a 1.5 m bar"
world:
  bounds: [0.0, 0.0, 8.0, 5.0]
  obstacles:
    - {center: [4.0, 0.6], size: [1.6, 0.8], yaw: 0.0}
people:
  - {x: 4.0, y: 3.8, theta: -1.5708, radius: 0.25, name: "standing"}
robot:
  base_radius: 0.35
  link_lengths: [0.6, 0.5]
  link_width: 0.08
object: !Bar {length: 1.5, thickness: 0.05}
start: [1.0, 2.5, 0.0, 1.5708]
goal: [6.5, 2.5, 0.0, 1.5708]
random_seed: 1
planner:
  iterations: 60
"""


def warm_up() -> dict[str, float | int]:
    """Compiles (or loads) every kernel with the commands' argument types.

    Returns:
        ``seconds`` (wall time), ``compiled`` (compilations numba's cache
        lacked) and ``functions`` (compiled functions of the kernels).
    """
    from drake_social.collision.drake_checker import make_checker
    from drake_social.planning.algorithms import ALGORITHM_SPECS, plan
    from drake_social.planning.rrt_star.compiled import cache_misses, kernel_dispatchers
    from drake_social.scenario import load_scenario_text

    t0 = time.perf_counter()
    scenario = load_scenario_text(WARMUP_SCENARIO, "<drake_social.warmup>")
    checker = make_checker(scenario, "planar")
    for name in ALGORITHM_SPECS:
        plan(scenario, checker, algorithm=name, seed=0)
    # The plans above run the scenario's defaults (shrinking radius, optimised);
    # these run the other settings, the paper's (fixed radius, raw path: the
    # paper study, bench and tiny.yaml) among them, with a progress callback.
    for mode, optimize in (("fixed", False), ("fixed", True), ("shrinking", False)):
        s = dc.replace(scenario, planner=dc.replace(scenario.planner, near_radius_mode=mode, optimize=optimize))
        plan(s, checker, seed=1, progress=lambda k, c: None)
    q_a, q_b = np.array(scenario.start, float), np.array(scenario.goal, float)
    qs = np.stack([q_a, q_b])
    checker.is_valid(q_a), checker.are_valid(qs), checker.clearance(q_a), checker.clearances(qs)
    checker.is_motion_valid(q_a, q_b), checker.are_motions_valid(qs[:1], qs[1:])
    checker.contacts(q_a), checker.body_poses(q_a), checker.capsules(q_a)
    _warm_up_analysis()
    _warm_up_people(scenario)
    _warm_up_timed(scenario)
    return {"seconds": time.perf_counter() - t0, "compiled": cache_misses(),
            "functions": sum(len(d.signatures) for d in kernel_dispatchers().values())}


def _warm_up_analysis() -> None:
    """The execution analysis's searches (:mod:`drake_social.sim.analysis_kernel`)
    with the argument types :func:`drake_social.sim.analysis.point_deviation` gives them."""
    from drake_social.sim import analysis_kernel

    points = np.ascontiguousarray([[0.5, 0.1], [1.5, -0.1]])
    curve = np.ascontiguousarray([[0.0, 0.0], [1.0, 0.0], [2.0, 0.0]])
    nearest = np.asarray([[0, 1], [1, 2]], np.int64)
    steps = np.asarray(analysis_kernel.nearest_segments(points, curve, nearest), np.int64)
    dense = np.ascontiguousarray([[0.0, 0.0, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0], [2.0, 0.0, 0.0, 0.0]])
    newton_steps = 8  # an int, as the analysis's own count
    analysis_kernel.step_distances(dense, points, steps, 2, 0.6, 0.5, 0.1, 0.0, newton_steps)


#: What the warm-up scenario lacks for the people's kernels: a walker (the
#: tracks' evaluation) and a crowd of one (the social-force step).
_WARMUP_PEOPLE = """
people:
  - {x: 4.0, y: 3.8, theta: -1.5708, radius: 0.25, name: "standing"}
  - {x: 1.0, y: 4.2, theta: 0.0, radius: 0.25, name: "walking", trajectory: [[0.0, 1.0, 4.2], [4.0, 7.0, 4.2]]}
crowd:
  people:
    - {x: 7.0, y: 1.0, goals: [[1.0, 1.0]], name: "crowd"}
"""


def _warm_up_people(scenario) -> None:
    """The per-step kernels of a simulation with people, with the argument types
    the diagram gives them: the tracks' evaluation
    (:mod:`drake_social.people.tracks_kernel`), the crowd's step with and
    without the robot (:mod:`drake_social.people.social_force_kernel`) and the
    safety monitor's distance (:mod:`drake_social.people.proximity_kernel`), and
    the interactive prediction's rollout (:mod:`drake_social.people.interactive_kernel`)."""
    from drake_social.control import SafetyMonitor
    from drake_social.scenario.geometry import arm_geometry
    from drake_social.people.compose import people_model
    from drake_social.scenario import load_scenario_text

    block = WARMUP_SCENARIO[WARMUP_SCENARIO.index("people:"):WARMUP_SCENARIO.index("robot:")]
    people = load_scenario_text(WARMUP_SCENARIO.replace(block, _WARMUP_PEOPLE.lstrip("\n")),
                                "<drake_social.warmup people>")
    model = people_model(people)
    state = model.state_at(0.5)  # the walker, the crowd stepped open loop (no robot)
    q = np.array(scenario.start, float)
    model.crowd.step(np.array(model.crowd.initial_state(), float), 0.0, model.open_loop_state(0.0), q.copy())
    SafetyMonitor(arm_geometry(people), safety_distance=0.05, period=0.01).too_close(q, state)
    # The replanner's interactive prediction (drake_social.people.interactive_kernel).
    from drake_social.people.interactive import InteractiveModel, predict_interactive

    predict_interactive(state, (np.stack([q, q]), np.array([0.5, 1.0])), 0.5, InteractiveModel.from_scenario(people))


def _warm_up_timed(scenario) -> None:
    """The replanner's search (:meth:`~drake_social.planning.rrt_star.RrtStar.solve_timed`):
    the room without its people, the person predicted at constant velocity,
    a seed path and a deadline, with the argument types the replanner gives."""
    from drake_social.collision.drake_checker import make_checker
    from drake_social.people import constant_velocity, people_model, without_people
    from drake_social.planning.algorithms import make_planner
    from drake_social.planning.rrt_star.compiled import timed_params

    planner = make_planner(scenario, make_checker(without_people(scenario), "planar"))
    prediction = constant_velocity(people_model(scenario).state_at(0.0), 1.0)
    prediction.state_at(0.5)  # the prediction's lookup from Python (its arrays are read-only)
    timed = timed_params(prediction, scenario.execution, 0.0, scenario.execution.safety_distance)
    start, goal = np.array(scenario.start, float), np.array(scenario.goal, float)
    seed = np.stack([start, start + np.array([0.5, 0.0, 0.0, 0.0])])
    planner.solve_timed(start, goal, np.random.default_rng(0), timed, seed_path=seed,
                        deadline=time.perf_counter() + 60.0, iterations=40)


def main(argv: list[str] | None = None) -> int:
    """``python -m drake_social.warmup``: warms the cache and says what it did."""
    argparse.ArgumentParser(prog="python -m drake_social.warmup", description=__doc__.splitlines()[0]).parse_args(argv)
    # The planner's own cold-cache warning would repeat what this reports.
    logging.getLogger("drake_social.planning.rrt_star.compiled").setLevel(logging.ERROR)
    report = warm_up()
    print(f"drake_social kernels ready: {report['functions']} compiled functions, {report['compiled']} compiled "
          f"now, {report['seconds']:.1f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
