"""Memory does not grow with the world's content: the heat map of a crowd,
Drake's SceneGraph of a room of many boxes, and a long description.

The scenarios come from :mod:`crowd_scenarios` (valid: everything inside the
bounds, nothing overlapping, start and goal free).
"""

from __future__ import annotations

import json
import subprocess
import sys
import textwrap
import tracemalloc
from pathlib import Path

import numpy as np
import pytest

from crowd_scenarios import crowd_scenario_text
from drake_social.cost import SocialCost
from drake_social.cost.agf import agf, agf_xy
from drake_social.scenario import load_scenario
from drake_social.scenario.geometry import arm_geometry
from drake_social.viz.labels import ELLIPSIS, MAX_LABEL_CHARS, MAX_TITLE_CHARS, fit_text
from drake_social.viz.world import field_grid, field_resolution

# Crowds and rooms of thousands of boxes.
pytestmark = pytest.mark.slow

REPO = Path(__file__).resolve().parent.parent


@pytest.fixture(scope="module")
def crowd(tmp_path_factory):
    """100 x 100 m, 300 people, no boxes."""
    path = tmp_path_factory.mktemp("crowd") / "crowd.yaml"
    path.write_text(crowd_scenario_text(100.0, people=300, obstacles=0, seed=3))
    return load_scenario(path)


def test_field_of_a_crowd_holds_bounded_temporaries(crowd):
    """The 512 x 512 heat map of 300 people: 79 million (cell, person)
    values, 629 MB per temporary array if held at once; the chunked field
    peaks at a few tens of MB and equals the direct sum row by row, bit for bit."""
    cost = SocialCost.from_scenario(crowd)
    xs, ys = field_grid(crowd.world.bounds, field_resolution(crowd.world.bounds))
    assert (len(xs), len(ys)) == (512, 512)
    tracemalloc.start()
    try:
        values = cost.field(xs[None, :], ys[:, None])
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert peak < 64e6, f"field() peaked at {peak / 1e6:.0f} MB"
    assert values.shape == (512, 512)
    for j in (0, 137, 300, 511):  # the unchunked formula, one row at a time
        row = agf(np.stack([xs, np.full_like(xs, ys[j])], -1), cost.people, cost.space).sum(-1)
        assert np.array_equal(values[j], row)
    assert values.max() > 0.2 and (values == 0).mean() > 0.1  # people are there, and far from everywhere


def test_cost_along_many_configurations_holds_bounded_temporaries(crowd):
    """S(q) of 20,000 configurations among 300 people (a long path's cost
    profile): 30 million (point, person) values, 240 MB per temporary array if
    held at once; bounded now, and equal to the direct formula bit for bit."""
    cost = SocialCost.from_scenario(crowd)
    rng = np.random.default_rng(1)
    q = np.column_stack([rng.uniform(0, 100, (20_000, 2)), rng.uniform(-np.pi, np.pi, (20_000, 2))])
    tracemalloc.start()
    try:
        values = cost(q)
        points = cost.point_costs(q)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert peak < 64e6, f"S(q) peaked at {peak / 1e6:.0f} MB"
    part = q[:700]
    x, y = cost.geometry.interest_xy(part, cost._active)
    assert np.array_equal(values[:700], agf_xy(x, y, cost.people, cost.space).sum(-1) @ cost._active_weights)
    assert np.array_equal(points[:700], agf(cost.geometry.interest_points(part), cost.people, cost.space).sum(-1))
    assert (values > 0).mean() > 0.05


def test_fit_text_cuts_lines_and_length():
    assert fit_text("short") == "short"
    assert fit_text("a\nb\n") == "a\nb"
    assert fit_text("x" * 10, max_chars=4) == "xxx" + ELLIPSIS
    assert fit_text("1\n2\n3\n4", max_lines=2) == "1\n2" + ELLIPSIS
    assert fit_text("ab\n" + "c" * 9, max_chars=5, max_lines=2) == "ab\ncccc" + ELLIPSIS
    assert fit_text("ab\ncd", max_chars=5, max_lines=1) == "ab" + ELLIPSIS
    assert fit_text("abcd", max_chars=4) == "abcd"
    assert fit_text("x" * 10**7, max_chars=4) == "xxx" + ELLIPSIS
    with pytest.raises(ValueError, match="must be >= 1"):
        fit_text("a", max_chars=0)


