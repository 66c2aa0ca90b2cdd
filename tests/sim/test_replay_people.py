"""Walking people in the replay (drake_social.sim.replay_people).

The people are a hand-built :class:`PeopleLog` (walkers on straight lines
back and forth, one who enters and leaves, one who stands), recorded over the
tiny scenario's robot as in test_replay.py; the page is read back in headless
Chromium (tests/sim/browser.py): each walker's frame at a time is the log's
pose at that time, hidden while the person is absent.
"""

from __future__ import annotations

import dataclasses as dc
import math
from pathlib import Path

import browser
import numpy as np
import pytest
from pydrake.math import RigidTransform, RotationMatrix
from pydrake.trajectories import PiecewisePolynomial
from test_replay import KNOTS, TIMES, record

from drake_social.cost.agf import PersonalSpace, agf_algorithm1
from drake_social.people import PeopleLog, people_model
from drake_social.scenario import load_scenario
from drake_social.sim import replay, replay_people
from drake_social.viz.tracks import moving_people

ROOT = Path(__file__).parents[2]


def walkers_log(bounds, count: int, duration: float, dt: float = 0.05, *, enter: tuple[float, float] | None = None,
                stander: bool = False, speed: float = 1.2) -> PeopleLog:
    """``count`` people walking back and forth along horizontal lines at
    ``speed`` m/s (heading along the motion, velocity set); with ``enter``
    = (t_in, t_out) person 0 is present only in [t_in, t_out); with
    ``stander`` one more person stands still at the room's centre."""
    x0, y0, x1, y1 = (float(v) for v in bounds)
    times = np.arange(0.0, duration + dt / 2, dt)
    span = (x1 - x0) - 2.0
    pos = np.zeros((len(times), count, 2))
    head = np.zeros((len(times), count))
    vel = np.zeros((len(times), count, 2))
    for i in range(count):
        v = speed * (0.8 + 0.4 * i / max(1, count - 1))
        phase = (v * times + i * span / max(1, count)) % (2 * span)  # distance along a there-and-back
        back = phase > span
        pos[:, i, 0] = x0 + 1.0 + np.where(back, 2 * span - phase, phase)
        pos[:, i, 1] = y0 + 1.0 + (y1 - y0 - 2.0) * (i + 0.5) / count
        head[:, i] = np.where(back, math.pi, 0.0)
        vel[:, i, 0] = np.where(back, -v, v)
    present = np.ones((len(times), count), bool)
    if enter is not None:
        present[:, 0] = (times >= enter[0]) & (times < enter[1])
    radii, names = np.full(count, 0.25), tuple(f"w{i}" for i in range(count))
    if stander:
        pos = np.concatenate([pos, np.broadcast_to([(x0 + x1) / 2, (y0 + y1) / 2], (len(times), 1, 2))], axis=1)
        head = np.concatenate([head, np.full((len(times), 1), 0.5)], axis=1)
        vel = np.concatenate([vel, np.zeros((len(times), 1, 2))], axis=1)
        present = np.concatenate([present, np.ones((len(times), 1), bool)], axis=1)
        radii, names = np.r_[radii, 0.3], names + ("stander",)
    return PeopleLog(times=times, positions=pos, headings=head, velocities=vel, present=present, radii=radii,
                     names=names)


@dc.dataclass
class Walked:
    html: Path
    scenario: object
    people: PeopleLog


@pytest.fixture(scope="module")
def walked(tmp_path_factory, tiny_scenario_path) -> Walked:
    scenario = load_scenario(tiny_scenario_path)
    people = walkers_log(scenario.world.bounds, 2, TIMES[-1], enter=(1.0, 3.0), stander=True, speed=1.0)
    html = tmp_path_factory.mktemp("walkers") / "replay.html"
    record(scenario, PiecewisePolynomial.FirstOrderHold(TIMES, KNOTS.T), html, KNOTS, people=people)
    return Walked(html, scenario, people)


# --- pure parts -----------------------------------------------------------------


def test_moving_and_standing_people():
    people = walkers_log([0, 0, 8, 6], 2, 4.0, stander=True)
    np.testing.assert_array_equal(moving_people(people), [True, True, False])
    standing = replay_people.standing_people(people)
    assert standing.names == ("stander",)
    np.testing.assert_allclose(standing.positions, [[4.0, 3.0]])
    # A person who only appears moves too; one always absent does not stand.
    entering = walkers_log([0, 0, 8, 6], 1, 4.0, enter=(1.0, 5.0), speed=0.0)
    assert entering.velocities.max() == 0 and moving_people(entering).tolist() == [True]
    gone = dc.replace(people, present=np.c_[people.present[:, :2], np.zeros(len(people.times), bool)])
    assert replay_people.standing_people(gone).count == 0


