"""Redundant waypoints (planning/collinear.py) and the optimiser's merge of
them: hand-made paths whose deviations are known by construction, the exact
checkers (planar, numpy) on the tiny scenario, and a recording checker that
shows every merged motion was checked."""

from __future__ import annotations

import copy

import numpy as np
import pytest

from drake_social.collision.geometric import GeometricChecker
from drake_social.cost import SocialCost
from drake_social.planning.collinear import COLLINEAR_TOLERANCE, collinear_runs, merge_collinear, segment_deviation
from drake_social.planning.objective import PathLengthObjective, SocialObjective
from drake_social.planning import optimize as opt_mod
from drake_social.planning.optimize import optimize_path, path_cost
from drake_social.planning.space import ConfigurationSpace

CARRY = (0.0, 1.5708)  # tiny.yaml's arm pose


def q(x, y, p1=0.0, p2=0.0):
    return [float(x), float(y), float(p1), float(p2)]


def deviation(m, a, b, w=(1.0, 1.0, 1.0, 1.0)):
    """Independent distance of m from the segment a -> b in ||W dq||: the
    nearer end when the foot of the perpendicular falls outside, else the
    length of m - a less its part along the unit vector of the segment."""
    m, a, b = (np.asarray(v, float) * np.asarray(w, float) for v in (m, a, b))
    length = np.sqrt(((b - a) ** 2).sum())
    if length == 0:
        return float(np.sqrt(((m - a) ** 2).sum()))
    e = (b - a) / length
    along = float(((m - a) * e).sum())
    if along < 0:
        return float(np.sqrt(((m - a) ** 2).sum()))
    if along > length:
        return float(np.sqrt(((m - b) ** 2).sum()))
    return float(np.sqrt((((m - a) - along * e) ** 2).sum()))


def redundant(wp, tol=COLLINEAR_TOLERANCE, w=(1.0, 1.0, 1.0, 1.0)):
    """Indices of interior waypoints within tol of their neighbours' segment."""
    return [k for k in range(1, len(wp) - 1) if deviation(wp[k], wp[k - 1], wp[k + 1], w) <= tol]


class Recording:
    """Wraps a checker, records every motion it is asked about and refuses
    the motions listed in ``refuse`` (pairs of waypoints)."""

    def __init__(self, inner, refuse=()):
        self.inner = inner
        self.refuse = {(tuple(map(float, a)), tuple(map(float, b))) for a, b in refuse}
        self.checked = []

    def is_valid(self, q):
        return self.inner.is_valid(q)

    def are_valid(self, qs):
        return self.inner.are_valid(qs)

    def are_motions_valid(self, qa, qb):
        qa, qb = np.atleast_2d(qa), np.atleast_2d(qb)
        pairs = [(tuple(map(float, a)), tuple(map(float, b))) for a, b in zip(qa, qb)]
        self.checked.extend(pairs)
        ok = np.asarray(self.inner.are_motions_valid(qa, qb), bool).copy()
        ok &= np.array([p not in self.refuse for p in pairs], dtype=bool)
        return ok


class AllValid:
    """Accepts everything."""

    def is_valid(self, q):
        return True

    def are_valid(self, qs):
        return np.ones(len(qs), dtype=bool)

    def are_motions_valid(self, qa, qb):
        return np.ones(len(np.atleast_2d(qa)), dtype=bool)


# ---------------------------------------------------------------- geometry


def test_segment_deviation_is_the_distance_from_the_segment():
    a, b = q(0, 0), q(4, 0)
    points = np.array([q(1, 3), q(-3, 4), q(7, -4), q(2, 0), q(4, 0), q(2, 0, 0.0, 1.5)])
    np.testing.assert_allclose(segment_deviation(points, a, b), [3.0, 5.0, 5.0, 0.0, 0.0, 1.5], rtol=1e-15)
    # weighted: W scales each coordinate before the distance
    w = np.array([1.0, 2.0, 1.0, 0.5])
    np.testing.assert_allclose(segment_deviation(points, a, b, w), [6.0, np.hypot(3, 8), np.hypot(3, 8), 0, 0, 0.75],
                               rtol=1e-15)
    # a degenerate segment is its point
    np.testing.assert_allclose(segment_deviation(points[:2], a, a), [np.hypot(1, 3), 5.0], rtol=1e-15)
    rng = np.random.default_rng(7)
    for _ in range(50):
        a, b, m = rng.normal(size=(3, 4))
        assert segment_deviation(m[None], a, b, w)[0] == pytest.approx(deviation(m, a, b, w), rel=1e-9, abs=1e-12)


