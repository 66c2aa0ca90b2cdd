"""The scenario files shipped in scenarios/: they load, and each one is solvable.

Solvability is shown with the Drake-free :class:`GeometricChecker`: start and
goal are collision-free, and for the office and the generic map a hand-made
witness path (straight motions between a few waypoints, the carrying pose
kept) is collision-free with a margin. The office is checked to offer what
Section V-A needs: a direct route past the people and a longer, socially
cheaper detour. The generic map is checked to be tight: the L passes its
passages only turned the right way.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from drake_social.cost import SocialCost
from drake_social.scenario.geometry import arm_geometry
from drake_social.collision.geometric import GeometricChecker
from drake_social.maps import FREE, read_map
from drake_social.scenario import Bar, LShape, load_scenario, validate_scenario

SCENARIO_DIR = Path(__file__).resolve().parent.parent / "scenarios"
SCENARIO_FILES = sorted(SCENARIO_DIR.glob("*.yaml"))


def test_the_three_scenarios_are_shipped():
    names = {p.name for p in SCENARIO_FILES}
    assert {"office_bar.yaml", "generic_L.yaml", "tiny.yaml"} <= names


@pytest.mark.parametrize("path", SCENARIO_FILES, ids=lambda p: p.stem)
def test_every_scenario_file_loads_and_validates(path):
    dut = load_scenario(path)
    assert validate_scenario(dut, source=str(path)) is None  # idempotent: still valid
    assert dut.description, f"{path.name}: give the scenario a description (shown in figures)"
    x0, y0, x1, y1 = dut.world.bounds
    for q in (dut.start, dut.goal):
        assert len(q) == 4 and x0 <= q[0] <= x1 and y0 <= q[1] <= y1
    for p in dut.people:
        assert x0 < p.x < x1 and y0 < p.y < y1


def _box_signed_distance(points: np.ndarray, box) -> np.ndarray:
    """Signed distance of world points (N, 2) to a rotated box (independent of
    the checker's implementation: corners in the box frame, then clamping)."""
    c, s = math.cos(box.yaw), math.sin(box.yaw)
    d = points - np.asarray(box.center)
    local = np.stack([c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1]], -1)
    half = np.asarray(box.size) / 2
    inside = np.all(np.abs(local) <= half, -1)
    outside = np.linalg.norm(np.maximum(np.abs(local) - half, 0.0), axis=-1)
    depth = np.min(half - np.abs(local), -1)
    return np.where(inside, -depth, outside)


@pytest.mark.parametrize("path", SCENARIO_FILES, ids=lambda p: p.stem)
def test_people_stand_in_free_space(path):
    """No person's body overlaps an obstacle, a wall or another person."""
    dut = load_scenario(path)
    x0, y0, x1, y1 = dut.world.bounds
    for i, p in enumerate(dut.people):
        assert min(p.x - x0, x1 - p.x, p.y - y0, y1 - p.y) > p.radius, f"person {i} overlaps a wall"
        centre = np.array([[p.x, p.y]])
        for k, box in enumerate(dut.world.obstacles):
            assert _box_signed_distance(centre, box)[0] > p.radius, f"person {i} overlaps obstacle {k}"
        if dut.world.map is not None:  # the body's cells in the map are free
            grid = read_map(dut.world.map)
            offsets = np.stack(np.meshgrid(*[np.linspace(-p.radius, p.radius, 21)] * 2), -1).reshape(-1, 2)
            disc = centre + offsets[np.hypot(*offsets.T) <= p.radius]
            assert (grid.class_at(disc) == FREE).all(), f"person {i} stands on an obstacle cell of the map"
        for j, other in enumerate(dut.people[:i]):
            assert math.hypot(p.x - other.x, p.y - other.y) > p.radius + other.radius, f"people {j}, {i} overlap"


@pytest.mark.parametrize("path", SCENARIO_FILES, ids=lambda p: p.stem)
def test_start_and_goal_are_collision_free(path):
    scenario = load_scenario(path)
    dut = GeometricChecker(scenario)
    clearance = dut.clearances(np.array([scenario.start, scenario.goal], float))
    assert np.all(clearance > 0.05), f"{path.name}: start/goal clearance {clearance} m"


# ---- the office (Section V-A) --------------------------------------------------


@pytest.fixture(scope="module")
def office():
    return load_scenario(SCENARIO_DIR / "office_bar.yaml")


def _waypoints(scenario, xys) -> np.ndarray:
    """Configurations at the given base positions, in the start's arm pose."""
    arm = np.asarray(scenario.start[2:], float)
    return np.array([[x, y, *arm] for x, y in xys])