def test_long_description_and_name_are_cut_in_figures():
    """A 10^6-character description (0.9 GB and 138 s to draw as a title) and
    a long person name reach the figure cut to a bounded size: one title
    line (the map figure's layout has room for one)."""
    from drake_social.viz.show import show_figure

    scenario = load_scenario(REPO / "scenarios" / "tiny.yaml")
    scenario.description = "lorem ipsum dolor " * 60_000 + "\nsecond line"
    scenario.people[0].name = "a very long name " * 1000
    fig = show_figure(scenario)
    assert fig._suptitle.get_text() == scenario.description[: MAX_TITLE_CHARS - 1] + ELLIPSIS
    labels = [t.get_text() for t in fig.axes[0].texts]
    assert scenario.people[0].name[: MAX_LABEL_CHARS - 1] + ELLIPSIS in labels
    assert max(len(t) for t in labels) <= MAX_TITLE_CHARS


# ---- a long run among many people ------------------------------------------------


@pytest.fixture(scope="module")
def walked_among_400(tmp_path_factory):
    """A 20 s run logged every 0.01 s (2,001 samples) among 400 walkers in a 30 x 30 m room: the
    robot drives diagonally through them, a fifth of them leaves halfway."""
    from drake_social.people.log import PeopleLog

    path = tmp_path_factory.mktemp("walked") / "crowd.yaml"
    path.write_text(crowd_scenario_text(30.0, people=400, obstacles=0, seed=7, clearance=1.0))
    scenario = load_scenario(path)
    rng = np.random.default_rng(11)
    times = np.round(np.arange(2001) * 0.01, 10)
    start = np.array([[p.x, p.y] for p in scenario.people])
    velocity = rng.uniform(-1.0, 1.0, (400, 2))
    positions = start[None] + times[:, None, None] * velocity[None]
    present = np.ones((2001, 400), bool)
    present[1000:, ::5] = False
    log = PeopleLog(times=times, positions=positions, headings=np.broadcast_to(np.arctan2(velocity[:, 1],
                                                                                          velocity[:, 0]), (2001, 400)),
                    velocities=np.broadcast_to(velocity, (2001, 400, 2)), present=present,
                    radii=np.full(400, 0.25), names=[f"p{k}" for k in range(400)])
    s = np.linspace(0.0, 1.0, 2001)[:, None]
    q = np.column_stack([3.0 + 24.0 * s, 3.0 + 24.0 * s, np.zeros((2001, 1)), np.full((2001, 1), 1.5708)])
    return scenario, times, q, log


def test_metrics_of_a_long_run_among_many_people_hold_bounded_temporaries(walked_among_400, monkeypatch):
    """The run's metrics among 400 people over 2,001 samples: the AGF over time was summed 2,048
    samples at a time (203 MB per temporary, some 1.3 GB for the Gaussian's) and the parts' distances
    all samples at once (51 MB per offset array): bounded now, and every figure is the one of the
    whole at once; the robot's distances equal the compiled one-configuration kernel's."""
    import drake_social.evaluation.nav_metrics as nav
    import drake_social.people.proximity as proximity

    scenario, times, q, log = walked_among_400
    tracemalloc.start()
    try:
        dut = nav.run_metrics(scenario, times, q, log, None, False, 20.0)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert peak < 64e6, f"run_metrics peaked at {peak / 1e6:.0f} MB"
    monkeypatch.setattr(nav, "FIELD_CHUNK_ELEMENTS", 1 << 40)  # one block: the whole run at once
    monkeypatch.setattr(proximity, "DISTANCE_CHUNK_ELEMENTS", 1 << 40)
    whole = nav.run_metrics(scenario, times, q, log, None, False, 20.0)
    assert dut.keys() == whole.keys()
    assert all(dut[k] == whole[k] or (np.isnan(dut[k]) and np.isnan(whole[k])) for k in dut)
    geometry = proximity.robot_distance_args(arm_geometry(scenario))
    robot = [proximity.robot_distance(geometry, q[k], log.positions[k], log.radii, log.present[k])
             for k in range(len(times))]
    assert dut["min_dist_robot"] == pytest.approx(min(robot), rel=1e-12)
    assert 0.0 < dut["agf_time_robot"] and dut["collisions_robot"] >= 1  # the walkers are met


def test_people_csv_of_a_long_run_is_written_row_by_row(walked_among_400, tmp_path):
    """people.csv of 400 people over 2,001 samples (720,400 rows): the rows were built as one list
    first (some 200 MB); written as they are made now, the file is the same rows."""
    from drake_social.io.paths import write_people_csv

    _, times, _, log = walked_among_400
    out = tmp_path / "people.csv"
    tracemalloc.start()
    try:
        write_people_csv(out, log)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert peak < 32e6, f"write_people_csv peaked at {peak / 1e6:.0f} MB"
    with out.open() as f:
        assert next(f) == "t,id,x,y,theta,v\n"
        rows = sum(1 for _ in f)
    assert rows == int(log.present.sum()) == 2001 * 400 - 1001 * 80
    last = out.read_text().rstrip("\n").rsplit("\n", 1)[1].split(",")
    assert (float(last[0]), last[1]) == (20.0, "p399")
    assert (float(last[2]), float(last[3])) == (log.positions[-1, 399, 0], log.positions[-1, 399, 1])


