"""Time-indexed safety against predicted people (collision.people_kernel, collision.people_safety),
checked against an independent computation: people.proximity.part_distances at Prediction.state_at(t)."""

from __future__ import annotations

import math
import time
from pathlib import Path

import numpy as np
import pytest

from drake_social.collision import people_kernel
from drake_social.collision.people_safety import PeopleSafety
from drake_social.collision.planar_checker import PlanarChecker
from drake_social.scenario.geometry import arm_geometry
from drake_social.people import without_people
from drake_social.people.prediction import Prediction
from drake_social.people.proximity import part_distances
from drake_social.scenario import load_scenario

SCENARIOS = Path(__file__).resolve().parents[2] / "scenarios"
SAFETY = 0.05


@pytest.fixture(scope="module")
def robot():
    scenario = load_scenario(SCENARIOS / "office_walkers.yaml")
    scene = PlanarChecker(without_people(scenario)).compiled_scene()
    return scene, arm_geometry(scenario)


def _prediction(rng, people=4, samples=30, t0=2.0, dt=0.1, standing=1, absent_rate=0.0, spread=1.5):
    """People doing piecewise-linear random walks around the origin (the first
    ``standing`` stand still); presence toggled at random when ``absent_rate``."""
    start = rng.uniform(-spread, spread, (1, people, 2))
    vel = rng.normal(0.0, 0.8, (samples - 1, people, 2))
    vel[:, :standing] = 0.0
    pos = start + np.concatenate([np.zeros((1, people, 2)), np.cumsum(vel * dt, axis=0)])
    present = rng.random((samples, people)) >= absent_rate
    step = np.diff(pos, axis=0)
    speeds = np.hypot(step[..., 0], step[..., 1]).max(axis=0) / dt if samples > 1 else np.zeros(people)
    return Prediction(t0=t0, dt=dt, positions=pos, headings=np.zeros((samples, people)), present=present,
                      radii=rng.uniform(0.15, 0.3, people), speeds=speeds, max_speeds=speeds,
                      names=tuple(f"p{i}" for i in range(people)))


def _exact(geometry, prediction, q, t):
    """The robot's distance to the people considered at t: part_distances at
    state_at(t), with the presence and beyond-horizon rules applied by hand."""
    state = prediction.state_at(t)
    considered = state.present & ((t <= prediction.horizon) | (prediction.max_speeds == 0.0))
    return part_distances(geometry, np.asarray(q, float).reshape(1, 4), state.positions, state.radii,
                          considered)["robot"][0]


def _dense(geometry, prediction, q_a, q_b, t_a, t_b, n=1501):
    """The exact distances (n,) at n evenly spaced u (one part_distances call)."""
    u = np.linspace(0.0, 1.0, n)
    qs = q_a + u[:, None] * (q_b - q_a)
    ts = t_a + u * (t_b - t_a)
    states = [prediction.state_at(t) for t in ts]
    centres = np.array([s.positions for s in states]).reshape(n, prediction.count, 2)
    considered = np.array([s.present & ((t <= prediction.horizon) | (prediction.max_speeds == 0.0))
                           for s, t in zip(states, ts)]).reshape(n, prediction.count)
    return part_distances(geometry, qs, centres, prediction.radii, considered)["robot"]


def _dense_min(geometry, prediction, q_a, q_b, t_a, t_b, n=1501):
    return float(_dense(geometry, prediction, q_a, q_b, t_a, t_b, n).min())


def _motion(rng, length=1.5):
    q_a = np.r_[rng.uniform(-1.5, 1.5, 2), rng.uniform(-math.pi, math.pi), rng.uniform(-2.5, 2.5)]
    heading = rng.uniform(-math.pi, math.pi)
    d = rng.uniform(0.2, length)
    q_b = q_a + np.r_[d * math.cos(heading), d * math.sin(heading), rng.uniform(-1.0, 1.0, 2)]
    return q_a, q_b, d / 0.5 + rng.uniform(0.0, 1.0)  # the duration: at most 0.5 m/s


