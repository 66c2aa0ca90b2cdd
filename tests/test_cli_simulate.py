"""``drake-social simulate``: a real run of tiny.yaml, its files, its replay in
a browser against the executed trajectory, its exit codes and input errors."""

from __future__ import annotations

import contextlib
import io
import json
import sys
from pathlib import Path

import numpy as np
import pytest
from matplotlib.image import imread

from drake_social.cli import main

sys.path.insert(0, str(Path(__file__).parent / "sim"))
import browser  # noqa: E402  (the shared headless-Chromium harness of tests/sim)

# ``drake-social simulate`` end to end: plans and Drake simulations.
pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def planned(tmp_path_factory, tiny_scenario_path):
    out = tmp_path_factory.mktemp("plan")
    assert main(["plan", str(tiny_scenario_path), "--checker", "numpy", "--out", str(out)]) == 0
    return out / "path.csv"


@pytest.fixture(scope="module")
def simulated(tmp_path_factory, tiny_scenario_path, planned):
    out = tmp_path_factory.mktemp("simulate")
    stdout = io.StringIO()
    with contextlib.redirect_stdout(stdout):
        code = main(["simulate", str(tiny_scenario_path), "--path", str(planned), "--out", str(out)])
    return code, out, stdout.getvalue()


def test_simulate_writes_its_files(simulated, planned):
    code, out, stdout = simulated
    assert code == 0
    # The page to open is the folder's link, which stays valid after the next run.
    assert stdout.splitlines()[-1] == f"open {(out.resolve() / 'replay.html').as_uri()} in a browser to watch the replay"
    names = sorted(p.name for p in out.iterdir() if not p.name.startswith("."))
    assert names == ["executed.csv", "motion.png", "people.csv", "replay.html", "sim.json", "tracking.png"]
    record = json.loads((out / "sim.json").read_text())
    assert record["reached"] and record["collision_free"]
    assert record["mode"] == "kinematic" and record["execution"] == "synchronized"
    assert record["max_point_deviation"]["max"] < 0.01
    # The followed path is the file's.
    np.testing.assert_array_equal(np.array(record["waypoints"]), np.loadtxt(planned, delimiter=",", skiprows=1))
    executed = np.loadtxt(out / "executed.csv", delimiter=",", skiprows=1)
    assert executed.shape[1] == 9
    np.testing.assert_allclose(executed[-1, 1:5], record["waypoints"][-1], atol=0.06)
    assert record["time_to_goal"] == pytest.approx(executed[-2, 0])
    assert imread(out / "tracking.png").shape[0] > 500
    assert imread(out / "motion.png").shape[0] > 500


def test_replay_shows_the_executed_trajectory(simulated):
    browser.require_chromium()
    _, out, _ = simulated
    executed = np.loadtxt(out / "executed.csv", delimiter=",", skiprows=1)
    t_end = executed[-1, 0]
    times = [round(0.2 * t_end, 2), round(0.5 * t_end, 2), round(0.8 * t_end, 2)]
    result = browser.probe(out / "replay.html", times)
    # The run stops at the first quarter second after the goal (drake_social.sim.run._CHUNK).
    assert t_end - 0.04 <= result["duration"] <= t_end + 0.25 + 0.04
    assert sorted(result["overlays"]) == ["field", "path", "people"]
    fps = 30.0
    speed = np.max(np.hypot(executed[:, 5], executed[:, 6]))
    tolerance = 0.003 + speed / fps  # float32 in the page, plus one frame of motion
    positions = {t: np.array(xyz) for t, *xyz in result["positions"]}
    for t in times:
        expected = [np.interp(t, executed[:, 0], executed[:, 1]), np.interp(t, executed[:, 0], executed[:, 2]), 0.0]
        np.testing.assert_allclose(positions[t], expected, atol=tolerance, err_msg=f"t = {t} s")


