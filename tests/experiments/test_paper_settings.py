"""``experiment paper`` runs the paper's planner (the raw tree path, the fixed
r_near, the pure social integral) although the scenario files' defaults are
an optimised path, the shrinking radius and a length tie-break."""

from __future__ import annotations

import dataclasses as dc

import numpy as np
import pytest

from drake_social.experiments.study import PAPER_OBJECTIVE, PAPER_PLANNER, paper_study
from drake_social.scenario import PlannerOptions, SocialCostOptions, load_scenario


def test_the_shipped_scenarios_default_to_the_optimised_path_and_the_shrinking_radius(repo_root):
    assert (PlannerOptions().optimize, PlannerOptions().near_radius_mode) == (True, "shrinking")
    for name in ("office_bar", "generic_L"):
        planner = load_scenario(repo_root / "scenarios" / f"{name}.yaml").planner
        assert (planner.optimize, planner.near_radius_mode) == (True, "shrinking"), name
    # the tests' scenario says otherwise: the paper's raw planner
    planner = load_scenario(repo_root / "scenarios" / "tiny.yaml").planner
    assert (planner.optimize, planner.near_radius_mode) == (False, "fixed")


def test_every_paper_group_pins_the_raw_planner_the_fixed_radius_and_the_pure_social_cost(repo_root):
    assert SocialCostOptions().length_weight == 0.001  # the default's tie-break, which the pin undoes
    study = paper_study(runs=2, iterations=100, scenario_dir=repo_root / "scenarios")
    assert len(study.groups) == 5
    for group in study.groups:
        assert group.overrides[-2:] == (PAPER_PLANNER, PAPER_OBJECTIVE)  # last: nothing after them can undo them
        scenario = load_scenario(group.scenario, list(group.overrides))
        assert scenario.planner.optimize is False and scenario.planner.near_radius_mode == "fixed", group.name
        assert scenario.social.length_weight == 0.0, group.name
        # the pins change nothing else of the planner or the cost
        unpinned = load_scenario(group.scenario, list(group.overrides[:-2]))
        assert unpinned.social.length_weight == 0.001
        assert (scenario.planner.near_radius, scenario.planner.planning_range, scenario.planner.iterations) == (
            unpinned.planner.near_radius, unpinned.planner.planning_range, unpinned.planner.iterations)
        assert scenario.social == dc.replace(unpinned.social, length_weight=0.0)


def test_the_paper_study_finds_the_shipped_scenarios_whatever_the_folder(tmp_path, monkeypatch, repo_root):
    """``experiment paper`` without --scenario-dir, and paper_study without
    scenario_dir, read office_bar.yaml and generic_L.yaml beside the package."""
    from drake_social.app import paper_experiment
    from drake_social.cli_parser import build_parser

    monkeypatch.chdir(tmp_path)
    shipped = repo_root / "scenarios"
    args = build_parser().parse_args(["experiment", "paper"])
    assert args.scenario_dir == shipped
    dut = paper_experiment(runs=1, iterations=10, seed=0, simulate=False, scenario_dir=args.scenario_dir)
    assert [g.scenario for g in dut.groups] == [str(shipped / "office_bar.yaml")] + [str(shipped / "generic_L.yaml")] * 4
    assert paper_study(runs=1, iterations=10) == dut


def dense_social_integral(cost, waypoints, samples=4001):
    """The social integral of a path by hand: S(q) (thresholded AGF, weighted
    over the interest points) at ``samples`` points of every straight motion,
    the trapezoid rule over the configuration distance."""
    total = 0.0
    for a, b in zip(waypoints[:-1], waypoints[1:]):
        t = np.linspace(0.0, 1.0, samples)[:, None]
        s = cost(a + t * (b - a))
        total += float(np.linalg.norm(b - a)) * float(np.sum(s[1:] + s[:-1]) / 2 / (samples - 1))
    return total


@pytest.mark.slow
def test_the_paper_study_plans_with_the_pure_social_integral(repo_root):
    """Group A (the office) as the study loads it: the planner's cost of its
    raw path is the social integral alone, that is, the sum of the social
    cost's motion integrals (to rounding) and, within 0.1 % (the trapezoid
    rule at 0.1 m steps: 0.009 % here), a dense integral of S by hand; the
    default objective's would add 0.001 times the path's length (0.28 % of
    the cost here, above both tolerances)."""
    from drake_social.collision.drake_checker import make_checker
    from drake_social.cost import SocialCost
    from drake_social.planning.algorithms import plan

    study = paper_study(runs=1, iterations=300, scenario_dir=repo_root / "scenarios")
    group = study.groups[0]
    scenario = load_scenario(group.scenario, list(group.overrides))
    dut = plan(scenario, make_checker(scenario, "planar"), algorithm="social_rrt_star", iterations=300, seed=0)
    assert dut.success and not dut.optimized
    cost, wp = SocialCost.from_scenario(scenario), dut.waypoints
    assert dut.cost == pytest.approx(float(cost.motion_cost(wp[:-1], wp[1:]).sum()), rel=1e-12)
    assert dut.cost == pytest.approx(dense_social_integral(cost, wp), rel=1e-3)
    assert 0.001 * dut.path_length > 2e-3 * dut.cost  # the tie-break would have shown