@pytest.mark.parametrize("offset, merged", [
    (COLLINEAR_TOLERANCE, True),
    (np.nextafter(COLLINEAR_TOLERANCE, 0.0), True),
    (np.nextafter(COLLINEAR_TOLERANCE, 1.0), False),
    (0.0, True),
])
def test_the_tolerance_holds_at_its_value_and_either_side(offset, merged):
    """A midpoint ``offset`` beside the segment of its neighbours: redundant
    up to COLLINEAR_TOLERANCE (1e-9) inclusive."""
    assert COLLINEAR_TOLERANCE == 1e-9
    wp = np.array([q(0, 0), q(1, offset), q(2, 0)])
    assert segment_deviation(wp[1:2], wp[0], wp[2])[0] == offset  # the deviation is the offset, exactly
    assert collinear_runs(wp) == ([(0, 2)] if merged else [])
    dut = merge_collinear(wp, AllValid())
    np.testing.assert_array_equal(dut, wp[[0, 2]] if merged else wp)


def test_the_tolerance_is_in_the_planners_weighted_distance():
    """0.6e-9 rad of psi1 is within 1e-9 with weight 1, 1.2e-9 (outside) with weight 2."""
    wp = np.array([q(0, 0, 0.3), q(1, 0, 0.3 + 0.6e-9), q(2, 0, 0.3)])
    assert deviation(wp[1], wp[0], wp[2], (1, 1, 2, 1)) > COLLINEAR_TOLERANCE > deviation(wp[1], wp[0], wp[2])
    assert collinear_runs(wp) == [(0, 2)]
    assert collinear_runs(wp, np.array([1.0, 1.0, 2.0, 1.0])) == []


def test_collinear_runs_are_maximal_and_stop_at_corners_and_reversals():
    wp = np.array([q(0, 0), q(1, 0), q(2, 0), q(3, 0),  # a straight run of four
                   q(3, 1), q(3, 1), q(3, 2),            # a corner, then a repeated waypoint on a straight run
                   q(4, 3), q(3.5, 2.5),                 # a reversal along its own line: not between its neighbours
                   q(5, 2.5, 0.5, -0.5), q(6.5, 2.5, 1.0, -1.0)])  # base and arm move together, in proportion
    assert collinear_runs(wp) == [(0, 3), (3, 6), (8, 10)]
    assert redundant(merge_collinear(wp, AllValid())) == []
    np.testing.assert_array_equal(merge_collinear(wp, AllValid()), wp[[0, 3, 6, 7, 8, 10]])
    for short in (wp[:0], wp[:1], wp[:2]):
        assert collinear_runs(short) == []
        np.testing.assert_array_equal(merge_collinear(short, AllValid()), short)


# ---------------------------------------------------------------- merging, checked


@pytest.fixture(scope="module")
def planar(tiny_scenario):
    from drake_social.collision.drake_checker import make_checker

    return make_checker(tiny_scenario, "planar")


BESIDE_THE_DESK = np.array([q(1.5, 1.3, *CARRY), q(2.75, 1.4, *CARRY), q(4.0, 1.5, *CARRY), q(6.5, 1.3, *CARRY)])


def test_a_merged_motion_is_checked_not_trusted(tiny_scenario, planar):
    """Past the desk of tiny.yaml, 0.2 m above the straight line: with a
    tolerance of 0.25 every waypoint counts as collinear, but the straight
    motion crosses the desk, and the exact checker refuses it. The waypoint
    that makes the detour stays; the one exactly on the way to it goes."""
    exact = GeometricChecker(tiny_scenario)
    wp = BESIDE_THE_DESK
    assert exact.are_motions_valid(wp[:-1], wp[1:]).all()
    assert not exact.are_motions_valid(wp[:1], wp[3:]).any() and not exact.is_valid(q(4.0, 1.3, *CARRY))
    assert collinear_runs(wp, tolerance=0.25) == [(0, 3)]
    for checker in (planar, exact):
        dut = merge_collinear(wp, checker, tolerance=0.25)
        np.testing.assert_array_equal(dut, wp[[0, 2, 3]])
        assert exact.are_motions_valid(dut[:-1], dut[1:]).all()
    assert collinear_runs(wp) == [(0, 2)]  # 1e-9: the detour's waypoint is no candidate
    np.testing.assert_array_equal(merge_collinear(wp, planar), wp[[0, 2, 3]])


