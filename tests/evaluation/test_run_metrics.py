"""run_metrics against hand computations on hand-built runs.

The robot of every run: base disc radius 0.35 m, links 0.6 m and 0.5 m
(capsule radius 0.04 m), a 1.5 m bar (capsule radius 0.025 m). With
psi1 = 0 and psi2 = pi/2 the first link points along +x from the base centre
(x, y), the second up to the gripper (x + 0.6, y + 0.5), and the bar lies
horizontal at y + 0.5 from x - 0.15 to x + 1.35. People's bodies are discs of
radius 0.25 m.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import quad

from drake_social.cost.social import SocialCost
from drake_social.evaluation.metrics import (
    RUN_PARTS,
    ZONES,
    executed_metrics,
    part_agf,
    run_metrics,
    trajectory_metrics,
)
from drake_social.scenario.geometry import arm_geometry
from drake_social.people import people_model
from drake_social.people.log import PeopleLog
from drake_social.scenario import load_scenario

_ROOM = """
description: "run metrics"
world: {bounds: [0.0, -10.0, 40.0, 10.0]}
people:
%(people)s
robot: {base_radius: 0.35, link_lengths: [0.6, 0.5], link_width: 0.08}
object: !Bar {length: 1.5, thickness: 0.05}
start: [1.0, 2.5, 0.0, 1.5707963267948966]
goal: [19.0, 2.5, 0.0, 1.5707963267948966]
social: {speed_scaling: %(scaling)s}
"""
_UP = math.pi / 2
_OFFSET = 0.35 + 0.25  # base radius + body radius


def _scenario(tmp_path, people: str = "  []", scaling: bool = False):
    path = tmp_path / "run.yaml"
    path.write_text(_ROOM % {"people": people, "scaling": str(scaling).lower()})
    return load_scenario(path)


def _q(x, y) -> np.ndarray:
    x = np.broadcast_to(np.asarray(x, float), np.shape(x) or (1,))
    return np.column_stack([x, np.broadcast_to(y, x.shape), np.zeros_like(x), np.full_like(x, _UP)])


def _log(times, positions, present=None, headings=None, velocities=None) -> PeopleLog:
    """A log of people at ``positions`` (T, P, 2); velocities by differences when not given."""
    times = np.asarray(times, float)
    positions = np.asarray(positions, float)
    t, p = positions.shape[:2]
    if velocities is None:
        velocities = np.gradient(positions, times, axis=0) if t > 1 else np.zeros_like(positions)
    return PeopleLog(times=times, positions=positions,
                     headings=np.zeros((t, p)) if headings is None else headings, velocities=velocities,
                     present=np.ones((t, p), bool) if present is None else present, radii=np.full(p, 0.25),
                     names=tuple(f"p{i}" for i in range(p)))


def _segment_distance(p, a, b) -> float:
    """Distance from point p to segment a-b, by the clamped projection."""
    p, a, b = (np.asarray(v, float) for v in (p, a, b))
    s = min(1.0, max(0.0, float(np.dot(p - a, b - a) / np.dot(b - a, b - a))))
    return float(np.linalg.norm(p - (a + s * (b - a))))


# ---- a robot at constant speed along x passing a person walking along y -------------------------------

def _crossing(tmp_path, dt=0.01):
    """Robot base at (1 + 0.5 t, 2.5), person at (10, -4 + 0.25 t), t in [0, 36] s."""
    times = np.arange(0.0, 36.0 + dt / 2, dt)
    q = _q(1.0 + 0.5 * times, 2.5)
    person = np.stack([np.full_like(times, 10.0), -4.0 + 0.25 * times], -1)[:, None, :]
    return _scenario(tmp_path), times, q, _log(times, person)


def test_crossing_base_distance_zones_and_mean_by_hand(tmp_path):
    scenario, times, q, people = _crossing(tmp_path)
    dut = run_metrics(scenario, times, q, people, None, True, 40.0)
    # Centre distance squared f(t) = (0.5 t - 9)^2 + (6.5 - 0.25 t)^2 = 0.3125 t^2 - 12.25 t + 123.25.
    a, b, c = 0.3125, -12.25, 123.25
    t_min = -b / (2 * a)  # 19.6 s
    assert dut["min_dist_base"] == pytest.approx(math.sqrt(a * t_min**2 + b * t_min + c) - _OFFSET, abs=1e-6)

    def inside(bound: float) -> float:
        """Seconds with the base's surface distance below ``bound``: f(t) < (bound + offset)^2."""
        disc = b * b - 4 * a * (c - (bound + _OFFSET) ** 2)
        return 0.0 if disc <= 0 else math.sqrt(disc) / a

    expected = {"intimate": inside(0.45), "personal": inside(1.2) - inside(0.45),
                "social": inside(3.6) - inside(1.2)}
    expected["public"] = 36.0 - sum(expected.values())
    # The profile reaches the personal zone, never the intimate one; every crossing is inside the run.
    assert expected["intimate"] == 0.0 and 0.5 < expected["personal"] and expected["social"] < 36.0
    for zone, seconds in expected.items():
        # Sample-and-hold: each boundary crossing is off by less than one step.
        assert dut[f"time_{zone}_base"] == pytest.approx(seconds, abs=2 * 0.01 + 1e-9), zone
        assert dut[f"share_{zone}_base"] == pytest.approx(dut[f"time_{zone}_base"] / 36.0, rel=1e-12)
    assert sum(dut[f"share_{z}_base"] for z in ZONES.names) == pytest.approx(1.0, abs=1e-12)
    mean, _ = quad(lambda t: math.sqrt(a * t * t + b * t + c) - _OFFSET, 0.0, 36.0, points=[t_min])
    assert dut["mean_dist_base"] == pytest.approx(mean / 36.0, abs=1e-5)
    assert dut["space_compliance_base"] == 1.0 and dut["collisions_base"] == 0.0
    assert dut["path_length_base"] == pytest.approx(18.0, abs=1e-9)
    assert dut["speed_mean_base"] == pytest.approx(0.5, abs=1e-9) and dut["speed_max_base"] == pytest.approx(0.5)
    assert dut["accel_max_base"] == pytest.approx(0.0, abs=1e-6) and dut["irregularity_base"] == 0.0
    assert dut["success"] == 1.0 and dut["time_to_goal"] == pytest.approx(36.0) and dut["timeout"] == 0.0
    assert dut["people_count"] == 1.0 and dut["people_moving"] == 1.0