def test_personal_space_texture_is_the_agf_in_the_person_frame():
    space = PersonalSpace(sigma_h=2.0, sigma_s=4 / 3, sigma_r=1.0, threshold=0.2)
    (u0, v0, u1, v1), values, png, alpha = replay_people.personal_space_texture(space, vmax=1.0)
    reach = math.sqrt(-2 * math.log(0.2))
    np.testing.assert_allclose([u0, v0, u1, v1], [-1.0 * reach, -4 / 3 * reach, 2.0 * reach, 4 / 3 * reach])
    nv, nu = values.shape
    u = u0 + (np.arange(nu) + 0.5) * (u1 - u0) / nu
    v = v0 + (np.arange(nv) + 0.5) * (v1 - v0) / nv
    # Algorithm 1 of the paper for a person at the origin facing +x.
    for j, i in [(nv // 2, nu // 2), (nv // 2, nu - 3), (2, nu // 3), (nv // 3, 1), (nv - 1, nu - 1)]:
        assert values[j, i] == pytest.approx(agf_algorithm1(u[i], v[j], (0.0, 0.0, 0.0), space), abs=1e-12)
    assert values[0, 0] == 0.0 and values.max() == pytest.approx(1.0, abs=0.01)
    assert png.startswith(b"\x89PNG") and alpha.startswith(b"\x89PNG")


def test_speed_scaling_sigma():
    scenario = load_scenario(ROOT / "scenarios" / "office_bar.yaml")
    np.testing.assert_allclose(replay_people.walker_sigma_h(scenario, [0.0, 1.0]), [scenario.social.sigma_h] * 2)
    scaled = dc.replace(scenario, social=dc.replace(scenario.social, speed_scaling=True))
    np.testing.assert_allclose(replay_people.walker_sigma_h(scaled, [0.0, 0.2, 1.5]), [0.5, 0.5, 3.0])


def test_arguments_are_checked(tiny_scenario_path):
    scenario = load_scenario(tiny_scenario_path)
    people = walkers_log(scenario.world.bounds, 1, 1.0)
    meshcat = replay.make_meshcat()
    for kwargs, field in (({"fps": 0.0}, "fps"), ({"fps": 30.0, "rate": 0.0}, "rate"),
                          ({"fps": 30.0, "vmax": math.nan}, "vmax")):
        with pytest.raises(ValueError, match=field):
            replay.animate_people(meshcat, scenario, people, **kwargs)


def test_static_people_leave_the_overlays_as_they_were(tiny_scenario_path):
    """A static log draws exactly what draw_overlays draws without one."""
    scenario = load_scenario(tiny_scenario_path)
    state = people_model(scenario).state_at(0.0)
    static = PeopleLog.from_states([state, dc.replace(state, t=5.0)])
    assert static.static
    pages = []
    for people in (None, static):
        meshcat = replay.make_meshcat()
        replay.draw_overlays(meshcat, scenario, KNOTS, people=people)
        pages.append(meshcat.StaticHtml())
    assert pages[0] == pages[1]
    assert replay.animate_people(replay.make_meshcat(), scenario, static, 30.0) == 0


# --- the page ---------------------------------------------------------------------


def test_walkers_follow_the_log(walked):
    browser.require_chromium()
    times = [0.5, 1.5, 2.2, 3.7]
    assert not walked.people.static
    for i in (0, 1):
        result = browser.probe(walked.html, times, f"{replay.OVERLAY_PREFIX}/walkers/{i}")
        assert "walkers" in result["overlays"]
        for (t, x, y, z), (_, yaw, shown, _) in zip(result["positions"], result["frames"]):
            state = walked.people.state_at(t)
            assert shown == bool(state.present[i]), f"person {i} at t = {t} s"
            if not shown:
                continue
            # Keyframes every 1/10 s, linear in between: exact on a straight
            # walk, up to one keyframe interval of motion at a turn.
            speed = float(np.max(np.linalg.norm(walked.people.velocities[:, i], axis=1)))
            np.testing.assert_allclose([x, y, z], [*state.positions[i], 0.0],
                                       atol=0.003 + speed / replay_people.PEOPLE_REPLAY_FPS, err_msg=f"t = {t}")
            assert math.cos(yaw - state.headings[i]) == pytest.approx(1.0, abs=1e-3)
    # Person 0 enters at 1 s and leaves at 3 s.
    frames = browser.probe(walked.html, [0.5, 1.5, 3.5], f"{replay.OVERLAY_PREFIX}/walkers/0")["frames"]
    assert [f[2] for f in frames] == [False, True, False]


def test_walkers_pose_at_keyframes_is_exact(walked):
    """At a keyframe time, the page's pose equals the log's (float32 page)."""
    browser.require_chromium()
    times = [0.3, 1.2, 2.0]  # multiples of 1 / PEOPLE_REPLAY_FPS
    result = browser.probe(walked.html, times, f"{replay.OVERLAY_PREFIX}/walkers/1")
    for (t, x, y, _), (_, yaw, _, _) in zip(result["positions"], result["frames"]):
        state = walked.people.state_at(t)
        np.testing.assert_allclose([x, y], state.positions[1], atol=1e-4, err_msg=f"t = {t}")
        assert math.cos(yaw - state.headings[1]) == pytest.approx(1.0, abs=1e-6)


def test_standing_person_stays_in_the_static_overlays(walked):
    """The stander (person 2) keeps a static arrow and no walker node; the
    walkers (0, 1) have no static arrow."""
    browser.require_chromium()
    result = browser.probe(walked.html, [0.0, 3.0], f"{replay.OVERLAY_PREFIX}/people/2")
    # Drawn in world coordinates under a node that never moves.
    assert [p[1:3] for p in result["positions"]] == [pytest.approx([0.0, 0.0], abs=1e-9)] * 2
    for missing in ("walkers/2", "people/0", "people/1"):
        with pytest.raises(RuntimeError, match="no scene-tree node"):
            browser.probe(walked.html, [0.0], f"{replay.OVERLAY_PREFIX}/{missing}")


def test_speed_scaling_scales_the_quad(tmp_path, tiny_scenario_path):
    browser.require_chromium()
    scenario = load_scenario(tiny_scenario_path)
    scenario = dc.replace(scenario, social=dc.replace(scenario.social, speed_scaling=True))
    # Walkers at 0.8 and 1.2 m/s: sigma_h = 1.6 and 2.4 m (Kirby: max(2 v, 0.5)).
    people = walkers_log(scenario.world.bounds, 2, TIMES[-1], speed=1.0)
    html = tmp_path / "replay.html"
    record(scenario, PiecewisePolynomial.FirstOrderHold(TIMES, KNOTS.T), html, KNOTS, people=people)
    for i, sigma_h in ((0, 1.6), (1, 2.4)):
        result = browser.probe(html, [0.5, 2.0], f"{replay.OVERLAY_PREFIX}/walkers/{i}/agf")
        for _, _, _, scale in result["frames"]:
            assert scale == pytest.approx(sigma_h / scenario.social.sigma_h, rel=1e-6)


def test_ten_walkers_two_minutes_stay_under_10_mb(tmp_path):
    """The office, 10 walkers over 120 s at the default replay rate (30 fps).

    The walkers' bodies (SceneGraph geometry on moving frames) are recorded
    by the visualizer in a full run; here each gets a transform track at
    every frame, as the visualizer records it, so the size is the full run's
    (6.6 MB with the float32 animation; 10.3 MB with float64).
    """
    scenario = load_scenario(ROOT / "scenarios" / "office_bar.yaml")
    fps = scenario.execution.replay_fps
    assert fps == 30.0
    duration = 120.0
    xy = np.array([[1.5, 4.8], [6.0, 4.8], [9.0, 5.6], [12.0, 5.2], [16.0, 4.8], [18.5, 4.8]])
    q = np.c_[xy, np.full(len(xy), scenario.start[2]), np.full(len(xy), scenario.start[3])]
    q[:, 2] += 0.3 * np.sin(np.arange(len(xy)))
    times = np.linspace(0.0, duration, len(xy))
    people = walkers_log(scenario.world.bounds, 10, duration, dt=scenario.execution.control_period * 10,
                         enter=(20.0, 90.0))

    def bodies(meshcat):
        recording = meshcat.get_mutable_recording()
        for k in range(int(duration * fps) + 1):
            state = people.state_at(k / fps)
            for i in range(people.count):
                x, y = state.positions[i]
                recording.SetTransform(k, f"/drake/illustration/walker_{i}/body",
                                       RigidTransform(RotationMatrix.MakeZRotation(state.headings[i]), [x, y, 0.0]))

    size = record(scenario, PiecewisePolynomial.FirstOrderHold(times, q.T), tmp_path / "replay.html", q,
                  people=people, before_overlays=bodies)
    assert size < 10e6
