"""What the robot predicted, in the replay (drake_social.sim.replay_predicted).

The log and its kept predictions are hand-made (the documented fields of a
ReplanResult and PredictedPeople), recorded over the tiny scenario's robot as
in test_replay_plans.py. The page's embedded commands are decoded: the
predicted people of each plan and wait are discs at the kept positions
(the culprit's wider, in their own node), visible exactly while that plan or
wait is in force; the label while it is new (a wait's: all along); headless
Chromium shows them at those times only.
"""

from __future__ import annotations

import dataclasses as dc
import math

import browser
import numpy as np
import pytest
from pydrake.trajectories import PiecewisePolynomial
from test_replay import KNOTS, TIMES, record
from test_replay_plans import Replan, _positions, commands

from drake_social.people.predicted import PredictedPeople
from drake_social.scenario import load_scenario
from drake_social.sim import replay, replay_predicted
from drake_social.sim.replay_predicted import CULPRIT_HALO, LABEL_SECONDS, SAME_PLACE

NODE = "/drake_social/predicted"
SEGMENTS = 12


def log() -> list[Replan]:
    """As test_replay_plans.log(): spans from replans 0 (t 0), 2 (1 s, new: unsafe), 3 (2 s, wait) and
    5 (2.5 s, new: cheaper)."""
    return [Replan(0.0, KNOTS, True, "initial"), Replan(0.5, KNOTS[1:], False, "kept"),
            Replan(1.0, KNOTS[[1, 3]], True, "new", reason="the current path is not safe any more (motion 1, "
                   "t = 1.20 .. 1.90 s comes within 0.05 m of a predicted person)"),
            Replan(2.0, KNOTS[2:3], False, "wait", math.inf, "waiting: a person is 0.010 m from the robot now"),
            Replan(2.2, KNOTS[2:3], False, "wait", math.inf, "waiting"),
            Replan(2.5, KNOTS[2:], True, "new", 3.0, "the search's path costs 3, below (1 - 0.05) x 4", 4.0),
            Replan(3.0, KNOTS[3:] + [0.5, 0, 0, 0], False, "kept")]


def _predicted(replan: int, t: float, culprit: int = -1) -> PredictedPeople:
    """Two people over 3 times 0.6 s apart: "ann" walks east 0.5 m a step (absent at the last), "bob" stands
    (one disc: his repeats fall within SAME_PLACE)."""
    times = t + 0.6 * np.arange(3)
    positions = np.array([[[1.0 + 0.5 * j, 4.0], [6.0, 1.0 + 0.2 * SAME_PLACE * j]] for j in range(3)])
    present = np.array([[True, True], [True, True], [False, True]])
    return PredictedPeople(replan, t, times, positions, present, [0.25, 0.3], [0, 1], ("ann", "bob"), culprit)


PREDICTED = [_predicted(0, 0.0), _predicted(2, 1.0, culprit=0), _predicted(3, 2.0, culprit=1), _predicted(5, 2.5)]


@pytest.fixture(scope="module")
def page(tmp_path_factory, tiny_scenario_path):
    scenario = load_scenario(tiny_scenario_path)
    html = tmp_path_factory.mktemp("predicted") / "replay.html"
    record(scenario, PiecewisePolynomial.FirstOrderHold(TIMES, KNOTS.T), html, KNOTS,
           before_overlays=lambda m: replay.draw_overlays(m, scenario, KNOTS, replans=log(), predicted=PREDICTED))
    return html, scenario


def _tracks(cmds) -> dict[str, list[tuple[int, bool]]]:
    out = {}
    for c in cmds:
        if c.get("type") == "set_animation":
            for a in c["animations"]:
                if a["path"].startswith(NODE + "/"):
                    (track,) = a["clip"]["tracks"]
                    assert track["name"] == ".visible"
                    out[a["path"]] = [(int(k["time"]), bool(k["value"])) for k in track["keys"]]
    return out


def _discs(geometry) -> tuple[np.ndarray, np.ndarray]:
    """Centres (D, 2) and rim radii (D, SEGMENTS) of a disc mesh as sent."""
    xyz = _positions(geometry).reshape(-1, SEGMENTS + 1, 3)
    centres = xyz[:, 0, :2]
    return centres, np.hypot(*(xyz[:, 1:, :2] - centres[:, None, :]).transpose(2, 0, 1))