def test_replay_first_view_is_the_whole_map(simulated, tmp_path):
    browser.require_chromium()
    _, out, _ = simulated
    png = browser.screenshot(out / "replay.html", tmp_path / "first.png", (1280, 720))
    image = np.round(imread(png)[:, :, :3] * 255).astype(int)
    assert len(np.unique(image.reshape(-1, 3), axis=0)) > 200
    # The map (not the white background) fills the middle band edge to edge in
    # height: the top-down frame holds the walls just inside the picture.
    column = image[:, image.shape[1] // 2]
    drawn = np.flatnonzero(np.any(column < 245, axis=1))
    assert drawn[0] < 0.1 * image.shape[0] and drawn[-1] > 0.9 * image.shape[0]


def test_time_limit_gives_exit_5(tmp_path, tiny_scenario_path, planned, capsys):
    code = main(["simulate", str(tiny_scenario_path), "--path", str(planned), "--no-replay", "--out", str(tmp_path),
                 "--set", "execution: {time_limit: 1.5}"])
    assert code == 5
    assert "not reached within the time limit of 1.5 s" in capsys.readouterr().err
    record = json.loads((tmp_path / "sim.json").read_text())
    assert record["reached"] is False and record["time_to_goal"] is None
    assert not (tmp_path / "replay.html").exists()


@pytest.mark.parametrize("text, message", [
    ("x,y,psi1,psi2\n1,2\n", "line 2"),
    ("a,b\n", "line 1: the header must be 'x,y,psi1,psi2'"),
    ("x,y,psi1,psi2\n1.0,2.5,0.0,1.5708\n", "at least 2 waypoints"),
    ("x,y,psi1,psi2\n1.0,2.5,0.0,1.5708\n6.5,2.5,0.0,nan\n", "line 3"),
    ("x,y,psi1,psi2\n2.0,2.5,0.0,1.5708\n6.5,2.5,0.0,1.5708\n", "is not the scenario's start"),
    ("x,y,psi1,psi2\n1.0,2.5,0.0,1.5708\n100,2.5,0,0\n6.5,2.5,0.0,1.5708\n",
     "(--path): line 3 (waypoint 1): x: 100.0 is outside the room [0.0, 8.0] (world.bounds)"),
    ("x,y,psi1,psi2\n1.0,2.5,0.0,1.5708\n\n2,2.5,0,10\n6.5,2.5,0.0,1.5708\n",
     "(--path): line 4 (waypoint 1): psi2: 10.0 is outside the joint range [-3.141592653589793, 3.141592653589793] (robot.joint_lower/joint_upper)"),
])
def test_bad_path_file_names_file_and_line(tmp_path, tiny_scenario_path, capsys, text, message):
    path = tmp_path / "path.csv"
    path.write_text(text)
    assert main(["simulate", str(tiny_scenario_path), "--path", str(path), "--no-replay",
                 "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert str(path) in err and message in err


def test_bad_mode_is_a_usage_error(tiny_scenario_path, capsys):
    assert main(["simulate", str(tiny_scenario_path), "--mode", "fast"]) == 2
    assert "invalid choice: 'fast'" in capsys.readouterr().err


def test_a_joint_limit_pass_exits_7_and_is_named_apart_from_collisions(tmp_path, tiny_scenario_path, capsys,
                                                                        monkeypatch):
    # A goal on psi1's upper limit pi, driven by a deliberately under-damped
    # servo (Kd = 12 1/s instead of 2 w = 120): the arm passes pi near the
    # goal without touching anything. The run is collision-free and its
    # finding is the limit, by name, joint, amount and time.
    import drake_social.sim.station as station

    monkeypatch.setattr(station, "servo_gains",
                        lambda: (np.array([0.0, 0.0, 3600.0, 3600.0]), np.array([50.0, 50.0, 12.0, 12.0])))
    out = tmp_path / "sim"
    code = main(["simulate", str(tiny_scenario_path), "--set", "goal: [6.5, 2.5, 3.141592653589793, 1.5708]",
                 "--mode", "dynamic", "--no-replay", "--out", str(out)])
    captured = capsys.readouterr()
    assert code == 7
    record = json.loads((out / "sim.json").read_text())
    assert record["reached"] and record["collision_free"] and record["first_collision_time"] is None
    assert record["within_limits"] is False
    (violation,) = record["limit_violations"]
    assert violation["joint"] == "psi1" and violation["bound"] == "upper"
    assert violation["limit"] == pytest.approx(np.pi, abs=0)
    executed = np.loadtxt(out / "executed.csv", delimiter=",", skiprows=1)
    beyond = executed[:, 3] - np.pi
    assert violation["max_excess"] == pytest.approx(beyond.max(), rel=1e-12) and beyond.max() > 0
    assert violation["first_time"] == pytest.approx(executed[np.argmax(beyond > 0), 0])
    assert "within the joint limits" not in captured.out and "BEYOND A LIMIT: psi1" in captured.out
    assert "collision-free" in captured.out and "COLLIDES" not in captured.out
    assert "drake-social: the executed trajectory passes a joint limit: psi1 " in captured.err
    assert "collides" not in captured.err


@pytest.mark.parametrize("name", ["sim.json", "executed.csv", "people.csv", "path.png", "tracking.png",
                                  "motion.png", "replay.html"])
def test_a_folder_named_like_an_output_is_refused_before_simulating(tmp_path, tiny_scenario_path, planned, capsys,
                                                                    name):
    out = tmp_path / "out"
    (out / name).mkdir(parents=True)
    code = main(["simulate", str(tiny_scenario_path), "--path", str(planned), "--no-replay", "--out", str(out)])
    captured = capsys.readouterr()
    assert code == 1 and captured.out == ""  # nothing simulated
    assert captured.err == (f"drake-social: error: {out / name} is a folder in the way of simulate's output {name}; "
                            "remove or rename it, or choose another --out\n")
    assert sorted(p.name for p in out.iterdir() if not p.name.startswith(".")) == [name]


def test_a_room_bound_pass_is_named_as_such(tmp_path, tiny_scenario_path, planned, capsys, monkeypatch):
    """A run whose base passes a room bound (the finding put into a real
    run's report): stderr and the summary name a room bound, not a joint limit."""
    import drake_social.sim.run as sim_run
    from drake_social.sim.results import LimitViolation

    real = sim_run.run_checked

    def passing_a_wall(*args, **kwargs):
        run = real(*args, **kwargs)
        run.report.within_limits = False
        run.report.limit_violations = [LimitViolation("base_x", "upper", 8.0, 1.0, 1.5, 0.01)]
        return run

    monkeypatch.setattr(sim_run, "run_checked", passing_a_wall)
    code = main(["simulate", str(tiny_scenario_path), "--path", str(planned), "--no-replay", "--out",
                 str(tmp_path / "out")])
    captured = capsys.readouterr()
    assert code == 7
    assert ("drake-social: the executed trajectory passes a room bound: base_x 0.01 m beyond its upper limit 8 at "
            "t = 1.50 s (first at t = 1.00 s)\n") in captured.err
    assert "joint limit" not in captured.err and "joint limits" not in captured.out
    assert "BEYOND A LIMIT: base_x 0.01 m" in captured.out


def test_a_run_within_its_limits_says_joint_limits_and_room_bounds(simulated):
    code, out, stdout = simulated
    assert code == 0 and "; collision-free; within the joint limits and room bounds; " in stdout


def test_simulate_help_describes_the_computed_torque_servo(capsys):
    assert main(["simulate", "--help"]) == 0
    text = " ".join(capsys.readouterr().out.split()).replace("- ", "-")  # argparse wraps at hyphens too
    assert "PD" not in text
    assert "dynamic (the MultibodyPlant driven by a computed-torque servo)" in text
    assert "passes a joint limit or a room bound" in text


def test_a_simulate_that_finds_no_path_shows_no_realtime_factor(tmp_path, capsys):
    """Nothing was simulated: the summary has no "nanx realtime"."""
    from test_cli_plan import WALLED

    scenario = tmp_path / "walled.yaml"
    scenario.write_text(WALLED)
    code = main(["simulate", str(scenario), "--checker", "numpy", "--iterations", "60", "--no-replay", "--out",
                 str(tmp_path / "out")])
    captured = capsys.readouterr()
    assert code == 3
    assert "no path to execute" in captured.out and "nan" not in captured.out and "realtime" not in captured.out


def test_replan_with_a_path_is_refused(tmp_path, tiny_scenario_path, planned, capsys):
    assert main(["simulate", str(tiny_scenario_path), "--path", str(planned), "--replan", "--no-replay",
                 "--out", str(tmp_path)]) == 2
    assert "--replan: replans the path; with --path" in capsys.readouterr().err
    assert not (tmp_path / "sim.json").exists()


def test_replan_writes_replans_csv_and_the_summary(tmp_path, tiny_scenario_path, capsys):
    pytest.importorskip("drake_social.planning.replan")
    code = main(["simulate", str(tiny_scenario_path), "--replan", "--no-replay", "--out", str(tmp_path),
                 "--set", "planner: {replan_iterations: 100, replan_rate: 5.0}"])
    out = capsys.readouterr().out
    record = json.loads((tmp_path / "sim.json").read_text())
    assert code == (0 if record["reached"] else 5)
    names = sorted(p.name for p in tmp_path.iterdir() if not p.name.startswith("."))
    assert names == ["executed.csv", "motion.png", "people.csv", "predictions.png", "replans.csv", "replans.png",
                     "sim.json", "tracking.png"]
    lines = (tmp_path / "replans.csv").read_text().splitlines()
    assert lines[0] == "t,plan_time,cost,changed,status,searched,iterations,deadline_hit"
    rows = [line.split(",") for line in lines[1:]]
    assert rows[0][4] == "initial" and float(rows[0][0]) == 0.0
    t = np.array([float(r[0]) for r in rows])
    np.testing.assert_allclose(np.diff(t), 0.2, atol=1e-9)  # every 1/rate s of simulated time
    assert {r[4] for r in rows[1:]} <= {"new", "kept", "wait"} and {r[3] for r in rows} <= {"0", "1"}
    summary = record["replanning"]
    plan_times = np.array([float(r[1]) for r in rows[1:]])
    assert summary["count"] == len(rows) - 1
    assert summary["changed"] == sum(r[3] == "1" for r in rows[1:])
    assert summary["waits"] == sum(r[4] == "wait" for r in rows[1:])
    assert summary["deadline_hits"] == sum(r[7] == "1" for r in rows[1:])
    assert summary["plan_time_median"] == pytest.approx(np.median(plan_times))
    assert summary["plan_time_p95"] == pytest.approx(np.percentile(plan_times, 95))
    assert summary["plan_time_max"] == pytest.approx(plan_times.max())
    assert (summary["rate"], summary["budget"]) == (5.0, 0.08)
    assert f"{summary['count']} replans at 5 Hz" in out
    # The followed path runs from the start to the goal.
    wp = np.array(record["waypoints"])
    assert "planner" not in record  # the replans are the record of the planning
    if record["reached"]:
        np.testing.assert_allclose(wp[-1], [6.5, 2.5, 0.0, 1.5708])


#: A person 0.03 m from the robot's base at the start of tiny.yaml (inside the 0.05 m safety distance), all the run.
BESIDE_THE_START = '  - {x: 0.37, y: 2.5, theta: 0.0, radius: 0.25, name: "beside the start"}\n'


def _stuck_scenario(tiny_scenario_path: Path, folder: Path) -> Path:
    """tiny.yaml with a person standing within the safety distance of the robot at its start."""
    text = tiny_scenario_path.read_text()
    anchor = 'name: "standing"}  # faces south\n'
    assert anchor in text
    path = folder / "stuck.yaml"
    path.write_text(text.replace(anchor, anchor + BESIDE_THE_START))
    return path


def test_a_replanning_robot_that_never_leaves_its_start_exits_5_with_its_outputs(tmp_path, tiny_scenario_path,
                                                                                   capsys):
    """Every replan waits (someone within the safety distance the whole run): a valid run that did
    not reach its goal, with the whole output set, as a run that planned once."""
    pytest.importorskip("drake_social.planning.replan")
    scenario = _stuck_scenario(tiny_scenario_path, tmp_path)
    out = tmp_path / "out"
    code = main(["simulate", str(scenario), "--replan", "--no-replay", "--out", str(out),
                 "--set", "planner: {replan_iterations: 100, replan_rate: 5.0}", "--set", "execution: {time_limit: 2}"])
    captured = capsys.readouterr()
    assert code == 5, captured.err
    assert captured.err == ("drake-social: goal not reached within the time limit of 2 s "
                            "(the last replan: wait)\n")
    names = sorted(p.name for p in out.iterdir() if not p.name.startswith("."))
    assert names == ["executed.csv", "motion.png", "people.csv", "predictions.png", "replans.csv", "replans.png",
                     "sim.json", "tracking.png"]
    rows = [line.split(",") for line in (out / "replans.csv").read_text().splitlines()[1:]]
    # The first plan and the replans at t = 0.2 .. 1.8 s (the one due at 2 s is past the run's end).
    assert [float(r[0]) for r in rows] == pytest.approx(np.arange(10) * 0.2) and {r[4] for r in rows} == {"wait"}
    executed = np.loadtxt(out / "executed.csv", delimiter=",", skiprows=1)
    start = [1.0, 2.5, 0.0, 1.5708]
    np.testing.assert_array_equal(executed[:, 1:5], np.tile(start, (len(executed), 1)))  # never moved
    record = json.loads((out / "sim.json").read_text())
    assert record["reached"] is False and record["num_waypoints"] == 1 and record["waypoints"] == [start]
    assert record["replanning"]["waits"] == record["replanning"]["count"] == 9
    # Measured against the one configuration it held: no motion, no deviation, 0.03 m from the person.
    assert record["planned_social_cost"] == record["executed_social_cost"] == 0.0
    assert record["max_point_deviation"]["max"] == record["max_config_deviation"] == 0.0
    assert record["collision_free"] is True and record["within_limits"] is True
    assert record["min_clearance"] == pytest.approx(0.03, abs=1e-9)
