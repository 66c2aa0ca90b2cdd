"""Replanning in the replay (drake_social.sim.replay_plans).

The log is hand-made: records with the documented fields of a ReplanResult
(drake_social.planning.replan: t, waypoints from the robot's configuration,
changed, status), recorded over the tiny scenario's robot as in
test_replay.py. The page's embedded commands are decoded
(drake_social.sim.replay_pack.unpack): one ribbon or ring per distinct plan or
wait, and its ``visible`` keyframes at the plan's frames; headless Chromium
(tests/sim/browser.py) shows the plan of each time and no other.
"""

from __future__ import annotations

import base64
import dataclasses as dc
import math
from pathlib import Path

import browser
import numpy as np
import pytest
from pydrake.trajectories import PiecewisePolynomial
from test_replay import KNOTS, TIMES, record

from drake_social.scenario import load_scenario
from drake_social.sim import replay, replay_plans
from drake_social.sim.replay_meshes import ribbon_mesh
from drake_social.sim.replay_pack import _EMBEDDED, unpack

PLANS = "/drake_social/plans"


@dc.dataclass(frozen=True)
class Replan:
    """The fields of a ReplanResult the replay reads (the plans; the reason and the candidate's cost
    for the label of what was predicted, test_replay_predicted.py)."""

    t: float
    waypoints: np.ndarray
    changed: bool
    status: str
    cost: float = 1.0
    reason: str = ""
    candidate_cost: float = math.inf


def log() -> list[Replan]:
    """Initial plan, kept, a new plan at 1 s, a wait from 2 s (two replans),
    a new plan at 2.5 s, kept."""
    return [Replan(0.0, KNOTS, True, "initial"), Replan(0.5, KNOTS[1:], False, "kept"),
            Replan(1.0, KNOTS[[1, 3]], True, "new"), Replan(2.0, KNOTS[2:3], False, "wait", math.inf),
            Replan(2.2, KNOTS[2:3], False, "wait", math.inf), Replan(2.5, KNOTS[2:], True, "new"),
            Replan(3.0, KNOTS[3:] + [0.5, 0, 0, 0], False, "kept")]


def commands(html: Path) -> list[dict]:
    """The page's embedded Meshcat commands, decoded."""
    text = html.read_text(encoding="utf-8")
    return [unpack(base64.b64decode(m.group(2))) for m in _EMBEDDED.finditer(text)]


def plan_tracks(cmds: list[dict]) -> dict[str, list[tuple[int, bool]]]:
    """{path: [(frame, visible), ...]} of the animation's plan nodes."""
    out = {}
    for c in cmds:
        if c.get("type") == "set_animation":
            for a in c["animations"]:
                if a["path"].startswith(PLANS + "/"):
                    (track,) = a["clip"]["tracks"]
                    assert track["name"] == ".visible" and track["type"] == "boolean"
                    out[a["path"]] = [(int(k["time"]), bool(k["value"])) for k in track["keys"]]
    return out


@pytest.fixture(scope="module")
def replanned(tmp_path_factory, tiny_scenario_path):
    scenario = load_scenario(tiny_scenario_path)
    html = tmp_path_factory.mktemp("plans") / "replay.html"
    record(scenario, PiecewisePolynomial.FirstOrderHold(TIMES, KNOTS.T), html, KNOTS,
           before_overlays=lambda m: replay.draw_overlays(m, scenario, KNOTS, replans=log()))
    return html, scenario


# --- pure parts -----------------------------------------------------------------


def test_plan_spans_are_the_changes_and_the_waits():
    spans = replay_plans.plan_spans(log())
    assert [(s.start, s.end, s.wait, s.replan) for s in spans] == [
        (0.0, 1.0, False, 0), (1.0, 2.0, False, 2), (2.0, 2.5, True, 3), (2.5, None, False, 5)]
    np.testing.assert_array_equal(spans[1].waypoints, KNOTS[[1, 3]])
    np.testing.assert_array_equal(spans[2].waypoints, KNOTS[2:3])
    # Leaving a wait begins a span even when the path did not "change".
    resumed = log()[:4] + [Replan(2.4, KNOTS[2:], False, "kept")]
    assert [s.start for s in replay_plans.plan_spans(resumed)] == [0.0, 1.0, 2.0, 2.4]
    # A run that never changes its plan: one span from the first replan.
    once = [Replan(0.0, KNOTS, True, "initial")] + [Replan(0.1 * k, KNOTS[1:], False, "kept") for k in range(1, 5)]
    assert [(s.start, s.end) for s in replay_plans.plan_spans(once)] == [(0.0, None)]
    assert replay_plans.plan_spans([]) == []


def test_plan_spans_check_the_log():
    with pytest.raises(ValueError, match=r"replans\[1\]\.t"):
        replay_plans.plan_spans([Replan(1.0, KNOTS, True, "initial"), Replan(0.5, KNOTS, True, "new")])
    with pytest.raises(ValueError, match=r"replans\[0\]\.status"):
        replay_plans.plan_spans([Replan(0.0, KNOTS, True, "moved")])
    with pytest.raises(ValueError, match=r"replans\[0\]\.waypoints"):
        replay_plans.plan_spans([Replan(0.0, np.zeros((0, 4)), True, "initial")])


def test_ring_mesh():
    vertices, faces = replay_plans.ring_mesh(1.0, 2.0, 0.4, 0.6, 0.02, segments=8)
    r = np.hypot(vertices[0] - 1.0, vertices[1] - 2.0)
    np.testing.assert_allclose(r[0::2], 0.4)
    np.testing.assert_allclose(r[1::2], 0.6)
    assert faces.shape == (3, 16) and faces.max() == 15 and np.all(vertices[2] == 0.02)
    with pytest.raises(ValueError, match="inner < outer"):
        replay_plans.ring_mesh(0, 0, 0.5, 0.5, 0)


