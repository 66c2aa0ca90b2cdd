"""Every object and robot shape that validation accepts builds in every model.

The models are the SDFormat text and Drake's plant (``build_robot_diagram``),
the planar checker read back from the SceneGraph, the pure-numpy checker, the
social cost and the robot's drawing. A property test draws object and robot
dimensions across the ranges ``validate_scenario`` accepts, with weight on
their edges (micrometre and kilometre sizes, segments shorter than, as long
as and just longer than the object's thickness, links wider than long,
repeated vertices, interest points on and far from the object) and asserts that validation either refuses the scenario
with a ScenarioError naming an object or robot field, or every model builds
and the three checkers agree.

The fixed cases are the shapes of issue 18 (item 11), which the planar
checker refused with "a robot box that is not a stadium".

Drake's checker runs serially here: one run of the property with its
parallel CheckConfigsCollisionFree spun for over 10 minutes of CPU on a
loaded two-core machine, where the same examples take 13 s.
"""

from __future__ import annotations

import dataclasses as dc
import math
import re

import numpy as np
import pytest
from hypothesis import event, given, settings
from hypothesis import strategies as st
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from drake_social.cost import SocialCost
from drake_social.kinematics import ArmGeometry
from drake_social.scenario.geometry import arm_geometry
from drake_social.collision.drake_checker import SceneGraphChecker
from drake_social.collision.planar_checker import PlanarChecker
from drake_social.model.plant import build_robot_diagram
from drake_social.collision.geometric import GeometricChecker
from drake_social.scenario import (
    MAX_OBJECT_POINTS,
    Bar,
    LShape,
    Polyline,
    Robot,
    ScenarioError,
    validate_scenario,
)
from drake_social.viz.robot import draw_robot
from drake_social.viz.world import draw_world


def check_every_model(scenario, n_configs: int = 40, seed: int = 0) -> None:
    """Builds every model of ``scenario`` and checks that they agree.

    On ``n_configs`` configurations (uniform in the limits, plus start and
    goal): the planar and numpy clearances are equal to 1e-9 m where
    positive and both <= 1e-9 where not; validity equals Drake's wherever the
    clearance is more than 1e-6 m from 0; the planar checker's capsules are
    the scenario's (``ArmGeometry.segments`` and ``segment_radii``); the
    social cost is finite; the robot draws.
    """
    model = build_robot_diagram(scenario)
    planar = PlanarChecker(scenario, model=model)
    numpy_ = GeometricChecker(scenario)
    drake = SceneGraphChecker(scenario, parallelism=False)  # serial: see the module docstring
    rng = np.random.default_rng(seed)
    qs = np.vstack([rng.uniform(planar.lower, planar.upper, (n_configs, 4)), scenario.start, scenario.goal])

    c_planar, c_numpy = planar.clearances(qs), numpy_.clearances(qs)
    pos = c_planar > 0
    np.testing.assert_allclose(c_numpy[pos], c_planar[pos], atol=1e-9, rtol=0)
    assert np.all(c_numpy[~pos] <= 1e-9)
    clear = np.abs(c_planar) > 1e-6
    np.testing.assert_array_equal(planar.are_valid(qs)[clear], drake.are_valid(qs)[clear])
    np.testing.assert_array_equal(planar.are_valid(qs)[clear], numpy_.are_valid(qs)[clear])

    # The capsules read back from the SceneGraph are the scenario's segments
    # (the object's zero-length segments are discs in both).
    geometry = arm_geometry(scenario)
    q = qs[0]
    want = [(*s[0], *s[1], r) for s, r in zip(geometry.segments(q[None])[0], geometry.segment_radii)]
    want.append((q[0], q[1], q[0], q[1], geometry.base_radius))
    got = planar.capsules(q)

    def inside(g, w) -> bool:
        """Capsule g lies in capsule w (to 1e-9 m): both of its end discs do (capsules are convex)."""
        a, b = np.asarray(w[:2]), np.asarray(w[2:4])
        d = b - a
        for p in (np.asarray(g[:2]), np.asarray(g[2:4])):
            t = np.clip(np.dot(p - a, d) / np.dot(d, d), 0.0, 1.0) if np.dot(d, d) > 0 else 0.0
            if np.hypot(*(p - a - t * d)) + g[4] > w[4] + 1e-9:
                return False
        return True

    # The same union: each capsule of one lies in a capsule of the other.
    assert all(any(inside(w, g) for g in got) for w in want), (want, got)
    assert all(any(inside(g, w) for w in want) for g in got), (want, got)

    cost = SocialCost.from_scenario(scenario)
    assert np.all(np.isfinite(cost(qs)))
    assert np.all(np.isfinite(cost.motion_cost(qs[:-1], qs[1:])))

    fig = Figure(figsize=(4, 3))
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    draw_world(ax, scenario, names=False)
    artists = draw_robot(ax, geometry, np.asarray(scenario.start, float))
    assert artists["object"] and artists["link1"] and artists["link2"]
    fig.canvas.draw()