def test_crossing_arm_and_object_distances_by_clamped_projection(tmp_path):
    scenario, times, q, people = _crossing(tmp_path, dt=0.05)
    dut = run_metrics(scenario, times, q, people, None, True, 40.0)
    arm, bar = [], []
    for t in times:
        x, p = 1.0 + 0.5 * t, (10.0, -4.0 + 0.25 * t)
        arm.append(min(_segment_distance(p, (x, 2.5), (x + 0.6, 2.5)),
                       _segment_distance(p, (x + 0.6, 2.5), (x + 0.6, 3.0))) - 0.04 - 0.25)
        bar.append(_segment_distance(p, (x - 0.15, 3.0), (x + 1.35, 3.0)) - 0.025 - 0.25)
    assert dut["min_dist_arm"] == pytest.approx(min(arm), abs=1e-9)
    assert dut["min_dist_object"] == pytest.approx(min(bar), abs=1e-9)
    assert dut["min_dist_robot"] == min(dut[f"min_dist_{p}"] for p in ("base", "arm", "object"))
    # The whole robot is never farther than any of its parts.
    assert dut["time_public_robot"] <= min(dut[f"time_public_{p}"] for p in ("base", "arm", "object"))
    near = {p: sum(dut[f"time_{z}_{p}"] for z in ("intimate", "personal", "social")) for p in RUN_PARTS}
    assert near["robot"] >= max(near["base"], near["arm"], near["object"])


# ---- contact episodes, absent people, stops --------------------------------------------------------------

def _pass_back_and_forth(dt=0.01):
    """A standing robot at (5, 2.5); a person walks x = 0 -> 3.2 -> 0 along y = 2.5 (on the
    base's side away from the arm) at 0.4 m/s: 8 s out, 8 s back."""
    times = np.arange(0.0, 16.0 + dt / 2, dt)
    x = np.where(times <= 8.0, 0.4 * times, 3.2 - 0.4 * (times - 8.0))
    return times, _q(np.full_like(times, 5.0), 2.5), x