# --- the page ---------------------------------------------------------------------


def test_one_visibility_animated_node_per_plan_change(replanned):
    html, scenario = replanned
    cmds = commands(html)
    fps = scenario.execution.replay_fps
    objects = {c["path"]: c for c in cmds if c.get("type") == "set_object" and c["path"].startswith(PLANS + "/")}
    assert sorted(objects) == [f"{PLANS}/{k}" for k in range(4)]
    # Frames of 0, 1, 2 and 2.5 s: each visible from its frame until the next one's.
    f = [int(round(t * fps)) for t in (0.0, 1.0, 2.0, 2.5)]
    assert plan_tracks(cmds) == {
        f"{PLANS}/0": [(0, True), (f[1], False)],
        f"{PLANS}/1": [(0, False), (f[1], True), (f[2], False)],
        f"{PLANS}/2": [(0, False), (f[2], True), (f[3], False)],
        f"{PLANS}/3": [(0, False), (f[3], True)],
    }
    # Before the animation plays, only the first plan shows; the one path is not drawn.
    shown = {c["path"]: c["value"] for c in cmds if c.get("type") == "set_property"
             and c["path"].startswith(PLANS + "/") and c["property"] == "visible"}
    assert shown == {f"{PLANS}/0": True, f"{PLANS}/1": False, f"{PLANS}/2": False, f"{PLANS}/3": False}
    assert not [c for c in cmds if c.get("path") == "/drake_social/path"]
    # The ribbons are the plans' base paths, the wait a ring about where the robot holds.
    width = replay_plans.path_width(scenario)
    for k, wp in ((0, KNOTS), (1, KNOTS[[1, 3]]), (3, KNOTS[2:])):
        vertices, _ = ribbon_mesh(wp[:, :2], width, replay_plans.PATH_Z)
        geometry = objects[f"{PLANS}/{k}"]["object"]["geometries"][0]
        got = _positions(geometry)
        np.testing.assert_allclose(got, vertices.T, atol=1e-6)
    ring = _positions(objects[f"{PLANS}/2"]["object"]["geometries"][0])
    radius = np.hypot(ring[:, 0] - KNOTS[2, 0], ring[:, 1] - KNOTS[2, 1])
    base = scenario.robot.base_radius
    np.testing.assert_allclose(radius[0::2], base + width, atol=1e-6)
    np.testing.assert_allclose(radius[1::2], base + 3 * width, atol=1e-6)


def _positions(geometry: dict) -> np.ndarray:
    """(n, 3) vertex positions of a three.js BufferGeometry as meshcat sends it."""
    array = geometry["data"]["attributes"]["position"]["array"]
    code, data = array  # MessagePack extension: typed array (float32, little-endian)
    return np.frombuffer(data, "<f4").reshape(-1, 3)


def test_without_replans_the_page_is_as_before(tiny_scenario_path):
    """An empty or absent log draws exactly what draw_overlays draws without one."""
    scenario = load_scenario(tiny_scenario_path)
    pages = []
    for replans in (None, []):
        meshcat = replay.make_meshcat()
        replay.draw_overlays(meshcat, scenario, KNOTS, replans=replans)
        pages.append(meshcat.StaticHtml())
    assert pages[0] == pages[1]
    meshcat = replay.make_meshcat()
    replay.draw_overlays(meshcat, scenario, KNOTS)
    assert meshcat.StaticHtml() == pages[0]


def test_same_frame_replacements_are_not_drawn(tiny_scenario_path):
    scenario = load_scenario(tiny_scenario_path)
    meshcat = replay.make_meshcat()
    # 1.0 s and 1.01 s fall in frame 30 at 30 fps: the first is never on screen.
    replans = [Replan(0.0, KNOTS, True, "initial"), Replan(1.0, KNOTS[1:], True, "new"),
               Replan(1.01, KNOTS[2:], True, "new"), Replan(1.5, KNOTS[2:3] * [1, 1, 0, 0], True, "new")]
    drawn = replay_plans.animate_plans(meshcat, scenario, replans, 30.0)
    # 0 and 2 drawn; 1 replaced within its frame; 3's base does not move (no ribbon).
    assert drawn == 2
    with pytest.raises(ValueError, match="fps"):
        replay_plans.animate_plans(meshcat, scenario, replans, 0.0)


@pytest.mark.slow
def test_browser_shows_the_plan_of_each_time(replanned):
    browser.require_chromium()
    html, _ = replanned
    times = [0.2, 1.5, 2.2, 3.5]  # one within each of the four spans
    for k in range(4):
        assert browser.visible_at(html, times, f"{PLANS}/{k}") == [j == k for j in range(4)], k


def test_the_replanners_records_are_read():
    """ReplanResult itself (drake_social.planning.replan), as SimulationResult.replans holds it."""
    from drake_social.planning.replan import ReplanResult

    def result(t, wp, status):
        waiting = status == "wait"
        return ReplanResult(t, wp, math.inf if waiting else 1.0, status in ("initial", "new"), status, "why", 0.01,
                            100, False, 1.0, 1.0, int(round(10 * t)))

    replans = [result(0.0, KNOTS, "initial"), result(0.1, KNOTS, "kept"), result(0.2, KNOTS[2:3], "wait"),
               result(0.3, KNOTS[2:], "kept"), result(0.4, KNOTS[[2, 3]], "new")]
    spans = replay_plans.plan_spans(replans)
    assert [(s.start, s.wait) for s in spans] == [(0.0, False), (0.2, True), (0.3, False), (0.4, False)]