def test_clearance_equals_part_distances(robot, rng):
    scene, geometry = robot
    for trial in range(40):
        pred = _prediction(rng, people=int(rng.integers(1, 6)), absent_rate=0.3, standing=int(rng.integers(0, 3)))
        safety = PeopleSafety(scene, pred, SAFETY)
        for _ in range(10):
            q = np.r_[rng.uniform(-2, 2, 2), rng.uniform(-math.pi, math.pi, 2)]
            t = rng.uniform(pred.t0 - 1.0, pred.horizon + 1.0)  # before, within and beyond the horizon
            ref = _exact(geometry, pred, q, t)
            got = safety.clearance(q, t)
            if math.isinf(ref):
                assert got == math.inf
            else:
                assert got == pytest.approx(ref, abs=1e-12)


def test_motion_check_is_sound_and_not_overly_conservative(robot, rng):
    """Random timed motions among random walkers: never clear where a dense
    sampling of the exact distance reaches safety; clear for (nearly) every
    motion whose dense minimum is > safety + 0.05."""
    scene, geometry = robot
    near, clear_cases, clear_said = 0, 0, 0
    for trial in range(400):
        pred = _prediction(rng, people=int(rng.integers(1, 5)), standing=int(rng.integers(0, 2)),
                           absent_rate=0.15 if trial % 2 else 0.0)
        q_a, q_b, duration = _motion(rng)
        t_a = rng.uniform(pred.t0 - 0.5, pred.horizon + 0.5)  # some motions cross the horizon or start beyond
        t_b = t_a + duration
        ok = PeopleSafety(scene, pred, SAFETY).motion_clear(q_a, q_b, t_a, t_b)
        d = _dense_min(geometry, pred, q_a, q_b, t_a, t_b, n=401)
        if d <= SAFETY:
            near += 1
            assert not ok, f"trial {trial}: dense minimum {d} <= safety yet said clear"
        elif d > SAFETY + 0.05 and pred.present.all():  # presence counts over a whole motion: exact without toggles
            clear_cases += 1
            clear_said += ok
    assert near > 50 and clear_cases > 50  # both kinds exercised
    assert clear_said / clear_cases >= 0.97


@pytest.mark.slow
def test_grazing_motions_are_caught(robot, rng):
    """People placed so the exact minimum is within a few millimetres of the
    safety distance, either side: every one at or below it is refused."""
    scene, geometry = robot
    below = 0
    for trial in range(150):
        pred = _prediction(rng, people=1, standing=int(trial % 2))
        q_a, q_b, duration = _motion(rng)
        t_a = pred.t0 + rng.uniform(0.0, 1.0)
        t_b = t_a + duration
        u = np.linspace(0, 1, 301)
        dists = _dense(geometry, pred, q_a, q_b, t_a, t_b, len(u))
        d, s = dists.min(), u[int(np.argmin(dists))]
        # Shift the person's whole track so the minimum becomes about safety + e.
        e = rng.uniform(-0.005, 0.005)
        if not np.isfinite(d):
            continue
        state = pred.state_at(t_a + s * (t_b - t_a))
        c = state.positions[0]
        q = q_a + s * (q_b - q_a)
        # Move along the direction away from the robot's base by (safety + e - d).
        away = (c - q[:2]) / max(np.linalg.norm(c - q[:2]), 1e-9)
        shifted = Prediction(t0=pred.t0, dt=pred.dt, positions=pred.positions + (SAFETY + e - d) * away,
                             headings=pred.headings, present=pred.present, radii=pred.radii, speeds=pred.speeds,
                             max_speeds=pred.max_speeds, names=pred.names)
        dense = _dense_min(geometry, shifted, q_a, q_b, t_a, t_b, n=2001)
        ok = PeopleSafety(scene, shifted, SAFETY).motion_clear(q_a, q_b, t_a, t_b)
        if dense <= SAFETY:
            below += 1
            assert not ok
    assert below > 20