def test_two_contact_episodes_of_known_duration(tmp_path):
    times, q, x = _pass_back_and_forth()
    scenario = _scenario(tmp_path)
    people = _log(times, np.stack([x, np.full_like(x, 2.5)], -1)[:, None, :])
    dut = run_metrics(scenario, times, q, people, None, False, 16.0)
    # Contact: 5 - x <= 0.6, x >= 4.4 ... never (the person turns at 3.2): no episode.
    assert dut["collisions_base"] == 0.0 and dut["collision_time_base"] == 0.0
    assert dut["min_dist_base"] == pytest.approx(5.0 - 3.2 - _OFFSET, abs=1e-9)
    # Walk to x = 4.8 instead (turn at t = 12 s): contact while x >= 4.4, from t = 11 s to t = 13 s.
    x = np.where(times <= 12.0, 0.4 * times, 4.8 - 0.4 * (times - 12.0))
    people = _log(times, np.stack([x, np.full_like(x, 2.5)], -1)[:, None, :])
    dut = run_metrics(scenario, times, q, people, None, False, 16.0)
    assert dut["collisions_base"] == 1.0 and dut["collision_time_base"] == pytest.approx(2.0, abs=0.01 + 1e-9)
    # Who made it needs the commands (tests/experiments/test_contact_classes.py); not recorded here.
    assert math.isnan(dut["collisions_moving_base"]) and dut["collisions_appeared_base"] == 0.0
    assert dut["min_dist_base"] == pytest.approx(5.0 - 4.8 - _OFFSET, abs=1e-9)
    # Two passes: out and back twice (turns at 4 s, 8 s, 12 s between x = 3.2 and 4.8).
    tri = 3.2 + 1.6 * np.abs(((times / 4.0) % 2.0) - 1.0)  # 4.8 at t = 0, 8, 16; 3.2 at 4, 12
    people = _log(times, np.stack([tri, np.full_like(tri, 2.5)], -1)[:, None, :])
    dut = run_metrics(scenario, times, q, people, None, False, 16.0)
    # x >= 4.4 within 1 s of t = 0, 8, 16: episodes [0, 1], [7, 9], [15, 16] s.
    assert dut["collisions_base"] == 3.0
    assert dut["collision_time_base"] == pytest.approx(1.0 + 2.0 + 1.0, abs=3 * 0.01 + 1e-9)
    assert dut["timeout"] == 1.0 and dut["success"] == 0.0 and math.isnan(dut["time_to_goal"])


def test_absent_people_are_ignored_and_presence_windows_count(tmp_path):
    times, q, x = _pass_back_and_forth(dt=0.25)
    scenario = _scenario(tmp_path)
    walker = np.stack([x, np.full_like(x, 2.5)], -1)
    alone = run_metrics(scenario, times, q, _log(times, walker[:, None, :]), None, True, 16.0)
    # A second person standing inside the base, never present, changes nothing.
    ghost = np.broadcast_to([5.0, 2.5], walker.shape)
    present = np.column_stack([np.ones(len(times), bool), np.zeros(len(times), bool)])
    both = run_metrics(scenario, times, q, _log(times, np.stack([walker, ghost], 1), present), None, True, 16.0)
    for key, value in alone.items():
        if key in ("people_count", "people_moving"):
            continue
        assert both[key] == pytest.approx(value, nan_ok=True, abs=0.0), key
    # Present from t = 2 s up to (not including) t = 3 s: samples 2.0, 2.25, 2.5, 2.75, each held 0.25 s,
    # 0.2 m from the base's surface: 1 s in the intimate zone, no contact.
    close = np.broadcast_to([5.0 - _OFFSET - 0.2, 2.5], walker.shape)
    present[:, 1] = (times >= 2.0) & (times < 3.0)
    dut = run_metrics(scenario, times, q, _log(times, np.stack([walker, close], 1), present), None, True, 16.0)
    assert dut["time_intimate_base"] == pytest.approx(1.0, abs=1e-12)
    assert dut["min_dist_base"] == pytest.approx(0.2, abs=1e-9) and dut["collisions_base"] == 0.0
    assert dut["space_compliance_base"] == pytest.approx(1.0 - 1.0 / 16.0, abs=1e-12)


def test_zone_times_on_a_hand_built_profile_at_uneven_times(tmp_path):
    scenario = _scenario(tmp_path)
    rng = np.random.default_rng(7)
    times = np.cumsum(rng.uniform(0.05, 0.5, 40))
    # Surface distances of the base: 10 samples in each zone, public first.
    d = np.repeat([5.0, 2.0, 0.8, 0.2], 10)
    person = np.stack([5.0 - _OFFSET - d, np.full_like(d, 2.5)], -1)[:, None, :]
    dut = run_metrics(scenario, times, _q(np.full_like(d, 5.0), 2.5), _log(times, person), None, True, 100.0)
    hold = np.append(np.diff(times), 0.0)
    for k, zone in enumerate(("public", "social", "personal", "intimate")):
        assert dut[f"time_{zone}_base"] == pytest.approx(hold[10 * k:10 * k + 10].sum(), abs=1e-12), zone
    assert dut["mean_dist_base"] == pytest.approx(np.trapezoid(d, times) / (times[-1] - times[0]), rel=1e-12)
    assert dut["people_moving"] == 1.0