def _path_clearance(checker: GeometricChecker, path: np.ndarray) -> float:
    """Smallest clearance over every checked configuration of a waypoint path."""
    qs, _ = checker.motion_samples(path[:-1], path[1:])
    return float(checker.clearances(qs).min())


def test_office_layout(office):
    x0, y0, x1, y1 = office.world.bounds
    assert x1 - x0 == pytest.approx(20.0, abs=2.0)
    assert y1 - y0 == pytest.approx(12.0, abs=2.0)
    assert len(office.people) >= 4
    assert len(office.world.obstacles) >= 10  # desks and interior walls: cluttered
    assert isinstance(office.object, Bar)
    assert office.object.length == pytest.approx(1.5)
    # Start at one end, goal at the other.
    assert office.start[0] - x0 < 0.15 * (x1 - x0)
    assert x1 - office.goal[0] < 0.15 * (x1 - x0)


def _direct_and_detour(office) -> tuple[np.ndarray, np.ndarray]:
    s, g = office.start, office.goal
    direct = _waypoints(office, [s[:2], g[:2]])
    detour = _waypoints(office, [s[:2], (2.5, 10.0), (17.5, 10.0), g[:2]])
    return direct, detour


def test_office_has_a_direct_route_past_people_and_a_cheaper_detour(office):
    """The straight route is free but socially expensive; the corridor detour
    is longer and costs less than half as much (uniform weights)."""
    checker = GeometricChecker(office)
    cost = SocialCost.from_scenario(office)
    direct, detour = _direct_and_detour(office)
    assert _path_clearance(checker, direct) > 0.2
    assert _path_clearance(checker, detour) > 0.2
    direct_cost = cost.motion_cost(direct[:-1], direct[1:]).sum()
    detour_cost = cost.motion_cost(detour[:-1], detour[1:]).sum()
    length = [np.linalg.norm(np.diff(p[:, :2], axis=0), axis=1).sum() for p in (direct, detour)]
    assert length[1] > 1.3 * length[0]
    assert direct_cost > 10.0  # it passes people
    assert detour_cost < 0.5 * direct_cost


# ---- the generic map (Section V-B) ---------------------------------------------


@pytest.fixture(scope="module")
def generic():
    return load_scenario(SCENARIO_DIR / "generic_L.yaml")


def test_generic_layout(generic):
    assert isinstance(generic.object, LShape)
    assert generic.object.lengths == pytest.approx([3.0, 2.0])
    assert len(generic.people) >= 3
    x0, y0, x1, y1 = generic.world.bounds
    assert (x1 - x0) * (y1 - y0) < 0.8 * 20 * 12  # tighter than the office


def test_generic_witness_path_is_collision_free(generic):
    """Through the lower passage and the middle passage, the hypotenuse of the
    L along the direction of travel, with 0.15 m to spare."""
    checker = GeometricChecker(generic)
    path = _waypoints(generic, [generic.start[:2], (4.9, 2.1), (8.2, 4.8), generic.goal[:2]])
    assert _path_clearance(checker, path) > 0.15


def test_generic_carrying_pose_makes_the_l_as_narrow_as_its_hull(generic):
    """In the start pose the L's extent across travel (y) equals the hull's
    minimal width: the altitude 3 * 2 / sqrt(3^2 + 2^2) = 1.664 m, plus the
    bar thickness; the base disc stays within that band."""
    geo = arm_geometry(generic)
    q = np.asarray(generic.start, float)
    seg = geo.segments(q)[2:]  # the two object bars
    ys = seg[..., 1]
    width = ys.max() - ys.min() + generic.object.thickness
    assert width == pytest.approx(6.0 / math.sqrt(13.0) + generic.object.thickness, abs=0.01)
    assert ys.min() < q[1] - generic.robot.base_radius and ys.max() > q[1] + generic.robot.base_radius


def test_generic_passages_block_the_l_turned_broadside(generic):
    """With the 3 m bar across the direction of travel (gripper angle 0), no
    base position in or at the passages of either partition is free."""
    checker = GeometricChecker(generic)
    arm = [generic.start[2], -generic.start[2]]  # psi1 + psi2 = 0
    ys = np.linspace(0.5, 9.5, 181)
    broadside = np.array([[x, y, *arm] for x in (5.5, 10.5) for y in ys])
    assert not checker.are_valid(broadside).any()
    # ... whereas in the carrying pose some position in each passage is free.
    carrying = np.array([[x, y, *generic.start[2:]] for x in (5.5, 10.5) for y in ys]).reshape(2, -1, 4)
    assert checker.are_valid(carrying[0]).any() and checker.are_valid(carrying[1]).any()