def _with(scenario, *, robot: dict | None = None, obj=None):
    out = dc.replace(scenario, robot=dc.replace(scenario.robot, **(robot or {})))
    if obj is not None:
        out = dc.replace(out, object=obj)
    return out


# ---- the shapes of issue 18 -----------------------------------------------------------


ISSUE_SHAPES = {
    "bar_0.01": dict(obj=Bar(length=0.01, thickness=0.05)),
    "L_0.01_0.5": dict(obj=LShape(lengths=[0.01, 0.5], thickness=0.05)),
    "polyline_short_segment": dict(obj=Polyline(points=[[0, -0.5], [0, 0.5], [0.01, 0.5], [0.01, 0.5], [0.4, 0.52]],
                                                thickness=0.05)),
    "link_width_0.7": dict(robot={"link_width": 0.7}),
}


@pytest.mark.parametrize("name", list(ISSUE_SHAPES))
def test_shapes_shorter_than_wide_build_and_agree(name, tiny_scenario):
    scenario = _with(tiny_scenario, **ISSUE_SHAPES[name])
    validate_scenario(scenario)
    check_every_model(scenario, n_configs=300)


def test_a_polyline_longer_than_the_limit_is_refused_by_name(tiny_scenario):
    t = np.linspace(-math.pi / 2, math.pi / 2, MAX_OBJECT_POINTS + 1)
    points = np.c_[0.3 * np.cos(t) - 0.3, 0.6 * np.sin(t)].tolist()
    with pytest.raises(ScenarioError) as e:
        validate_scenario(_with(tiny_scenario, obj=Polyline(points=points, thickness=0.05)), "s.yaml")
    assert str(e.value) == (f"s.yaml: object.points: at most {MAX_OBJECT_POINTS} vertices (each is a collision "
                            f"shape of the model, checked at every step of a motion), got {MAX_OBJECT_POINTS + 1}; a "
                            f"polyline through fewer of its vertices approximates a smooth curve")
    validate_scenario(_with(tiny_scenario, obj=Polyline(points=points[:MAX_OBJECT_POINTS], thickness=0.05)))


@pytest.mark.parametrize("field, change, message", [
    ("robot.link_width", dict(robot={"link_width": 1e6}),
     "must be < 5 m in this room (the links' width must be less than its smaller side, 5 m, or the robot touches "
     "a wall everywhere), got 1000000.0"),
    ("robot.base_radius", dict(robot={"base_radius": 2.5}),
     "must be < 2.5 m in this room (the base's diameter must be less than its smaller side, 5 m, or the robot "
     "touches a wall everywhere), got 2.5"),
    ("object.thickness", dict(obj=Bar(length=1.5, thickness=5.0)),
     "must be < 5 m in this room (the object's thickness must be less than its smaller side, or the object "
     "touches a wall everywhere), got 5.0"),
])
def test_a_part_as_wide_as_the_room_is_refused_by_name(tiny_scenario, field, change, message):
    """Drake's distance queries stalled (minutes) on a link or object 10^6 m wide in the 8 x 5 m room."""
    with pytest.raises(ScenarioError) as e:
        validate_scenario(_with(tiny_scenario, **change), "s.yaml")
    assert str(e.value) == f"s.yaml: {field}: {message}"


