"""The compiled tree loop returns the Python reference's tree bit for bit."""

from __future__ import annotations

import copy
import dataclasses as dc
import json
import math
import subprocess
import sys
import textwrap

import numpy as np
import pytest

from drake_social.collision.planar_checker import PlanarChecker
from drake_social.planning.rrt_star import compiled_support, tree_kernel
from drake_social.planning.algorithms import make_planner
from drake_social.scenario import load_scenario

pytestmark = pytest.mark.skipif(not tree_kernel.AVAILABLE, reason="numba is not importable")


def run(scenario, checker, algorithm, seed, compiled, **options):
    planner = make_planner(scenario, checker, algorithm)
    planner.options = dc.replace(planner.options, compiled=compiled, **{"lazy_costs": False, **options})
    assert compiled_support(planner.checker, planner.objective, dc.replace(planner.options, compiled=True))[0]
    return planner.solve(np.array(scenario.start), np.array(scenario.goal), np.random.default_rng(seed))


def assert_same(reference, dut):
    np.testing.assert_array_equal(dut.waypoints, reference.waypoints)
    np.testing.assert_array_equal(dut.tree_nodes, reference.tree_nodes)
    np.testing.assert_array_equal(dut.tree_parents, reference.tree_parents)
    np.testing.assert_array_equal(dut.tree_costs, reference.tree_costs)
    np.testing.assert_array_equal(dut.cost_history, reference.cost_history)
    assert dut.cost == reference.cost and dut.first_solution_iteration == reference.first_solution_iteration
    assert (dut.num_config_checks, dut.num_motion_checks, dut.num_cost_evaluations) == (
        reference.num_config_checks, reference.num_motion_checks, reference.num_cost_evaluations)


@pytest.fixture(scope="module")
def tiny(tiny_scenario):
    scenario = copy.deepcopy(tiny_scenario)
    scenario.planner = dc.replace(scenario.planner, iterations=300)
    return scenario, PlanarChecker(scenario)


@pytest.mark.parametrize("seed", [0, 7])
@pytest.mark.parametrize("algorithm", ["rrt_star", "social_rrt_star", "base_rrt_star"])
def test_compiled_loop_equals_the_reference_on_tiny(tiny, algorithm, seed):
    scenario, checker = tiny
    assert_same(run(scenario, checker, algorithm, seed, False), run(scenario, checker, algorithm, seed, True))


def test_compiled_loop_equals_the_reference_with_lambda_and_a_shrinking_radius(tiny):
    """A small gamma makes the radius shrink below r_near within the run."""
    scenario, checker = tiny
    scenario = copy.deepcopy(scenario)
    scenario.social.length_weight = 0.5
    options = dict(near_radius_mode="shrinking", near_radius_gamma=2.5)
    reference = run(scenario, checker, "social_rrt_star", 3, False, **options)
    planner = make_planner(scenario, checker)
    planner.options = dc.replace(planner.options, **options)
    assert planner.near_radius(reference.tree_size) < scenario.planner.near_radius
    assert_same(reference, run(scenario, checker, "social_rrt_star", 3, True, **options))


@pytest.mark.parametrize("algorithm", ["social_rrt_star", "informed_social_rrt_star"])
def test_compiled_lazy_costs_equal_the_reference(tiny, algorithm):
    """With lambda > 0 both loops skip the same integrations: the same tree,
    the same checks and the same (fewer) cost evaluations."""
    scenario, checker = tiny
    scenario = copy.deepcopy(scenario)
    scenario.social.length_weight = 0.4
    reference = run(scenario, checker, algorithm, 4, False, lazy_costs=True)
    dut = run(scenario, checker, algorithm, 4, True, lazy_costs=True)
    assert_same(reference, dut)
    eager = run(scenario, checker, algorithm, 4, True)
    np.testing.assert_array_equal(eager.tree_nodes, dut.tree_nodes)
    assert dut.num_cost_evaluations < eager.num_cost_evaluations  # the laziness skips work