def test_the_predicted_people_of_each_plan_while_it_is_in_force(page):
    html, scenario = page
    cmds = commands(html)
    fps = scenario.execution.replay_fps
    f = [int(round(t * fps)) for t in (0.0, 1.0, 2.0, 2.5)]
    tracks = _tracks(cmds)
    # The folders: as the plans' ribbons and ring.
    assert {k: v for k, v in tracks.items() if k.count("/") == 3} == {
        f"{NODE}/0": [(0, True), (f[1], False)], f"{NODE}/1": [(0, False), (f[1], True), (f[2], False)],
        f"{NODE}/2": [(0, False), (f[2], True), (f[3], False)], f"{NODE}/3": [(0, False), (f[3], True)]}
    # The labels: from the replan for LABEL_SECONDS or until the span ends (a wait's: all of it); none for the first.
    assert {k: v for k, v in tracks.items() if k.endswith("/why")} == {
        f"{NODE}/1/why": [(f[1], True), (f[2], False)], f"{NODE}/2/why": [(f[2], True), (f[3], False)],
        f"{NODE}/3/why": [(f[3], True), (int(round((2.5 + LABEL_SECONDS) * fps)), False)]}
    objects = {c["path"]: c["object"] for c in cmds if c.get("type") == "set_object" and c["path"].startswith(NODE)}
    # Span 1: ann is the culprit (3 - 1 absent = 2 orange discs, wider); bob one teal disc.
    centres, rims = _discs(objects[f"{NODE}/1/culprit"]["geometries"][0])
    np.testing.assert_allclose(centres, [[1.0, 4.0], [1.5, 4.0]], atol=1e-6)
    np.testing.assert_allclose(rims, 0.25 + CULPRIT_HALO, atol=1e-5)
    centres, rims = _discs(objects[f"{NODE}/1/people"]["geometries"][0])
    np.testing.assert_allclose(centres, [[6.0, 1.0]], atol=1e-6)
    np.testing.assert_allclose(rims, 0.3, atol=1e-5)
    # Span 2 (the wait): bob is the culprit; ann in teal.
    centres, _ = _discs(objects[f"{NODE}/2/culprit"]["geometries"][0])
    np.testing.assert_allclose(centres, [[6.0, 1.0]], atol=1e-6)
    centres, _ = _discs(objects[f"{NODE}/2/people"]["geometries"][0])
    np.testing.assert_allclose(centres, [[1.0, 4.0], [1.5, 4.0]], atol=1e-6)
    assert f"{NODE}/0/culprit" not in objects and f"{NODE}/3/culprit" not in objects
    assert f"{NODE}/0/why" not in objects and f"{NODE}/3/why" in objects
    # The discs' colours: faded teal, the culprit orange.
    materials = {p: o["materials"][0] for p, o in objects.items() if "materials" in o}
    assert materials[f"{NODE}/1/people"]["transparent"] and materials[f"{NODE}/1/people"]["opacity"] == \
        pytest.approx(replay_predicted.PREDICTED_RGBA.a())


def test_label_lines():
    lines = replay_predicted.label_lines(log()[2], PREDICTED[1])
    assert lines[0] == "t = 1.0 s: new route: not safe any more"
    assert lines[1].startswith("because of 'ann' (orange")
    assert " ".join(lines[2:]).startswith("the current path is not safe any more (motion 1, t = 1.20 .. 1.90 s")
    long = dc.replace(log()[5], reason="word " * 200)
    lines = replay_predicted.label_lines(long, None)
    assert len(lines) == replay_predicted.LABEL_LINES and lines[-1].endswith("...")
    assert lines[0] == "t = 2.5 s: new route: cheaper"


def test_without_predictions_the_page_is_as_before(tiny_scenario_path, tmp_path):
    """No predictions, or only one of a replan that began no plan or wait (replan 1 kept the
    path): the page is the one drawn without the argument, with no predicted node in its
    decoded commands; a prediction of a replan that began a span is drawn."""
    scenario = load_scenario(tiny_scenario_path)
    pages = []
    for k, predicted in enumerate(((_predicted(1, 0.5),), None, (_predicted(2, 1.0),))):
        meshcat = replay.make_meshcat()
        if predicted is None:
            replay.draw_overlays(meshcat, scenario, KNOTS, replans=log())
        else:
            replay.draw_overlays(meshcat, scenario, KNOTS, replans=log(), predicted=predicted)
        page = tmp_path / f"page{k}.html"
        page.write_text(meshcat.StaticHtml(), encoding="utf-8")
        pages.append(page)
    drawn = [any(str(c.get("path", "")).startswith(NODE) for c in commands(p)) for p in pages]
    assert pages[0].read_text(encoding="utf-8") == pages[1].read_text(encoding="utf-8")
    assert drawn == [False, False, True]


@pytest.mark.slow
def test_browser_shows_the_predictions_of_each_time(page):
    browser.require_chromium()
    html, _ = page
    times = [0.2, 1.5, 2.2, 3.5]  # one within each of the four spans
    for k in range(4):
        assert browser.visible_at(html, times, f"{NODE}/{k}/people") == [j == k for j in range(4)], k
