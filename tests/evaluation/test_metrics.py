"""Metrics on hand-made paths with answers computed by hand."""

from __future__ import annotations

import math

import numpy as np
import pytest

from drake_social.evaluation.metrics import (
    ZONES,
    base_irregularity,
    executed_metrics,
    part_names,
    path_metrics,
    zone_shares,
)
from drake_social.scenario.geometry import arm_geometry
from drake_social.scenario import load_scenario

# A 20 x 6 m empty room; one person at (10, 3.8) facing south, towards the
# robot's straight pass along y = 2.5 (psi1 = 0, psi2 = pi/2: link 1 along +x,
# link 2 up, the 1.5 m bar horizontal at y = 3.0, centred at x + 0.6).
_ROOM = """
description: "straight pass"
world: {bounds: [0.0, 0.0, 20.0, 6.0]}
people:
  - {x: 10.0, y: 3.8, theta: %(theta)s, radius: 0.25}
robot: {base_radius: 0.35, link_lengths: [0.6, 0.5], link_width: 0.08}
object: !Bar {length: 1.5, thickness: 0.05}
start: [1.0, 2.5, 0.0, 1.5707963267948966]
goal: [19.0, 2.5, 0.0, 1.5707963267948966]
"""


def _scenario(tmp_path, theta: float = -math.pi / 2, people: bool = True):
    text = _ROOM % {"theta": repr(theta)}
    if not people:
        text = text.replace("people:\n  - {x: 10.0, y: 3.8, theta: %r, radius: 0.25}\n" % theta, "people: []\n")
    path = tmp_path / "pass.yaml"
    path.write_text(text)
    return load_scenario(path)


def _straight(scenario) -> np.ndarray:
    return np.array([scenario.start, scenario.goal], float)


def test_straight_pass_minimum_distances_surface_to_surface(tmp_path):
    scenario = _scenario(tmp_path)
    dut = path_metrics(scenario, _straight(scenario))
    # Person centre 3.8 m up, body radius 0.25.
    expected = {
        "base": 1.3 - 0.35 - 0.25,          # disc to disc
        "link1_tip": 1.3 - 0.25,            # the elbow at y = 2.5
        "link2_tip": 0.8 - 0.25,            # the gripper at y = 3.0
        "object_1": 0.8 - 0.25,
        "object_2": 0.8 - 0.25,
        "arm": 0.8 - 0.04 - 0.25,           # link-2 capsule, radius 0.04
        "object": 0.8 - 0.025 - 0.25,       # bar capsule, radius 0.025
        "robot": 0.8 - 0.04 - 0.25,
    }
    assert set(part_names(arm_geometry(scenario))) == set(expected)
    for part, d in expected.items():
        assert dut[f"min_dist_{part}"] == pytest.approx(d, abs=2e-3), part


def test_straight_pass_zone_shares_by_arc_length(tmp_path):
    scenario = _scenario(tmp_path)
    dut = path_metrics(scenario, _straight(scenario))

    def within(offset: float, limit: float) -> float:
        """Length of x in [1, 19] where hypot(x - 10, 1.3 or 0.8) - offset < limit."""
        return 2.0 * math.sqrt(max(0.0, (limit + offset) ** 2 - dy**2))

    for part, dy, offset in (("base", 1.3, 0.6), ("link1_tip", 1.3, 0.25), ("link2_tip", 0.8, 0.25)):
        intimate = within(offset, ZONES.intimate) / 18.0
        personal = within(offset, ZONES.personal) / 18.0 - intimate
        social = within(offset, ZONES.social) / 18.0 - intimate - personal
        got = [dut[f"zone_{z}_{part}"] for z in ZONES.names]
        assert got == pytest.approx([intimate, personal, social, 1 - intimate - personal - social], abs=4e-3), part
    assert dut["zone_intimate_base"] == 0.0  # never closer than 0.7 m
    assert dut["zone_intimate_link2_tip"] == 0.0  # never closer than 0.55 m


def test_straight_pass_agf_maxima_per_part(tmp_path):
    scenario = _scenario(tmp_path)
    dut = path_metrics(scenario, _straight(scenario))
    sigma_h = scenario.social.sigma_h  # straight in front of the person: exp(-u^2 / (2 sigma_h^2))
    front = {"base": 1.3, "link1_tip": 1.3, "link2_tip": 0.8, "object": 0.8, "arm": 0.8, "robot": 0.8}
    for part, u in front.items():
        assert dut[f"agf_max_{part}"] == pytest.approx(math.exp(-u * u / (2 * sigma_h**2)), abs=1e-3), part
    # Each bar end also passes straight in front of the person, 0.8 m away.
    for part in ("object_1", "object_2"):
        assert dut[f"agf_max_{part}"] == pytest.approx(math.exp(-0.64 / (2 * sigma_h**2)), abs=1e-3)
    # agf_mean * length is each point's unweighted share of F (all weights 1).
    shares = sum(dut[f"agf_mean_{p}"] for p in arm_geometry(scenario).interest_names)
    assert shares * dut["path_length"] == pytest.approx(dut["F_multi"], rel=2e-2)
    assert dut["agf_mean_base"] * dut["path_length"] == pytest.approx(dut["F_base"], rel=2e-2)
    assert dut["path_length"] == pytest.approx(18.0) and dut["base_length"] == pytest.approx(18.0)
    assert dut["irregularity"] == 0.0