def test_stopped_time_and_episodes(tmp_path):
    scenario = _scenario(tmp_path)
    times = np.array([0.0, 0.5, 1.0, 2.0, 2.5, 4.0, 5.0])
    stopped = np.array([False, True, True, False, True, False, True])
    q = _q(np.linspace(1.0, 2.0, len(times)), 2.5)
    dut = run_metrics(scenario, times, q, None, stopped, True, 10.0)
    assert dut["stop_count"] == 3.0
    assert dut["stopped_time"] == pytest.approx(0.5 + 1.0 + 1.5 + 0.0, abs=1e-12)
    assert dut["stopped_share"] == pytest.approx(3.0 / 5.0, abs=1e-12)
    unknown = run_metrics(scenario, times, q, None, None, True, 10.0)
    assert all(math.isnan(unknown[k]) for k in ("stopped_time", "stop_count", "stopped_share"))


def test_slow_down_time_and_stops(tmp_path):
    scenario = _scenario(tmp_path)
    times = np.array([0.0, 0.5, 1.0, 2.0, 2.5, 4.0, 5.0])
    limit = np.array([np.inf, 0.3, 0.0, 0.0, np.inf, 0.0, 0.2])
    slow_stopped = limit == 0.0
    q = _q(np.linspace(1.0, 2.0, len(times)), 2.5)
    dut = run_metrics(scenario, times, q, None, None, True, 10.0, speed_limit=limit, slow_stopped=slow_stopped)
    assert dut["slowed_time"] == pytest.approx(0.5 + 1.0 + 0.5 + 1.0 + 0.0, abs=1e-12)
    assert dut["slow_stop_count"] == 2.0 and dut["slow_stopped_time"] == pytest.approx(1.5 + 1.0, abs=1e-12)
    unknown = run_metrics(scenario, times, q, None, None, True, 10.0)
    assert all(math.isnan(unknown[k]) for k in ("slowed_time", "slow_stop_count", "slow_stopped_time"))


def test_jerk_of_a_cubic_motion_is_six_a3_at_any_spacing(tmp_path):
    scenario = _scenario(tmp_path)
    times = np.cumsum(np.random.default_rng(3).uniform(0.01, 0.1, 60))
    a1, a2, a3 = 0.2, -0.05, 0.03
    x = 1.0 + a1 * times + a2 * times**2 + a3 * times**3
    dut = run_metrics(scenario, times, _q(x, 2.5), None, None, True, 10.0)
    assert dut["jerk_mean_base"] == pytest.approx(6 * a3, rel=1e-6)
    assert dut["jerk_max_base"] == pytest.approx(6 * a3, rel=1e-6)
    t0, t1, t2 = times[:-2], times[1:-1], times[2:]
    accel = np.abs(2 * a2 + 2 * a3 * (t0 + t1 + t2))  # 2 x the second divided difference of a cubic
    assert dut["accel_max_base"] == pytest.approx(accel.max(), rel=1e-9)
    assert dut["accel_mean_base"] == pytest.approx(accel.mean(), rel=1e-9)
    s0, s1 = times[:-1], times[1:]
    speed = np.abs(a1 + a2 * (s0 + s1) + a3 * (s0**2 + s0 * s1 + s1**2))
    assert dut["speed_max_base"] == pytest.approx(speed.max(), rel=1e-9)
    # The object's points translate with the base (the arm does not turn): the same statistics.
    for stat in ("speed", "accel", "jerk"):
        for kind in ("mean", "max"):
            assert dut[f"{stat}_{kind}_object"] == pytest.approx(dut[f"{stat}_{kind}_base"], rel=1e-6)


def test_no_people_gives_the_documented_values(tmp_path):
    scenario = _scenario(tmp_path)
    times = np.linspace(0.0, 4.0, 41)
    dut = run_metrics(scenario, times, _q(1.0 + 0.5 * times, 2.5), None, None, True, 10.0)
    empty = run_metrics(scenario, times, _q(1.0 + 0.5 * times, 2.5), _log(times, np.zeros((41, 0, 2))), None,
                        True, 10.0)
    for part in RUN_PARTS:
        for got in (dut, empty):
            assert got[f"min_dist_{part}"] == math.inf and math.isnan(got[f"mean_dist_{part}"])
            assert got[f"time_public_{part}"] == pytest.approx(4.0) and got[f"share_public_{part}"] == 1.0
            assert got[f"collisions_{part}"] == 0.0 and got[f"agf_time_{part}"] == 0.0
            assert got[f"space_compliance_{part}"] == 1.0
    assert dut["people_count"] == 0.0 and dut["people_moving"] == 0.0
    one = run_metrics(scenario, times[:1], _q(1.0, 2.5), None, None, False, 10.0)
    assert one["duration"] == 0.0 and math.isnan(one["share_public_base"]) and math.isnan(one["speed_mean_base"])