@pytest.mark.parametrize("name", ["office_bar", "generic_L"])
def test_compiled_loop_equals_the_reference_on_the_shipped_maps(name, repo_root):
    scenario = load_scenario(repo_root / "scenarios" / f"{name}.yaml")
    scenario.planner = dc.replace(scenario.planner, iterations=600)
    checker = PlanarChecker(scenario)
    assert_same(run(scenario, checker, "social_rrt_star", 1, False), run(scenario, checker, "social_rrt_star", 1, True))


def test_other_checkers_use_the_python_loop(tiny, tiny_scenario):
    from drake_social.collision.geometric import GeometricChecker

    scenario, _ = tiny
    planner = make_planner(scenario, GeometricChecker(scenario))
    assert compiled_support(planner.checker, planner.objective, planner.options) == (
        False, "the checker GeometricChecker declares no compiled_scene() (the validity protocol's "
        "CompiledSceneChecker capability)")


@pytest.mark.parametrize("mode", ["paper", "admissible"])
def test_compiled_informed_sampling_equals_the_reference(tiny, mode):
    """Informed sampling compiled: the same ellipse draws, the same diameters
    after every iteration, the same tree (admissible needs lambda > 0)."""
    scenario, checker = tiny
    scenario = copy.deepcopy(scenario)
    scenario.social.length_weight = 0.3
    scenario.planner = dc.replace(scenario.planner, informed_mode=mode)
    reference = run(scenario, checker, "informed_social_rrt_star", 2, False)
    dut = run(scenario, checker, "informed_social_rrt_star", 2, True)
    assert_same(reference, dut)
    np.testing.assert_array_equal(dut.informed_diameters, reference.informed_diameters)
    finite = np.isfinite(dut.informed_diameters)
    assert finite.sum() > 100 and len(np.unique(dut.informed_diameters[finite])) > 2  # the ellipse shrank


def test_a_progress_callback_sees_every_iteration_of_the_compiled_loop(tiny, monkeypatch):
    """With a callback the compiled loop runs in chunks: every iteration is
    reported, in order, with its best cost, and the result is the reference's."""
    scenario, checker = tiny
    planner = make_planner(scenario, checker, "social_rrt_star")
    planner.options = dc.replace(planner.options, lazy_costs=False)
    seen = []
    args = (np.array(scenario.start), np.array(scenario.goal))
    with_progress = planner.solve(*args, np.random.default_rng(5), lambda k, c: seen.append((k, c)))
    assert [k for k, _ in seen] == list(range(1, scenario.planner.iterations + 1))
    np.testing.assert_array_equal([c for _, c in seen], with_progress.cost_history)
    assert np.isinf(seen[0][1]) and np.isfinite(seen[-1][1])
    reference = run(scenario, checker, "social_rrt_star", 5, False)
    assert_same(reference, with_progress)
    assert_same(reference, planner.solve(*args, np.random.default_rng(5)))


@pytest.mark.parametrize("loaded", [False, True])
def test_the_compiled_loop_is_loaded_once_outside_the_timing(tiny, monkeypatch, loaded):
    """Before numba has loaded the loop in this process (no signatures yet)
    solve first runs it untimed on a throwaway tree (the start's goal
    connection alone, iterations -1 .. 0, its own generator); once loaded it
    does not. Either way the tree is the same, and wall_time leaves out the
    load: with a load made 0.3 s slow on purpose it is at most the call's
    own duration minus 0.3 s."""
    import time

    scenario, checker = tiny
    planner = make_planner(scenario, checker, "social_rrt_star")
    reference = planner.solve(np.array(scenario.start), np.array(scenario.goal), np.random.default_rng(5))
    grow, calls = tree_kernel.grow, []

    def spy(rng, it_start, it_stop, *rest):
        calls.append((it_start, it_stop))
        if (it_start, it_stop) == (-1, 0) and not loaded:
            time.sleep(0.3)  # a slow load
        return grow(rng, it_start, it_stop, *rest)

    spy.signatures = ["loaded"] if loaded else []
    monkeypatch.setattr(tree_kernel, "grow", spy)
    t = time.perf_counter()
    dut = planner.solve(np.array(scenario.start), np.array(scenario.goal), np.random.default_rng(5))
    elapsed = time.perf_counter() - t
    assert (calls[0] == (-1, 0) and calls[1][0] == -1) != loaded
    np.testing.assert_array_equal(dut.waypoints, reference.waypoints)
    assert dut.cost == reference.cost and dut.tree_size == reference.tree_size
    if not loaded:
        assert dut.wall_time <= elapsed - 0.3