def _standing(xy, radius=0.25, present=True, samples=11, t0=0.0, dt=0.5, speed=0.0, velocity=(0.0, 0.0)):
    """One person from ``xy`` at constant ``velocity`` (m/s) over ``samples`` samples."""
    times = t0 + dt * np.arange(samples)
    pos = np.asarray(xy, float)[None, None] + (times - t0)[:, None, None] * np.asarray(velocity, float)
    return Prediction(t0=t0, dt=dt, positions=pos, headings=np.zeros((samples, 1)),
                      present=np.full((samples, 1), present), radii=np.array([radius]),
                      speeds=np.array([speed]), max_speeds=np.array([speed]), names=("x",))


def test_a_walker_crossing_a_still_robot_mid_motion_is_caught(robot):
    """The robot turns its arm in place (the base still) while a walker passes
    through the base's position at t = 2.5 s: refused; the same walker an
    hour later (beyond the horizon, the robot's motion over) or a walker
    passing 3 m away: clear."""
    scene, geometry = robot
    q_a, q_b = np.array([0.0, 0.0, 0.0, 0.3]), np.array([0.0, 0.0, 0.2, 0.5])
    walker = _standing((-5.0, 0.0), samples=21, dt=0.5, speed=2.0, velocity=(2.0, 0.0))  # at x = 0 when t = 2.5
    safety = PeopleSafety(scene, walker, SAFETY)
    assert safety.clearance(q_a, 0.0) > 4.0 and safety.clearance(q_b, 5.0) > 3.0  # far at both ends
    assert _dense_min(geometry, walker, q_a, q_b, 0.0, 5.0) < 0  # the exact distance: they pass through the base
    assert not safety.motion_clear(q_a, q_b, 0.0, 5.0)
    assert safety.path_clear(np.array([q_a, q_a, q_b]), np.array([0.0, 0.1, 5.0])) == (False, 1)
    assert safety.motion_clear(q_a, q_b, 0.0, 0.5)  # over before they arrive
    far = _standing((-5.0, 3.0), samples=21, dt=0.5, speed=2.0, velocity=(2.0, 0.0))
    assert PeopleSafety(scene, far, SAFETY).motion_clear(q_a, q_b, 0.0, 5.0)


def test_beyond_the_horizon_only_standing_people_count(robot):
    scene, _ = robot
    q = np.array([0.0, 0.0, 0.0, 0.0])
    # A walker who, at the horizon's end (t = 5), stands on the robot; after it, not considered.
    walker = _standing((-5.0, 0.0), samples=11, dt=0.5, speed=1.0, velocity=(1.0, 0.0))
    safety = PeopleSafety(scene, walker, SAFETY)
    assert safety.clearance(q, 5.0) < 0  # at the horizon: considered, overlapping
    assert safety.clearance(q, 5.0 + 1e-6) == math.inf  # beyond: not
    assert safety.motion_clear(q, q, 5.5, 9.0)  # wholly beyond the horizon
    assert not safety.motion_clear(q, q, 4.0, 9.0)  # reaches the robot at t = 5
    # A standing person holds beyond the horizon.
    stand = PeopleSafety(scene, _standing((0.2, 0.0)), SAFETY)
    assert stand.clearance(q, 100.0) < 0 and not stand.motion_clear(q, q, 50.0, 60.0)
    # Before t0 the first sample holds.
    late = PeopleSafety(scene, _standing((-5.0, 0.0), t0=10.0, speed=1.0, velocity=(1.0, 0.0)), SAFETY)
    assert late.clearance(q, 0.0) == pytest.approx(late.clearance(q, 10.0), abs=1e-15)