# ---- Drake: the room in parts -------------------------------------------------


@pytest.fixture(scope="module")
def boxes(tmp_path_factory):
    """A 40 x 40 m room of 300 boxes and 60 people: more than one part."""
    path = tmp_path_factory.mktemp("boxes") / "boxes.yaml"
    path.write_text(crowd_scenario_text(40.0, people=60, obstacles=300, seed=5, clearance=2.5))
    return load_scenario(path)


def test_planar_checker_reads_the_same_room_in_parts(boxes):
    from drake_social.model.plant import ENVIRONMENT_PART, build_robot_diagram
    from drake_social.collision.planar_checker import PlanarChecker

    whole = PlanarChecker(boxes, model=build_robot_diagram(boxes))
    parts = PlanarChecker(boxes)
    assert len(whole.env) == 300 + 60 + 4 > ENVIRONMENT_PART
    assert parts.env_names == whole.env_names
    assert np.array_equal(parts.env, whole.env)
    assert np.array_equal(parts.robot, whole.robot) and np.array_equal(parts.bodies, whole.bodies)
    # The first part's SceneGraph holds the robot and at most ENVIRONMENT_PART shapes.
    from pydrake.geometry import Role

    inspector = parts.model.diagram.scene_graph().model_inspector()
    assert inspector.NumGeometriesWithRole(Role.kProximity) <= ENVIRONMENT_PART + 3 * len(parts.robot)


def test_local_drake_checks_answer_as_the_whole_room(boxes, monkeypatch):
    """verify_path and the start/goal check from the shapes near the path
    (in parts) agree with one Drake checker of the whole room, on random
    straight motions, many of them colliding."""
    from drake_social.collision.drake_checker import (
        SceneGraphChecker,
        _segment_groups,
        check_start_goal,
        near_environment,
        valid_configurations,
        verify_path,
    )
    from drake_social.collision.planar_checker import PlanarChecker
    from drake_social.scenario import ScenarioError

    import drake_social.model.plant as plant

    whole = SceneGraphChecker(boxes)
    planar = PlanarChecker(boxes)
    monkeypatch.setattr(plant, "ENVIRONMENT_PART", 3)  # the 4 walls alone fill more than a part
    rng = np.random.default_rng(0)
    lo, hi = whole.lower, whole.upper
    step = np.array([0.8, 0.8, 0.6, 0.6])

    def valid_sample():
        while True:
            q = rng.uniform(lo, hi)
            if planar.is_valid(q):
                return q

    outcomes = set()
    for _ in range(20):  # short motions between valid configurations: some collide, some not
        wp = [valid_sample()]
        for _ in range(2):
            wp.append(np.clip(wp[-1] + rng.uniform(-step, step), lo, hi))
        wp = np.array(wp)
        expected = verify_path(whole, wp)
        assert verify_path(planar, wp) == expected
        assert verify_path(boxes, wp[1:2]) == verify_path(whole, wp[1:2])
        outcomes.add(expected)
    assert {None, 0, 1} <= outcomes
    # A collision-free walk: with parts of 3 shapes every segment is a group of its own, checked in parts.
    walk = [valid_sample()]
    while len(walk) < 30:
        q = np.clip(walk[-1] + rng.uniform(-2 * step, 2 * step), lo, hi)
        if planar.is_motion_valid(walk[-1], q):
            walk.append(q)
    walk = np.array(walk)
    assert len(_segment_groups(boxes, walk)) > 1
    samples = np.vstack([walk[:10], rng.uniform(lo, hi, (40, 4))])  # a run, then scattered (many collide)
    verdicts = valid_configurations(boxes, samples)
    assert np.array_equal(verdicts, whole.are_valid(samples)) and verdicts[:10].all() and not verdicts.all()
    assert np.array_equal(valid_configurations(boxes, samples[12:13]), whole.are_valid(samples[12:13]))
    assert verify_path(planar, walk) is None is verify_path(whole, walk)
    walk[20] = np.array([*boxes.world.obstacles[0].center, 0.0, 0.0])  # on a box
    assert verify_path(planar, walk) == verify_path(whole, walk) == 19
    near = near_environment(boxes, np.array([[20.0, 20.0]]), np.array([[20.0, 20.0]]))
    assert 4 <= len(near) < 100  # the walls and the shapes around the centre
    box = boxes.world.obstacles[0]
    boxes.start = [box.center[0], box.center[1], 0.0, 1.5708]  # the base on a box
    try:
        with pytest.raises(ScenarioError) as local:
            check_start_goal(boxes, None, "b.yaml")
        with pytest.raises(ScenarioError) as full:
            check_start_goal(boxes, SceneGraphChecker(boxes), "b.yaml")
    finally:
        boxes.start = [3.0, 3.0, 0.0, 1.5708]
    assert str(local.value) == str(full.value) and "obstacle[0]" in str(local.value)