def test_progress_is_at_most_one_chunk_of_64_iterations_late(tiny, monkeypatch):
    """The README's "at most 64 iterations late": with a callback the loop
    runs chunks of at most PROGRESS_CHUNK = 64 iterations, and iteration k is
    reported after the chunk that ran it and before the next chunk starts."""
    from drake_social.planning import rrt_star

    assert rrt_star.PROGRESS_CHUNK == 64
    scenario, checker = tiny
    planner = make_planner(scenario, checker, "social_rrt_star")
    events = []
    grow = tree_kernel.grow

    def spy(rng, it_start, it_stop, *rest):
        events.append(("grow", it_start, it_stop))
        return grow(rng, it_start, it_stop, *rest)

    spy.signatures = grow.signatures or ["loaded"]  # as loaded: no untimed first call (next test)
    monkeypatch.setattr(tree_kernel, "grow", spy)
    planner.solve(np.array(scenario.start), np.array(scenario.goal), np.random.default_rng(5),
                  lambda k, c: events.append(("progress", k)))
    chunks = [(e[1], e[2]) for e in events if e[0] == "grow"]
    assert chunks[0] == (-1, 63) and all(b - max(a, 0) <= 64 for a, b in chunks)
    assert [a for a, _ in chunks[1:]] == [b for _, b in chunks[:-1]] and chunks[-1][1] == scenario.planner.iterations
    ran_by = -1  # iterations 1 .. ran_by have run when a progress event comes
    for e in events:
        if e[0] == "grow":
            assert e[1] == ran_by  # chunks follow each other
            reported_up_to = max(e[1], 0)
            ran_by = e[2]
        else:
            assert reported_up_to < e[1] <= ran_by  # after its chunk ran, before the next one
            assert ran_by - e[1] < 64  # at most 63 iterations ran beyond it
            reported_up_to = e[1]
    assert reported_up_to == scenario.planner.iterations


def test_ctrl_c_stops_the_compiled_loop_between_chunks(tiny):
    """KeyboardInterrupt raised in the callback (as Python raises it for
    Ctrl-C between two chunks) ends the run at once, after one chunk."""
    from drake_social.planning import rrt_star

    scenario, checker = tiny
    scenario = copy.deepcopy(scenario)
    scenario.planner = dc.replace(scenario.planner, iterations=50 * rrt_star.PROGRESS_CHUNK)
    planner = make_planner(scenario, checker, "social_rrt_star")
    seen = []

    def interrupt(k, c):
        seen.append(k)
        if k == 10:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        planner.solve(np.array(scenario.start), np.array(scenario.goal), np.random.default_rng(0), interrupt)
    assert seen == list(range(1, 11))