def test_absent_people_do_not_count_and_presence_counts_over_the_motion(robot):
    scene, _ = robot
    q = np.zeros(4)
    absent = PeopleSafety(scene, _standing((0.0, 0.0), present=False), SAFETY)
    assert absent.clearance(q, 1.0) == math.inf and absent.motion_clear(q, q, 0.0, 5.0)
    # Present only from sample 6 (t = 3.0) on, standing on the robot.
    base = _standing((0.0, 0.0))
    present = np.zeros((11, 1), bool)
    present[6:] = True
    enters = Prediction(t0=0.0, dt=0.5, positions=base.positions, headings=base.headings, present=present,
                        radii=base.radii, speeds=base.speeds, max_speeds=base.max_speeds, names=base.names)
    safety = PeopleSafety(scene, enters, SAFETY)
    assert safety.clearance(q, 2.99) == math.inf and safety.clearance(q, 3.0) < 0
    assert safety.motion_clear(q, q, 0.0, 2.9)
    assert not safety.motion_clear(q, q, 0.0, 3.2)
    # Wholly after the entry (the sample at or before t = 3.1 is sample 6, present).
    assert not safety.motion_clear(q, q, 3.1, 3.2)


def test_safety_distance_is_strict(robot):
    """Clearance exactly the safety distance is refused; a little more passes."""
    scene, _ = robot
    q = np.zeros(4)
    probe = PeopleSafety(scene, _standing((3.0, 0.0), radius=0.25), 0.0)
    d = probe.clearance(q, 0.0)
    assert PeopleSafety(scene, _standing((3.0, 0.0), radius=0.25), d).clearance(q, 0.0) == d
    assert not PeopleSafety(scene, _standing((3.0, 0.0), radius=0.25), d).motion_clear(q, q, 0.0, 1.0)
    assert PeopleSafety(scene, _standing((3.0, 0.0), radius=0.25), d - 1e-6).motion_clear(q, q, 0.0, 1.0)
    assert PeopleSafety(scene, _standing((3.0, 0.0), radius=0.25), d - 1e-6).path_clear(np.array([q]), [0.0]) \
        == (True, -1)
    assert PeopleSafety(scene, _standing((3.0, 0.0), radius=0.25), d).path_clear(np.array([q]), [0.0]) == (False, 0)


def test_kernel_with_nobody(robot):
    scene, _ = robot
    xy, present = np.zeros((3, 0, 2)), np.zeros((3, 0), bool)
    empty = np.zeros(0)
    q = np.zeros(4)
    assert people_kernel.people_clearance(q, 0.0, scene.bodies, scene.robot, xy, present, empty, empty, 0.0, 0.1) \
        == math.inf
    assert people_kernel.motion_clear_of_people(q, q + 1, 0.0, 1.0, scene.bodies, scene.robot, scene.levers, xy,
                                                present, empty, empty, 0.0, 0.1, SAFETY)


def test_bad_arguments(robot):
    scene, _ = robot
    pred = _standing((3.0, 0.0))
    with pytest.raises(TypeError, match="PeopleSafety: scene must be a PlanarScene"):
        PeopleSafety("planar", pred, SAFETY)
    with pytest.raises(TypeError, match="PeopleSafety: prediction must be"):
        PeopleSafety(scene, None, SAFETY)
    with pytest.raises(ValueError, match="PeopleSafety: safety must be >= 0"):
        PeopleSafety(scene, pred, -0.1)
    with pytest.raises(TypeError, match="PeopleSafety: safety must be a finite number"):
        PeopleSafety(scene, pred, "0.1")
    lying = Prediction(t0=0.0, dt=0.5, positions=_standing((0, 0), velocity=(1.0, 0.0)).positions,
                       headings=pred.headings, present=pred.present, radii=pred.radii, speeds=pred.speeds,
                       max_speeds=np.array([0.5]), names=pred.names)
    with pytest.raises(ValueError, match=r"max_speeds\[0\] = 0.5 m/s is below"):
        PeopleSafety(scene, lying, SAFETY)
    safety = PeopleSafety(scene, pred, SAFETY)
    with pytest.raises(ValueError, match="PeopleSafety.clearance: q: must be a \\(4,\\) array"):
        safety.clearance(np.zeros(3), 0.0)
    with pytest.raises(TypeError, match="PeopleSafety.clearance: t must be a finite number"):
        safety.clearance(np.zeros(4), None)
    with pytest.raises(ValueError, match="t_b must be >= t_a"):
        safety.motion_clear(np.zeros(4), np.ones(4), 2.0, 1.0)
    with pytest.raises(ValueError, match="PeopleSafety.path_clear: times: must be"):
        safety.path_clear(np.zeros((3, 4)), [0.0, 1.0])
    with pytest.raises(ValueError, match=r"times must be non-decreasing, got times\[1\]"):
        safety.path_clear(np.zeros((3, 4)), [0.0, 2.0, 1.0])
    with pytest.raises(ValueError, match="PeopleSafety.path_clear: waypoints: must be"):
        safety.path_clear(np.zeros((0, 4)), [])