def test_parts_just_narrower_than_the_room_build(tiny_scenario):
    scenario = _with(tiny_scenario, robot={"base_radius": 2.499999, "link_width": 4.999999},
                     obj=Bar(length=1.5, thickness=4.999999))
    scenario = dc.replace(scenario, people=[])  # the standing person would start inside so wide a robot
    validate_scenario(scenario)
    check_every_model(scenario, n_configs=20)


# ---- the property ---------------------------------------------------------------------

#: Sizes at the edges of what validation accepts (> 0, finite), metres.
_EDGE_SIZES = [1e-9, 1e-6, 1e-3, 0.01, 0.05, 0.08, 0.35, 0.7, 1.5, 10.0, 1000.0]
sizes = st.one_of(st.sampled_from(_EDGE_SIZES), st.floats(1e-9, 3.0))


@st.composite
def segment_length(draw, thickness: float, zero: bool = False) -> float:
    """A segment's length: at the edges relative to the thickness (0 if
    ``zero``: a repeated vertex), or any size."""
    edges = [thickness * (1 - 1e-12), thickness, thickness * (1 + 1e-12), thickness / 2] + ([0.0] if zero else [])
    return draw(st.one_of(st.sampled_from(edges), sizes))


@st.composite
def interest_points(draw):
    """None (the defaults) or 1-3 points, on the object or far from it, metres."""
    coordinate = st.one_of(st.sampled_from([0.0, 1e-9, -1e-9]), sizes, sizes.map(lambda v: -v))
    return draw(st.one_of(st.none(), st.lists(st.lists(coordinate, min_size=2, max_size=2), min_size=1, max_size=3)))


@st.composite
def objects(draw):
    thickness = draw(sizes)
    kind = draw(st.sampled_from(["bar", "lshape", "polyline"]))
    interest = draw(interest_points())
    if kind == "bar":
        length = draw(segment_length(thickness))
        return Bar(length=length, thickness=thickness, interest_points=interest)
    if kind == "lshape":
        lengths = [draw(segment_length(thickness)) for _ in range(2)]
        return LShape(lengths=lengths, thickness=thickness, interest_points=interest)
    n = draw(st.integers(2, 7))
    point, heading, points = np.zeros(2), 0.0, [[0.0, 0.0]]
    for _ in range(n - 1):
        heading += draw(st.sampled_from([0.0, math.pi / 2, -math.pi / 2, math.pi, 1e-6, 2.5]))
        point = point + draw(segment_length(thickness, zero=True)) * np.array([math.cos(heading), math.sin(heading)])
        points.append(point.tolist())
    return Polyline(points=points, thickness=thickness, interest_points=draw(interest_points()))


@st.composite
def robots(draw):
    return Robot(base_radius=draw(sizes), link_lengths=[draw(sizes), draw(sizes)], link_width=draw(sizes))


@pytest.mark.slow
@settings(max_examples=80)
@given(obj=objects(), robot=robots())
def test_every_accepted_shape_builds_in_every_model(tiny_scenario, obj, robot):
    scenario = dc.replace(tiny_scenario, object=obj, robot=dc.replace(robot, joint_lower=tiny_scenario.robot.joint_lower,
                                                                     joint_upper=tiny_scenario.robot.joint_upper))
    try:
        validate_scenario(scenario, "s.yaml")
    except ScenarioError as e:
        # people[0]: the standing person inside a large robot or object at its start.
        assert re.match(r"s\.yaml: (object|robot|social\.resolution|people\[0\])[.\[:]", str(e)), str(e)
        event(f"refused: {str(e).split(':')[1].strip()}")
        return
    event("accepted")
    check_every_model(scenario, n_configs=20)