#: Ctrl-C after Ctrl-C on the compiled loop: SIGINT to the main thread every 0 to 2 ms while the planner
#: of tiny.yaml (300 iterations, about 10 ms) solves again and again; the handler raises
#: KeyboardInterrupt only inside solve(), as Python's own does wherever it runs.
_STORM = textwrap.dedent("""
    import dataclasses as dc, json, signal, sys, threading, time
    import numpy as np
    from drake_social.collision.planar_checker import PlanarChecker
    from drake_social.planning.algorithms import make_planner
    from drake_social.scenario import load_scenario

    scenario = load_scenario(sys.argv[1])
    scenario.planner = dc.replace(scenario.planner, iterations=300)
    planner = make_planner(scenario, PlanarChecker(scenario), "social_rrt_star")
    start, goal = np.array(scenario.start), np.array(scenario.goal)
    before = planner.solve(start, goal, np.random.default_rng(0))
    inside, storming = False, threading.Event()

    def interrupt(signum, frame):
        if inside:
            raise KeyboardInterrupt

    signal.signal(signal.SIGINT, interrupt)

    def storm():
        pause = np.random.default_rng(1)
        while storming.is_set():
            time.sleep(pause.uniform(0.0, 0.002))
            signal.pthread_kill(threading.main_thread().ident, signal.SIGINT)

    storming.set()
    threading.Thread(target=storm, daemon=True).start()
    caught = solved = 0
    while caught < int(sys.argv[2]):
        inside = True
        try:
            planner.solve(start, goal, np.random.default_rng(solved))
            inside = False
            solved += 1
        except KeyboardInterrupt:
            inside = False
            caught += 1
    storming.clear()
    time.sleep(0.01)
    after = planner.solve(start, goal, np.random.default_rng(0))
    print(json.dumps({"caught": caught, "same": bool(np.array_equal(before.waypoints, after.waypoints)
                                                       and before.cost == after.cost)}))
""")


def test_ctrl_c_during_the_compiled_loop_is_a_clean_keyboard_interrupt(tiny_scenario_path):
    """numba's passing of the generator and its boxing of the tree's state run Python code that a
    KeyboardInterrupt raised inside crashed (a segmentation fault, or a SystemError): 300 Ctrl-Cs
    that land in the compiled loop are each a KeyboardInterrupt, and the next plan is the same."""
    done = subprocess.run([sys.executable, "-c", _STORM, str(tiny_scenario_path), "300"], capture_output=True,
                          text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]
    assert json.loads(done.stdout) == {"caught": 300, "same": True}


@pytest.mark.slow
def test_grid_neighbour_queries_equal_the_direct_scan(rng):
    """Nearest (lowest index on ties) and near sets (ascending) over the grid
    equal a brute-force scan, on clustered nodes with exact duplicates."""
    lower, upper = np.array([0.0, 0.0, -3.0, -3.0]), np.array([20.0, 12.0, 3.0, 3.0])
    w = np.array([1.0, 0.7, 0.5, 0.3])
    q = np.vstack([lower + rng.random((600, 4)) * (upper - lower),
                   rng.normal([3.0, 3.0, 0.0, 0.0], 0.2, (300, 4))])
    q = np.vstack([q, q[:50]])  # duplicates: ties at any query
    geom = tree_kernel._grid_geometry(lower, upper, w, 2.0)
    head = np.full(int(geom[3]) * int(geom[4]), -1, dtype=np.int64)
    nxt = np.full(len(q), -1, dtype=np.int64)
    for i in range(len(q)):
        tree_kernel._insert(i, q, w, head, nxt, geom)
    out = np.empty(len(q), dtype=np.int64)
    queries = np.vstack([lower + rng.random((200, 4)) * (upper - lower), q[:20], q[600:620] + 1e-3])
    for x in queries:
        d = np.sqrt((((q - x) * w) ** 2).sum(axis=1))
        i, dist = tree_kernel._nearest(q, x, w, head, nxt, geom)
        assert dist == pytest.approx(d.min(), abs=1e-12) and i == int(np.flatnonzero(d <= d[i])[0])
        for r in (0.3, 1.0, 2.5, 30.0):
            m = tree_kernel._within(q, x, w, r, r * r, head, nxt, geom, out)
            d2 = np.array([tree_kernel._d2(p, x, w) for p in q])
            np.testing.assert_array_equal(out[:m], np.flatnonzero(d2 <= r * r))


