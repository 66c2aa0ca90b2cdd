"""``experiment paper`` runs the paper's planner (the raw tree path, the fixed
r_near) although the scenario files' defaults are an optimised path and the
shrinking radius."""

from __future__ import annotations

from drake_social.experiments.study import PAPER_PLANNER, paper_study
from drake_social.scenario import PlannerOptions, load_scenario


def test_the_shipped_scenarios_default_to_the_optimised_path_and_the_shrinking_radius(repo_root):
    assert (PlannerOptions().optimize, PlannerOptions().near_radius_mode) == (True, "shrinking")
    for name in ("office_bar", "generic_L"):
        planner = load_scenario(repo_root / "scenarios" / f"{name}.yaml").planner
        assert (planner.optimize, planner.near_radius_mode) == (True, "shrinking"), name
    # the tests' scenario says otherwise: the paper's raw planner
    planner = load_scenario(repo_root / "scenarios" / "tiny.yaml").planner
    assert (planner.optimize, planner.near_radius_mode) == (False, "fixed")


def test_every_paper_group_pins_the_raw_planner_and_the_fixed_radius(repo_root):
    study = paper_study(runs=2, iterations=100, scenario_dir=repo_root / "scenarios")
    assert len(study.groups) == 5
    for group in study.groups:
        assert group.overrides[-1] == PAPER_PLANNER  # last: nothing after it can undo it
        scenario = load_scenario(group.scenario, list(group.overrides))
        assert scenario.planner.optimize is False and scenario.planner.near_radius_mode == "fixed", group.name
        # the pin changes nothing else of the planner
        unpinned = load_scenario(group.scenario, list(group.overrides[:-1]))
        assert (scenario.planner.near_radius, scenario.planner.planning_range, scenario.planner.iterations) == (
            unpinned.planner.near_radius, unpinned.planner.planning_range, unpinned.planner.iterations)
        assert scenario.social == unpinned.social


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