def test_rotated_person_facing_away_costs_less_and_distances_do_not_change(tmp_path):
    facing = path_metrics(s := _scenario(tmp_path), _straight(s))
    away = path_metrics(s := _scenario(tmp_path, theta=math.pi / 4 + math.pi / 2), _straight(s))
    assert away["min_dist_base"] == pytest.approx(facing["min_dist_base"], abs=1e-12)
    assert away["agf_max_base"] < facing["agf_max_base"]


def test_executed_time_shares_equal_length_shares_at_constant_speed(tmp_path):
    scenario = _scenario(tmp_path)
    x = np.linspace(1.0, 19.0, 721)
    q = np.column_stack([x, np.full_like(x, 2.5), np.zeros_like(x), np.full_like(x, math.pi / 2)])
    dut = executed_metrics(scenario, np.linspace(0.0, 36.0, len(x)), q)
    for z in ZONES.names:
        assert dut[f"exec_zone_time_{z}_base"] == pytest.approx(dut[f"exec_zone_{z}_base"], abs=1e-9)
    # 20 s for the first 3 m (far from the person: public for the base), 16 s for the other 15 m.
    slow_start = np.where(x < 4.0, (x - 1.0) * 20.0 / 3.0, 20.0 + (x - 4.0) * 16.0 / 15.0)
    dut = executed_metrics(scenario, slow_start, q)
    assert dut["exec_zone_time_public_base"] > dut["exec_zone_public_base"]  # lingered far from the person


def test_empty_room_every_part_is_public_and_costless(tmp_path):
    scenario = _scenario(tmp_path, people=False)
    dut = path_metrics(scenario, _straight(scenario))
    assert dut["min_dist_robot"] == math.inf
    assert dut["zone_public_robot"] == 1.0 and dut["agf_max_robot"] == 0.0 and dut["F_multi"] == 0.0


def test_zone_shares_without_motion_are_nan_and_irregularity_of_a_right_angle():
    assert all(math.isnan(v) for v in zone_shares(np.array([1.0, 1.0]), np.zeros(1)).values())
    dut = base_irregularity(np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 2.0]]))
    assert dut == pytest.approx((math.pi / 2) / 4.0, rel=1e-6)
    assert base_irregularity(np.array([[0.0, 0.0], [1.0, 0.0], [3.0, 0.0]])) == 0.0


def _front_agf(u: float, sigma_h: float, threshold: float = 0.2) -> float:
    """Kirby's AGF on the facing axis, u metres in front, thresholded (by hand)."""
    value = math.exp(-u * u / (2.0 * sigma_h * sigma_h))
    return value if value > threshold else 0.0


@pytest.mark.parametrize("speed", [None, 0.0, 0.4])
def test_arm_and_object_agf_use_the_speed_scaled_sigmas_of_the_points(speed):
    # tiny: the person at (4, 3.8) faces south; at q = (3, 2.2, 0, pi/2) the bar lies along
    # y = 2.7 from x = 2.85 to 4.35, its nearest point (4, 2.7) 1.1 m in front of the person.
    from drake_social.cost.social import SocialCost
    from drake_social.evaluation.metrics import part_agf
    from drake_social.people import PeopleState

    scenario = load_scenario("scenarios/tiny.yaml")
    scenario.social.speed_scaling = speed is not None
    v = speed or 0.0
    person = scenario.people[0]
    state = PeopleState(t=0.0, positions=[[person.x, person.y]], headings=[person.theta],
                        velocities=[[0.0, -v]], radii=[person.radius], names=(person.name,))
    n = arm_geometry(scenario).num_interest_points
    dut = part_agf(SocialCost.from_scenario(scenario, np.ones(n), people=state), np.array([3.0, 2.2, 0.0, 1.5708]))
    # sigma_h: the scenario's 2 m without scaling, max(2 v, 0.5) with it.
    sigma_h = 2.0 if speed is None else max(2.0 * v, 0.5)
    # The bar's axis is sampled every 5 cm: its best sample is within 2.5 cm of x = 4 (v <= 2.5 cm to the side).
    assert dut["object"][0] == pytest.approx(_front_agf(1.1, sigma_h), abs=2e-3)
    # The arm's nearest point to the person is its tip (3.6, 2.7): u = 1.1, 0.4 m to the side.
    sigma_s = 2.0 / 3.0 * sigma_h
    arm = _front_agf(1.1, sigma_h, 0.0) * math.exp(-0.16 / (2.0 * sigma_s ** 2))
    assert dut["arm"][0] == pytest.approx(arm if arm > 0.2 else 0.0, abs=2e-3)
    assert dut["arm"][0] >= max(dut["link1_tip"][0], dut["link2_tip"][0])
    assert dut["object"][0] >= max(dut["object_1"][0], dut["object_2"][0])
    assert dut["robot"][0] == max(dut[p][0] for p in ("base", "link1_tip", "link2_tip", "object_1", "object_2",
                                                      "arm", "object"))