# ---- carrying poses ------------------------------------------------------------


@pytest.mark.parametrize("name", ["office_bar.yaml", "generic_L.yaml"])
def test_start_and_goal_hold_the_object_folded_over_the_base(name):
    """Link 2 is folded back: the gripper is within 0.3 m of the base centre
    (it could be up to l1 + l2 = 1.1 m away)."""
    scenario = load_scenario(SCENARIO_DIR / name)
    geo = arm_geometry(scenario)
    for q in (scenario.start, scenario.goal):
        base, _, gripper = (p for p in geo.joints(np.asarray(q, float)))
        assert np.linalg.norm(gripper - base) < 0.3


# ---- the README's annotated example ----------------------------------------------


def _readme_block(language: str) -> str:
    """The first fenced code block of the given language in README.md."""
    text = (SCENARIO_DIR.parent / "README.md").read_text()
    start = text.index(f"```{language}\n") + len(language) + 4
    return text[start : text.index("```", start)]


def test_readme_example_scenario_loads_and_is_collision_free(tmp_path):
    """The annotated example in the README is a valid scenario (every section,
    a !Bar object), with free start and goal."""
    path = tmp_path / "example.yaml"
    path.write_text(_readme_block("yaml"))
    dut = load_scenario(path)
    assert len(dut.world.obstacles) == 2 and dut.world.obstacles[1].yaw == pytest.approx(0.3)
    assert [p.name for p in dut.people] == ["faces south", "at desk"]
    assert isinstance(dut.object, Bar) and dut.planner.algorithm == "social_rrt_star"
    assert len(dut.social.weights) == arm_geometry(dut).num_interest_points
    clearance = GeometricChecker(dut).clearances(np.array([dut.start, dut.goal], float))
    assert np.all(clearance > 0.05)


@pytest.mark.parametrize("tag", ["!Bar {length: 1.5}", "!LShape {lengths: [3.0, 2.0]}",
                                 "!Polyline {points: [[0, -0.5], [0, 0.5], [0.4, 0.5]]}"])
def test_readme_object_kinds_load(tag):
    """The three object tags listed in the README comment are accepted."""
    dut = load_scenario(SCENARIO_DIR / "tiny.yaml", f"object: {tag}")
    assert type(dut.object).__name__ == tag.split()[0][1:]


# ---- walking people (issue 20) ----------------------------------------------------
# Routes checked by sampling them every 2 cm against the obstacles (the box
# distance above), the room bounds, the robot at its start and goal and each
# other: independent of drake_social.people's models and validation.

_ROUTE_STEP = 0.02  # metres between checked points of a route
_CLEAR = 0.1  # least room between a body and an obstacle or wall, metres


def _route_points(points) -> np.ndarray:
    """Points every _ROUTE_STEP along the polyline through ``points`` (N, 2)."""
    points = np.asarray(points, float)
    parts = [points[:1]]
    for a, b in zip(points[:-1], points[1:]):
        n = max(1, int(math.ceil(np.linalg.norm(b - a) / _ROUTE_STEP)))
        parts.append(a + np.linspace(0.0, 1.0, n + 1)[1:, None] * (b - a))
    return np.concatenate(parts)


def _obstacle_clearance(scenario, points: np.ndarray) -> float:
    """Smallest distance of ``points`` (N, 2) to the obstacles and the room's walls."""
    x0, y0, x1, y1 = scenario.world.bounds
    walls = min((points[:, 0] - x0).min(), (x1 - points[:, 0]).min(), (points[:, 1] - y0).min(),
                (y1 - points[:, 1]).min())
    return min([walls] + [_box_signed_distance(points, box).min() for box in scenario.world.obstacles])


def _scripted_xy(person, t: np.ndarray) -> np.ndarray:
    """Where a scripted person is at times ``t``: linear between waypoints, standing before and after, looping."""
    tr = np.asarray(person.trajectory, float)
    if person.loop:
        t = np.where(t > tr[-1, 0], tr[0, 0] + np.mod(t - tr[0, 0], tr[-1, 0] - tr[0, 0]), t)
    return np.stack([np.interp(t, tr[:, 0], tr[:, 1]), np.interp(t, tr[:, 0], tr[:, 2])], -1)


def _robot_gap(scenario, q, centres: np.ndarray, radius: float) -> float:
    """Smallest surface distance between the robot at configurations ``q`` (M, 4) and body discs at ``centres``."""
    from drake_social.people.proximity import part_distances

    geometry = arm_geometry(scenario)
    q = np.asarray(q, float).reshape(-1, 4)
    return float(part_distances(geometry, q, centres, np.full(len(centres), radius))["robot"].min())