@pytest.mark.parametrize("bounds, people, grid_shape", [
    # People 7 m apart along x: 2 cells by 1 (the cell side is reach + point reach, about 5 m).
    (None, [(0.5, 0.4, 0.0), (7.5, 0.4, math.pi)], (0.5, 0.4, 2, 1)),
    # Two people by the south wall and one 5.3 m north of them, facing the corridor: 2 x 2.
    ([0.0, 0.0, 8.0, 10.0], [(0.5, 0.3, 0.0), (7.5, 0.3, math.pi), (4.0, 5.6, -math.pi / 2)], (0.5, 0.3, 2, 2)),
])
def test_compiled_loop_culls_people_in_a_people_grid(tiny, bounds, people, grid_shape):
    """The compiled loop reads the people grid's origin and shape right and
    costs every person near a motion as the reference does; the last person,
    in a cell of their own, changes the tree (mutation runs let nx = ny pass,
    and the origin's y read from nx, which drops the north person for
    motions that stay below y = 2)."""
    from drake_social.cost import SocialCost
    from drake_social.scenario import Person, validate_scenario

    scenario, _ = tiny
    scenario = copy.deepcopy(scenario)
    if bounds is not None:
        scenario.world.bounds = bounds
    scenario.people = [Person(x=x, y=y, theta=theta) for x, y, theta in people]
    validate_scenario(scenario)
    grid = SocialCost.from_scenario(scenario)._people_grid()
    assert (grid[2], grid[3], grid[4], grid[5]) == grid_shape  # x0, y0, nx, ny of the people grid
    checker = PlanarChecker(scenario)
    reference = run(scenario, checker, "social_rrt_star", 6, False)
    assert_same(reference, run(scenario, checker, "social_rrt_star", 6, True))
    without_last = copy.deepcopy(scenario)
    without_last.people = without_last.people[:-1]
    without = run(without_last, checker, "social_rrt_star", 6, False)  # the same checks, one person fewer
    assert not np.array_equal(without.tree_costs[:50], reference.tree_costs[:50])


@pytest.mark.parametrize("algorithm", ["rrt_star", "social_rrt_star"])
def test_compiled_loop_connects_the_start_to_a_near_goal_once(tiny, algorithm):
    """Start and goal 1 m apart (within r_near): the root's goal connection
    is made once, before the first sample, by both loops; the same tree,
    costs and counts (a mutation run let the compiled loop make it twice)."""
    scenario, _ = tiny
    scenario = copy.deepcopy(scenario)
    scenario.goal = [2.0, 2.5, 0.0, 1.5708]
    scenario.planner = dc.replace(scenario.planner, iterations=40)
    checker = PlanarChecker(scenario)
    reference = run(scenario, checker, algorithm, 1, False, lazy_costs=True)
    dut = run(scenario, checker, algorithm, 1, True, lazy_costs=True)
    assert_same(reference, dut)
    assert dut.first_solution_iteration == 1 and np.isfinite(dut.cost_history[0])


def test_compiled_admissible_ellipse_with_unequal_distance_weights(tiny):
    """The admissible informed bound divides by lambda min(w_x, w_y): with
    w_x != w_y the compiled loop's diameters and tree are the reference's
    (a mutation run let lambda / min and min(w_x, w_psi1) pass)."""
    scenario, checker = tiny
    scenario = copy.deepcopy(scenario)
    scenario.social.length_weight = 0.3
    scenario.planner = dc.replace(scenario.planner, informed_mode="admissible",
                                  distance_weights=[2.0, 2.5, 0.4, 0.3])
    reference = run(scenario, checker, "informed_social_rrt_star", 2, False)
    dut = run(scenario, checker, "informed_social_rrt_star", 2, True)
    assert_same(reference, dut)
    np.testing.assert_array_equal(dut.informed_diameters, reference.informed_diameters)
    finite = dut.informed_diameters[np.isfinite(dut.informed_diameters)]
    # Admissible: best cost / (lambda min(w_x, w_y)) = cost / (0.3 * 2.0).
    assert len(finite) > 100
    np.testing.assert_allclose(finite[-1], dut.cost / 0.6, rtol=1e-12)