# ---- peak memory of the CLI -----------------------------------------------------

_PEAK = textwrap.dedent("""
    import resource, subprocess, sys
    done = subprocess.run(sys.argv[1:], capture_output=True, text=True)
    sys.stderr.write(done.stderr[-2000:])
    print(done.returncode, resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss)
""")


def _peak_mb(args: list[str]) -> tuple[int, float]:
    """Exit code and peak resident memory (MB) of ``drake-social ARGS`` in a fresh process."""
    cmd = [sys.executable, "-c", "from drake_social.cli import main; raise SystemExit(main())", *args]
    out = subprocess.run([sys.executable, "-c", _PEAK, *cmd], capture_output=True, text=True, check=True)
    code, kb = out.stdout.split()
    return int(code), int(kb) / 1024


@pytest.mark.parametrize("command", ["show", "plan"])
def test_cli_peak_memory_of_a_crowd_among_boxes(tmp_path, command):
    """300 people and 2,000 boxes in a 100 x 100 m room: show and plan stay
    under 1.2 GB (3.8 and 4.0 GB for 300 people, 2.5 GB for plan with 2,000
    boxes before; about 0.3 and 0.5 GB now)."""
    scenario = tmp_path / "crowd.yaml"
    scenario.write_text(crowd_scenario_text(100.0, people=300, obstacles=2000, seed=0, iterations=100))
    code, peak = _peak_mb([command, str(scenario), "--out", str(tmp_path / "out")])
    assert code in (0, 3), code  # plan may find no path in 100 samples
    assert (tmp_path / "out" / ("scene.png" if command == "show" else "path.png")).is_file()
    assert peak < 1200, f"{command} peaked at {peak:.0f} MB"


def test_cli_peak_memory_of_a_replanning_run_among_400_walkers(tmp_path):
    """``simulate --replan`` of 10 s among a crowd of 400 walkers: 1.3 GB before (the run's metrics
    and people.csv held every (sample, point, person) value at once), about 0.65 GB now; planning
    once finds no path through them (nothing runs: 0.5 GB)."""
    scenario = tmp_path / "walkers.yaml"
    scenario.write_text(crowd_scenario_text(30.0, people=400, seed=7, clearance=1.0, walking=True, iterations=300)
                        + "execution: {time_limit: 10}\n")
    code, peak = _peak_mb(["simulate", str(scenario), "--replan", "--no-replay", "--out", str(tmp_path / "out")])
    assert code in (0, 5), code
    record = json.loads((tmp_path / "out" / "sim.json").read_text())
    assert record["num_samples"] == 1001 or record["reached"]  # the whole 10 s ran (or the goal was reached)
    assert (tmp_path / "out" / "people.csv").is_file()
    assert peak < 950, f"simulate --replan peaked at {peak:.0f} MB"


def test_cli_peak_memory_of_map_inspect_of_the_largest_map(tmp_path):
    """``map inspect`` of a 5000 x 5000 map of grid lines every 7 rows and 11 columns (docs/maps.md's
    largest measured map, 325,780 boxes): 1.87 GB before (matplotlib resampled a float copy of the
    25 million cells and held an outline per box), under 0.6 GB now, reading included."""
    from PIL import Image

    rows, cols = np.mgrid[0:5000, 0:5000]
    Image.fromarray(np.where((rows % 7 == 0) | (cols % 11 == 0), 0, 254).astype(np.uint8)).save(tmp_path / "grid.pgm")
    (tmp_path / "grid.yaml").write_text("image: grid.pgm\nresolution: 0.05\norigin: [0.0, 0.0, 0.0]\nnegate: 0\n"
                                        "occupied_thresh: 0.65\nfree_thresh: 0.196\n")
    del rows, cols
    code, peak = _peak_mb(["map", "inspect", str(tmp_path / "grid.yaml"), "--out", str(tmp_path / "out")])
    assert code == 0
    with Image.open(tmp_path / "out" / "map.png") as png:
        assert png.size[0] > 1000
    assert peak < 600, f"map inspect peaked at {peak:.0f} MB"
    from drake_social.viz.world import MAP_MAX_OUTLINES, MAP_PICTURE_CELLS

    # What the figure drew: the cells in 3 x 3 blocks, and no outlines (325,780 boxes).
    assert 5000 / 3 <= MAP_PICTURE_CELLS < 5000 / 2 and MAP_MAX_OUTLINES < 325_780