def test_the_walking_scenarios_are_shipped():
    office, walkers = (load_scenario(SCENARIO_DIR / name) for name in ("office_bar.yaml", "office_walkers.yaml"))
    # The office of office_bar: only the people and the description differ.
    for field in ("world", "robot", "object", "start", "goal", "social", "planner", "execution", "random_seed"):
        assert getattr(walkers, field) == getattr(office, field), field
    scripted = [p for p in walkers.people if p.trajectory is not None]
    assert len(walkers.people) == 10 and len(scripted) >= 6 and sum(p.loop for p in scripted) >= 2
    lobby = load_scenario(SCENARIO_DIR / "lobby_crowd.yaml")
    assert 10 <= len(lobby.crowd.people) <= 15 and 1 <= len(lobby.people) <= 2
    assert isinstance(lobby.object, LShape) and any(p.cycle for p in lobby.crowd.people)


@pytest.mark.parametrize("path", SCENARIO_FILES, ids=lambda p: p.stem)
def test_scripted_routes_keep_clear(path):
    """Each scripted body stays _CLEAR from obstacles and walls along its whole
    route, starts where x, y say, is clear of the robot at start and goal when
    it stands there, and no two people come within 0.3 m of each other over
    the first 300 s (sampled every 0.02 s)."""
    scenario = load_scenario(path)
    t = np.arange(0.0, 300.0, 0.02)
    tracks = []
    for i, p in enumerate(scenario.people):
        if p.trajectory is None:
            tracks.append(np.broadcast_to([p.x, p.y], (len(t), 2)))
            continue
        tr = np.asarray(p.trajectory, float)
        assert tr[0, 1:] == pytest.approx([p.x, p.y]), f"person {i}: x, y are not the first point"
        assert not p.loop or tr[-1, 1:] == pytest.approx(tr[0, 1:]), f"person {i}: a loop must be closed"
        speeds = np.hypot(*np.diff(tr[:, 1:], axis=0).T) / np.diff(tr[:, 0])
        assert np.all(speeds <= 1.6), f"person {i}: walks at {speeds.max():.2f} m/s"
        assert _obstacle_clearance(scenario, _route_points(tr[:, 1:])) > p.radius + _CLEAR, f"person {i}"
        assert _robot_gap(scenario, [scenario.start, scenario.goal], tr[[0, -1], 1:], p.radius) > 0.3, f"person {i} stands in the robot's way"
        tracks.append(_scripted_xy(p, t))
    radii = [p.radius for p in scenario.people]
    for i in range(len(tracks)):
        for j in range(i):
            gap = np.linalg.norm(tracks[i] - tracks[j], axis=-1).min() - radii[i] - radii[j]
            assert gap > 0.3, f"people {j} and {i} come within {gap:.2f} m"


@pytest.mark.parametrize("path", SCENARIO_FILES, ids=lambda p: p.stem)
def test_crowd_goals_are_reachable_in_straight_lines(path):
    """Every leg of a crowd person (start, goals, back to the first goal when
    cycling) keeps _CLEAR from obstacles and walls, and 0.5 m from the standing
    people; nobody starts within 1 m of the robot's start."""
    scenario = load_scenario(path)
    if scenario.crowd is None:
        pytest.skip("no crowd")
    standing = np.array([[p.x, p.y] for p in scenario.people], float).reshape(-1, 2)
    standing_radii = np.array([p.radius for p in scenario.people])
    starts = []
    for i, p in enumerate(scenario.crowd.people):
        stops = [[p.x, p.y]] + [list(g) for g in p.goals] + ([list(p.goals[0])] if p.cycle else [])
        route = _route_points(stops)
        assert _obstacle_clearance(scenario, route) > p.radius + _CLEAR, f"crowd person {i}"
        if len(standing):
            gaps = np.linalg.norm(route[:, None] - standing[None], axis=-1) - standing_radii - p.radius
            assert gaps.min() > 0.5, f"crowd person {i} walks through a standing person"
        assert _robot_gap(scenario, scenario.start, np.array([[p.x, p.y]]), p.radius) > 1.0, f"crowd person {i}"
        starts.append((p.x, p.y, p.radius))
    bodies = starts + [(p.x, p.y, p.radius) for p in scenario.people]
    for k, a in enumerate(bodies):
        for b in bodies[:k]:
            assert math.hypot(a[0] - b[0], a[1] - b[1]) > a[2] + b[2] + 0.3
