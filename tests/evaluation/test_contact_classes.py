"""Who made a contact: run_metrics' appeared / moving / held classes on hand-built runs.

The rule (drake_social/evaluation/nav_metrics.py): a contact episode starting
at sample k is *appeared* when a person entering at k (present at t_k, absent
at t_{k-1} or k = 0) touches the part at t_k; otherwise *moving* when k >= 1
and the robot is not held (``stopped`` or ``waiting``) at both samples k - 1
and max(k - 2, 0) (over [t_{k-1}, t_k), when the contact began, the base
follows the hold of t_{k-1} and the arm's trajectory that of t_{k-2});
otherwise the robot was held and a person walked into it.

The robot: base disc radius 0.35 m at (X, 2.5), the arm along +x (psi1 = 0),
the bar above at y = 3; people are discs of radius 0.25 m, so a person on
y = 2.5 west of the base touches it when X - x <= 0.6.
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from drake_social.evaluation.metrics import RUN_PARTS, execution_metrics, run_metrics
from drake_social.people.log import PeopleLog
from drake_social.scenario import load_scenario

_ROOM = """
description: "contact classes"
world: {bounds: [-10.0, -10.0, 40.0, 10.0]}
robot: {base_radius: 0.35, link_lengths: [0.6, 0.5], link_width: 0.08}
object: !Bar {length: 1.5, thickness: 0.05}
start: [1.0, 2.5, 0.0, 1.5707963267948966]
goal: [19.0, 2.5, 0.0, 1.5707963267948966]
"""
_DT = 0.25
_TIMES = np.arange(0.0, 16.0 + _DT / 2, _DT)
_T = len(_TIMES)
#: The base creeps east by 0.1 mm a sample: a held robot's servo residue in dynamic mode.
_CREEP = 5.0 + 1e-4 * np.arange(_T)


@pytest.fixture(scope="module")
def scenario(tmp_path_factory):
    path = tmp_path_factory.mktemp("contacts") / "room.yaml"
    path.write_text(_ROOM)
    return load_scenario(path)


def _q(x) -> np.ndarray:
    x = np.asarray(x, float)
    return np.column_stack([x, np.full_like(x, 2.5), np.zeros_like(x), np.full_like(x, math.pi / 2)])


def _log(positions, present=None) -> PeopleLog:
    positions = np.asarray(positions, float)
    t, p = positions.shape[:2]
    return PeopleLog(times=_TIMES, positions=positions, headings=np.zeros((t, p)),
                     velocities=np.gradient(positions, _TIMES, axis=0),
                     present=np.ones((t, p), bool) if present is None else present, radii=np.full(p, 0.25),
                     names=tuple(f"p{i}" for i in range(p)))


def _walker():
    """A person walking east along y = 2.5 at 0.4 m/s from x = 0.35, stopping at x = 4.8 (inside the
    base); with the creeping base, the contact's first sample k0 by hand: the first with
    X_k - x_k <= 0.6 (t = 10.25 s: 0.05 m apart at 10.0 s, 0.04 m overlap at 10.25 s)."""
    x = np.minimum(0.35 + 0.4 * _TIMES, 4.8)
    k0 = int(np.flatnonzero(_CREEP - x <= 0.6)[0])
    assert _TIMES[k0] == 10.25 and _CREEP[k0 - 1] - x[k0 - 1] > 0.6 + 0.04
    return _log(np.stack([x, np.full_like(x, 2.5)], -1)[:, None, :]), k0


def _flags(on):
    flag = np.zeros(_T, bool)
    flag[on] = True
    return flag


def _classes(dut, part="base"):
    return (dut[f"collisions_{part}"], dut[f"collisions_appeared_{part}"], dut[f"collisions_moving_{part}"])


def test_a_contact_beginning_while_the_monitor_holds_the_creeping_robot_is_not_moving(scenario):
    people, k0 = _walker()
    # The monitor held the robot from 9 s on (the walker within its safety distance); the robot creeps.
    dut = run_metrics(scenario, _TIMES, _q(_CREEP), people, _TIMES >= 9.0, False, 16.0)
    for part in ("base", "robot"):
        assert _classes(dut, part) == (1.0, 0.0, 0.0), part
    # Waiting for a replan holds the same way.
    waiting = run_metrics(scenario, _TIMES, _q(_CREEP), people, np.zeros(_T, bool), False, 16.0,
                          waiting=_TIMES >= 9.0)
    assert _classes(waiting) == (1.0, 0.0, 0.0)


def test_a_contact_beginning_while_commanded_to_move_is_moving_whatever_the_motion(scenario):
    people, _ = _walker()
    for x in (_CREEP, np.full(_T, 5.0)):  # creeping, or standing exactly still (e.g. starting from rest)
        dut = run_metrics(scenario, _TIMES, _q(x), people, np.zeros(_T, bool), False, 16.0)
        assert _classes(dut) == (1.0, 0.0, 1.0)
        # waiting=None: no replanner, never waiting; all False: the same.
        same = run_metrics(scenario, _TIMES, _q(x), people, np.zeros(_T, bool), False, 16.0,
                           waiting=np.zeros(_T, bool))
        assert _classes(same) == (1.0, 0.0, 1.0)


@pytest.mark.parametrize("kind, offset, moving", [
    ("never", 0, 1.0),
    # Held from sample k0 + offset on. Over [t_{k0-1}, t_k0), where the contact began, the base follows
    # the hold of k0 - 1 and the arm's trajectory that of k0 - 2.
    ("from", 1, 1.0),
    ("from", 0, 1.0),  # decided with the contact
    ("from", -1, 1.0),  # the base held, the arm still commanded (it reads the hold a period later)
    ("from", -2, 0.0),  # both held over the step in which the contact began
    # Released at sample k0 + offset: commanded from there on.
    ("until", -2, 1.0),
    ("until", -1, 1.0),  # released at k0 - 1: the base commanded over [t_{k0-1}, t_k0)
    ("until", 0, 0.0),  # released at k0, the contact's sample: held over the step before it
    ("until", 1, 0.0),
])
def test_a_contact_is_held_only_when_both_samples_before_it_hold(scenario, kind, offset, moving):
    people, k0 = _walker()
    held = {"never": slice(0, 0), "from": slice(k0 + offset, None), "until": slice(0, k0 + offset)}[kind]
    for name in ("stopped", "waiting"):
        flag = _flags(held)
        stopped, waiting = (flag, None) if name == "stopped" else (np.zeros(_T, bool), flag)
        dut = run_metrics(scenario, _TIMES, _q(_CREEP), people, stopped, False, 16.0, waiting=waiting)
        assert _classes(dut) == (1.0, 0.0, moving), name


def test_a_contact_at_the_second_sample_reads_the_first_samples_hold_alone(scenario):
    # max(k - 2, 0): for k = 1 both commands of [t_0, t_1) are those decided at t_0.
    times = _TIMES[:3]
    people = PeopleLog(times=times, positions=[[[4.3, 2.5]], [[4.5, 2.5]], [[4.5, 2.5]]],
                       headings=np.zeros((3, 1)), velocities=np.zeros((3, 1, 2)), present=np.ones((3, 1), bool),
                       radii=[0.25], names=("p0",))  # 0.1 m apart at t_0, 0.1 m overlap from t_1 on
    for held, moving in (([True, False, False], 0.0), ([False, True, True], 1.0)):
        dut = run_metrics(scenario, times, _q(np.full(3, 5.0)), people, np.array(held), False, 1.0)
        assert _classes(dut) == (1.0, 0.0, moving), held


def test_a_person_appearing_inside_the_robot_is_counted_apart(scenario):
    # A recorded track that begins inside the base at t = 6 s (entering the camera's view) and stays.
    inside = np.broadcast_to([5.0 - 0.4, 2.5], (_T, 1, 2))
    present = (_TIMES >= 6.0)[:, None]
    dut = run_metrics(scenario, _TIMES, _q(_CREEP), _log(inside, present), np.zeros(_T, bool), False, 16.0)
    for part in ("base", "robot"):
        assert _classes(dut, part) == (1.0, 1.0, 0.0), part
    assert _classes(dut, "arm") == (0.0, 0.0, 0.0)  # 0.4 m west of the base's centre: 0.11 m clear of the arm
    # Present from the first sample: an appearance too (no robot command can have made it).
    first = run_metrics(scenario, _TIMES, _q(_CREEP), _log(inside), np.zeros(_T, bool), False, 16.0)
    assert _classes(first) == (1.0, 1.0, 0.0)
    # In view for [2, 3) s, out of view, back from 6 s: every entry in contact is an appearance.
    twice = (_TIMES >= 2.0) & (_TIMES < 3.0) | (_TIMES >= 6.0)
    dut = run_metrics(scenario, _TIMES, _q(_CREEP), _log(inside, twice[:, None]), np.zeros(_T, bool), False, 16.0)
    assert _classes(dut) == (2.0, 2.0, 0.0)
    # Without a recorded stop flag the moving contacts are unknown; the appearances are not.
    unknown = run_metrics(scenario, _TIMES, _q(_CREEP), _log(inside, present), None, False, 16.0)
    assert unknown["collisions_appeared_base"] == 1.0 and math.isnan(unknown["collisions_moving_base"])


def test_an_appearance_is_a_contact_at_the_entering_sample_exactly(scenario):
    """A person enters at sample j = 24 (t = 6 s) on y = 2.5 west of the base at (0.6, 2.5), standing
    then one 2 mm step east: touching (the distance exactly 0 is contact) or overlapping at entry is an
    appearance; 1 mm away at entry, the contact starts at j + 1 with the robot commanded: moving."""
    j = 24
    assert abs(0.6 - 0.0) - 0.25 - 0.35 == 0.0  # the base's distance at entry from x0 = 0, as computed
    present = (np.arange(_T) >= j)[:, None]
    q = _q(np.full(_T, 0.6))
    for x0, expected in ((0.0, (1.0, 1.0, 0.0)), (0.05, (1.0, 1.0, 0.0)), (-0.001, (1.0, 0.0, 1.0))):
        x = np.where(np.arange(_T) > j, x0 + 0.002, x0)  # one step in after entering
        people = _log(np.stack([x, np.full(_T, 2.5)], -1)[:, None, :], present)
        dut = run_metrics(scenario, _TIMES, q, people, np.zeros(_T, bool), False, 16.0)
        assert _classes(dut) == expected, x0
    assert dut["min_dist_base"] == pytest.approx(-0.001, abs=1e-12)


def test_appearances_are_per_part(scenario):
    # A person entering on the bar (y = 3 from x - 0.15 to x + 1.35), clear of the base and the arm.
    bar = np.broadcast_to([5.0 + 1.2, 3.0 + 0.1], (_T, 1, 2))
    present = (_TIMES >= 4.0)[:, None]
    dut = run_metrics(scenario, _TIMES, _q(np.full(_T, 5.0)), _log(bar, present), np.zeros(_T, bool), False, 16.0)
    assert _classes(dut, "object") == (1.0, 1.0, 0.0) and _classes(dut, "robot") == (1.0, 1.0, 0.0)
    assert _classes(dut, "base") == (0.0, 0.0, 0.0) and _classes(dut, "arm") == (0.0, 0.0, 0.0)


def test_an_episode_starting_with_an_entrant_who_does_not_touch_is_no_appearance(scenario):
    # The walker touches the base at k0; at k0 another person enters far away: the contact is the walker's.
    people, k0 = _walker()
    far = np.broadcast_to([20.0, 2.5], (_T, 1, 2))
    both = PeopleLog(times=_TIMES, positions=np.concatenate([people.positions, far], 1),
                     headings=np.zeros((_T, 2)), velocities=np.concatenate([people.velocities, np.zeros_like(far)], 1),
                     present=np.column_stack([np.ones(_T, bool), np.arange(_T) >= k0]), radii=[0.25, 0.25],
                     names=("walker", "far"))
    dut = run_metrics(scenario, _TIMES, _q(_CREEP), both, np.zeros(_T, bool), False, 16.0)
    assert _classes(dut) == (1.0, 0.0, 1.0)


def test_the_classes_never_exceed_the_contacts(scenario):
    """Seeded random walkers entering and leaving around a creeping robot, random holds: appeared +
    moving <= contacts per part, and with every flag set (always held) no contact is moving."""
    rng = np.random.default_rng(29)
    for _ in range(20):
        p = 3
        start = rng.uniform([3.0, 1.5], [7.0, 3.5], (p, 2))
        velocity = rng.uniform(-0.2, 0.2, (p, 2))
        positions = start[None] + _TIMES[:, None, None] * velocity[None]
        present = rng.random((_T, p)) < 0.8
        stopped = rng.random(_T) < 0.5
        people = _log(positions, present)
        dut = run_metrics(scenario, _TIMES, _q(_CREEP), people, stopped, False, 16.0)
        held = run_metrics(scenario, _TIMES, _q(_CREEP), people, np.ones(_T, bool), False, 16.0)
        for part in RUN_PARTS:
            total, appeared, moving = _classes(dut, part)
            assert appeared + moving <= total, part
            assert held[f"collisions_moving_{part}"] == 0.0
            assert held[f"collisions_appeared_{part}"] == appeared


def test_execution_metrics_reads_the_runs_stop_and_wait_flags(scenario):
    people, _ = _walker()
    run = SimpleNamespace(times=_TIMES, q=_q(_CREEP), reached=False, time_to_goal=None, people=people,
                          stopped=np.zeros(_T, bool))
    assert execution_metrics(scenario, run)["nav_collisions_moving_base"] == 1.0
    run.waiting = _TIMES >= 9.0  # the replanner held the robot from before the contact
    assert execution_metrics(scenario, run)["nav_collisions_moving_base"] == 0.0
    del run.stopped  # a simulator that records no stop flag: unknown
    assert math.isnan(execution_metrics(scenario, run)["nav_collisions_moving_base"])