def test_speed_on_office_walker_like_inputs(robot, rng):
    """Reported, loosely bounded: 10 people, 1.5 m motions (the number is in the report)."""
    scene, _ = robot
    pred = _prediction(rng, people=10, samples=51, t0=0.0, dt=0.1, standing=3, spread=4.0)
    xy, present = np.ascontiguousarray(pred.positions), np.ascontiguousarray(pred.present)
    motions = []
    for _ in range(500):
        q_a, q_b, duration = _motion(rng)
        t_a = rng.uniform(0.0, 4.0)
        motions.append((q_a, q_b, t_a, t_a + duration))
    args = (scene.bodies, scene.robot, scene.levers, xy, present, pred.radii, pred.max_speeds, 0.0, 0.1, SAFETY)
    people_kernel.motion_clear_of_people(*motions[0], *args)
    start = time.perf_counter()
    for m in motions:
        people_kernel.motion_clear_of_people(*m, *args)
    per_call = (time.perf_counter() - start) / len(motions)
    assert per_call < 1e-3


@pytest.mark.slow
def test_motion_check_is_sound_in_odd_cases(robot, rng):
    """Fast walkers, one-sample predictions, late t0 (rounding), zero-length
    and zero-duration motions, safety 0 .. 0.3 m: never a false clear."""
    scene, geometry = robot
    near = 0
    for trial in range(300):
        people, samples = int(rng.integers(1, 4)), int(rng.integers(1, 25))
        dt, t0 = float(rng.choice([0.05, 0.1, 0.3])), float(rng.choice([0.0, 1000.0, 12345.678]))
        walk = np.cumsum(rng.normal(0.0, 2.5, (samples - 1, people, 2)) * dt, axis=0)
        pos = rng.uniform(-1.5, 1.5, (1, people, 2)) + np.concatenate([np.zeros((1, people, 2)), walk])
        pos[:, :int(rng.integers(0, 2))] = pos[:1, :1]  # sometimes one stands
        step = np.diff(pos, axis=0)
        speeds = np.hypot(step[..., 0], step[..., 1]).max(axis=0) / dt if samples > 1 else np.zeros(people)
        pred = Prediction(t0=t0, dt=dt, positions=pos, headings=np.zeros((samples, people)),
                          present=rng.random((samples, people)) > 0.1, radii=rng.uniform(0.1, 0.3, people),
                          speeds=speeds, max_speeds=speeds, names=tuple(map(str, range(people))))
        q_a, q_b, duration = _motion(rng, 3.0)
        if trial % 5 == 0:
            q_b = q_a.copy()
        t_a = t0 + rng.uniform(-0.5, (samples - 1) * dt + 0.5)
        t_b = t_a + (duration if trial % 7 else 0.0)
        safety = float(rng.choice([0.0, 0.05, 0.3]))
        if _dense_min(geometry, pred, q_a, q_b, t_a, t_b, n=1001) <= safety:
            near += 1
            assert not PeopleSafety(scene, pred, safety).motion_clear(q_a, q_b, t_a, t_b), f"trial {trial}"
    assert near > 50