def test_every_merged_motion_goes_through_the_checker():
    wp = np.array([q(0, 0), q(1, 0), q(2, 0), q(3, 0), q(3, 1), q(3, 2), q(3, 3)])
    checker = Recording(AllValid())
    dut = merge_collinear(wp, checker)
    np.testing.assert_array_equal(dut, wp[[0, 3, 6]])
    assert checker.checked == [(tuple(wp[0]), tuple(wp[3])), (tuple(wp[3]), tuple(wp[6]))]  # one batched call


def test_a_refused_run_falls_back_to_the_farthest_accepted_shorter_one():
    wp = np.array([q(0, 0), q(1, 0), q(2, 0), q(3, 0), q(4, 0), q(4, 1)])
    checker = Recording(AllValid(), refuse=[(wp[0], wp[4]), (wp[0], wp[3])])
    dut = merge_collinear(wp, checker)
    np.testing.assert_array_equal(dut, wp[[0, 2, 4, 5]])  # 0 -> 2 accepted, then 2 -> 4
    assert checker.checked == [tuple(map(tuple, m)) for m in ((wp[0], wp[4]), (wp[0], wp[3]), (wp[0], wp[2]),
                                                              (wp[2], wp[4]))]
    every = Recording(AllValid(), refuse=[(wp[i], wp[j]) for i in range(5) for j in range(i + 2, 5)])
    np.testing.assert_array_equal(merge_collinear(wp, every), wp)  # nothing accepted: all kept


# ---------------------------------------------------------------- in the optimiser


def thirds(wp):
    """Every motion cut into three equal parts: collinear runs."""
    out = [wp[:1]]
    for a, b in zip(wp[:-1], wp[1:]):
        out.append(np.array([a + (b - a) / 3, a + 2 * (b - a) / 3, b]))
    return np.concatenate(out)


@pytest.mark.parametrize("people, length_weight, left", [(True, 0.5, 2), (False, 0.001, 10)],
                         ids=["person", "nobody"])
def test_the_optimiser_returns_no_collinear_waypoint(tiny_scenario, planar, people, length_weight, left,
                                                      monkeypatch):
    """A path with collinear runs in (every motion in thirds), the tiny
    scenario's social objective (with its person, or nobody: the length
    alone) and the exact planar checker: none out (the rounds alone leave
    ``left``: parts of subdivided motions the descent did not move), every
    motion valid for the independent numpy checker, the cost the sum of the
    returned motions' costs, and every merged motion checked."""
    scenario = copy.deepcopy(tiny_scenario)
    if not people:
        scenario.people = []
    objective = SocialObjective(SocialCost.from_scenario(scenario), length_weight=length_weight)
    space = ConfigurationSpace.from_scenario(scenario)
    s, g = np.array(scenario.start), np.array(scenario.goal)
    wp = thirds(np.array([s, [2.0, 1.6, 0.4, 1.2], [4.0, 2.0, 0.0, 1.5708], [6.0, 3.2, 0.1, 1.4], g]))
    assert len(redundant(wp)) == 8
    checker = Recording(planar)
    dut, cost = optimize_path(wp, objective, checker, space)
    assert cost < path_cost(objective, wp) and redundant(dut) == []
    np.testing.assert_array_equal(dut[[0, -1]], wp[[0, -1]])
    assert cost == pytest.approx(sum(float(objective.motion_cost(a, b)[0]) for a, b in zip(dut[:-1], dut[1:])),
                                 rel=1e-12)
    assert GeometricChecker(scenario).are_motions_valid(dut[:-1], dut[1:]).all()
    given, checked = {(tuple(a), tuple(b)) for a, b in zip(wp[:-1], wp[1:])}, set(checker.checked)
    new = [(tuple(a), tuple(b)) for a, b in zip(dut[:-1], dut[1:]) if (tuple(a), tuple(b)) not in given]
    assert new and all(m in checked for m in new)
    if not people:  # nothing to avoid in the room's middle: the straight motion
        np.testing.assert_array_equal(dut, [s, g])
    monkeypatch.setattr(opt_mod, "merge_collinear", lambda wp, *args: wp)
    assert len(redundant(optimize_path(wp, objective, planar, space)[0])) == left


def test_the_raw_input_comes_back_unchanged_when_nothing_is_gained():
    """A straight path of collinear waypoints under the path length is
    already optimal: the optimiser gains nothing and gives the input back
    as it is (raw paths are not merged)."""
    wp = np.array([q(0, 0), q(1, 0), q(2, 0)])
    dut, cost = optimize_path(wp, PathLengthObjective(), AllValid(),
                              ConfigurationSpace(np.array([-1.0, -1, -3, -3]), np.array([5.0, 5, 3, 3])))
    np.testing.assert_array_equal(dut, wp)
    assert cost == 2.0