# ---- the AGF over time --------------------------------------------------------------------------------

def test_agf_of_a_walker_with_the_base_held_in_front(tmp_path):
    """A person walks along +x at 0.5 m/s facing +x; the base centre keeps 1.0 m ahead of them: the
    base's AGF is exp(-1 / (2 sigma_h^2)) all the time; with Kirby's speed scaling sigma_h = max(2 v, 0.5)
    = 1.0 m."""
    times = np.linspace(0.0, 10.0, 201)
    person = np.stack([2.0 + 0.5 * times, np.full_like(times, 2.5)], -1)[:, None, :]
    velocities = np.broadcast_to([0.5, 0.0], person.shape)
    q = _q(3.0 + 0.5 * times, 2.5)
    for scaling, sigma_h in ((False, None), (True, 1.0)):
        scenario = _scenario(tmp_path, scaling=scaling)
        sigma_h = scenario.social.sigma_h if sigma_h is None else sigma_h
        people = _log(times, person, velocities=velocities)
        dut = run_metrics(scenario, times, q, people, None, True, 10.0)
        value = math.exp(-1.0 / (2 * sigma_h**2))
        assert value > scenario.social.threshold
        assert dut["agf_time_base"] == pytest.approx(10.0 * value, rel=1e-12), scaling


def test_static_people_agree_with_the_trajectory_metrics(tmp_path):
    people = "  - {x: 10.0, y: 3.8, theta: -1.5707963267948966, radius: 0.25}\n" \
             "  - {x: 14.0, y: 1.0, theta: 2.0, radius: 0.3}"
    scenario = _scenario(tmp_path, people)
    times = np.linspace(0.0, 36.0, 1441)
    x = 1.0 + 18.0 * (times / 36.0) ** 2 * (3 - 2 * times / 36.0)  # smooth start and stop
    q = _q(x, 2.5 + 0.3 * np.sin(times / 6.0))
    log = PeopleLog.sample(people_model(scenario), times)
    dut = run_metrics(scenario, times, q, log, np.zeros(len(times), bool), True, 40.0)
    ref = trajectory_metrics(scenario, q, None, times)
    exe = executed_metrics(scenario, times, q)
    assert dut["people_moving"] == 0.0 and dut["people_count"] == 2.0
    for part in RUN_PARTS:
        assert dut[f"min_dist_{part}"] == ref[f"min_dist_{part}"], part
        # Zone shares by time: sample-and-hold here, the step's mean distance there; they differ only on
        # the steps where the zone changes.
        zones = ZONES.classify(log_distance := _distances(scenario, q, log)[part])
        changes = int(np.count_nonzero(np.diff(zones)))
        worst = changes * float(np.diff(times).max()) / 36.0
        for z in ZONES.names:
            assert abs(dut[f"share_{z}_{part}"] - ref[f"zone_time_{z}_{part}"]) <= worst + 1e-12, (part, z)
        assert log_distance.min() == dut[f"min_dist_{part}"]
        # AGF: the trapezoid over time of part_agf's values with the people standing where they are.
        values = part_agf(SocialCost.from_scenario(scenario, np.ones(5), people=log.state(0)), q)[part]
        assert dut[f"agf_time_{part}"] == pytest.approx(np.trapezoid(values, times), rel=1e-12, abs=1e-15), part
        assert dut[f"agf_time_{part}"] > 0.0
    assert dut["path_length_base"] == pytest.approx(exe["exec_base_length"], rel=1e-12)
    assert dut["irregularity_base"] == exe["exec_irregularity"]
    assert dut["stopped_time"] == 0.0 and dut["stop_count"] == 0.0


def _distances(scenario, q, log):
    from drake_social.people.proximity import part_distances

    return part_distances(arm_geometry(scenario), q, log.positions, log.radii, log.present)


def test_bad_inputs_are_refused_with_the_rule(tmp_path):
    scenario = _scenario(tmp_path)
    times = np.linspace(0.0, 1.0, 11)
    q = _q(1.0 + times, 2.5)
    with pytest.raises(ValueError, match="strictly increasing"):
        run_metrics(scenario, times[::-1], q, None, None, True, 1.0)
    with pytest.raises(ValueError, match="other times"):
        run_metrics(scenario, times, q, _log(times[:5], np.zeros((5, 1, 2))), None, True, 1.0)
    with pytest.raises(ValueError, match="stopped must be"):
        run_metrics(scenario, times, q, None, np.zeros(3, bool), True, 1.0)
