"""Drive the drake_social station with a controller of your own.

The station (:func:`drake_social.sim.station.make_station`) is the robot and
its world only: it takes the drivers' commands (input ports ``wheel_speeds``
and ``arm_command``) and gives the sensors (``robot_state``, the people,
SceneGraph's ``query_object``). This script builds it alone, without the
package's autonomy, and drives it with :class:`WaypointFollower`, a
LeafSystem of its own: a reference that runs along fixed waypoints at a
constant speed per straight segment, a proportional law on the base (with
or without the reference's velocity fed forward) and the arm commanded
along the reference. It simulates with Drake's Simulator and prints what
was measured, for two gains::

    python docs/examples/custom_controller.py [scenarios/tiny.yaml]

Nothing of drake_social's builders is edited: the controller below could be
any Drake system with those ports.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
from pydrake.systems.analysis import ApplySimulatorConfig, Simulator
from pydrake.systems.framework import BasicVector, Context, DiagramBuilder, LeafSystem
from pydrake.systems.primitives import LogVectorOutput

from drake_social.collision.drake_checker import make_checker
from drake_social.control import saturate_norm, wheel_speeds
from drake_social.scenario.geometry import arm_geometry
from drake_social.planning.algorithms import plan
from drake_social.scenario import Scenario, load_scenario
from drake_social.sim.analysis import point_deviation
from drake_social.sim.run import scenario_simulator_config
from drake_social.sim.station import make_station

#: Share of the base's speed limit the reference runs at: the rest is the P term's.
SPEED_SHARE = 0.8


class WaypointFollower(LeafSystem):
    """Follows fixed waypoints: a reference at constant speed along each
    straight segment, a P law on the base, the arm along the reference.

    The reference ``r(t)`` takes ``max(|dxy| / base_speed, max |dpsi| /
    arm_speed)`` seconds per segment (m/s, rad/s) and stops at the last
    waypoint. Ports: input ``robot_state`` (8); outputs ``wheel_speeds``
    (4, rad/s: the mecanum wheel speeds of ``v = kp (r_xy - q_xy)``, plus
    ``dr_xy/dt`` when ``feedforward``, its norm capped at ``max_speed`` and
    the wheels scaled down together to ``max_wheel_speed``),
    ``arm_command`` (6: ``[r_psi, dr_psi/dt, 0, 0]``) and ``reference`` (4:
    ``r(t)``). ``arm_command`` and ``reference`` depend on the time only:
    the kinematic station's ``robot_state`` depends on ``arm_command`` at
    once, so an arm command read from ``robot_state`` would close an
    algebraic loop.
    """

    def __init__(self, waypoints, *, base_speed: float, arm_speed: float, kp: float, max_speed: float,
                 wheel_radius: float, max_wheel_speed: float, feedforward: bool = True):
        super().__init__()
        wp = np.asarray(waypoints, float)
        wp = wp[np.r_[True, np.any(np.diff(wp, axis=0) != 0, axis=1)]]  # no zero-length segment
        d = np.diff(wp, axis=0)
        durations = np.maximum(np.hypot(d[:, 0], d[:, 1]) / base_speed, np.max(np.abs(d[:, 2:]), axis=1) / arm_speed)
        self._waypoints, self._times = wp, np.concatenate([[0.0], np.cumsum(durations)])
        self._kp, self._max_speed, self._feedforward = kp, max_speed, feedforward
        self._radius, self._max_wheel = wheel_radius, max_wheel_speed
        self.DeclareVectorInputPort("robot_state", 8)
        time_only = {self.time_ticket()}
        self.DeclareVectorOutputPort("wheel_speeds", 4, self._CalcWheelSpeeds)
        self.DeclareVectorOutputPort("arm_command", 6, self._CalcArmCommand, prerequisites_of_calc=time_only)
        self.DeclareVectorOutputPort("reference", 4, self._CalcReference, prerequisites_of_calc=time_only)

    @property
    def duration(self) -> float:
        """Seconds until the reference stands at the last waypoint."""
        return float(self._times[-1])

    def reference(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """The reference's position and velocity at ``t`` seconds, (4,) each."""
        wp, times = self._waypoints, self._times
        if t >= times[-1]:
            return wp[-1].copy(), np.zeros(4)
        i = min(max(int(np.searchsorted(times, t, side="right")) - 1, 0), len(wp) - 2)
        rate = (wp[i + 1] - wp[i]) / (times[i + 1] - times[i])
        return wp[i] + rate * (t - times[i]), rate

    def _CalcWheelSpeeds(self, context: Context, output: BasicVector) -> None:
        q = self.get_input_port(0).Eval(context)[:2]
        position, velocity = self.reference(context.get_time())
        v = self._kp * (position[:2] - q)
        if self._feedforward:
            v = velocity[:2] + v
        w = wheel_speeds(saturate_norm(v, self._max_speed), self._radius)
        largest = np.max(np.abs(w))
        output.SetFromVector(w * (self._max_wheel / largest) if largest > self._max_wheel else w)

    def _CalcArmCommand(self, context: Context, output: BasicVector) -> None:
        position, velocity = self.reference(context.get_time())
        output.SetFromVector(np.concatenate([position[2:], velocity[2:], np.zeros(2)]))

    def _CalcReference(self, context: Context, output: BasicVector) -> None:
        output.SetFromVector(self.reference(context.get_time())[0])


def reference_speed(scenario: Scenario) -> float:
    """The follower's base speed (m/s): :data:`SPEED_SHARE` of what the base
    reaches in any direction (its speed limit, and the wheels' limit along a
    diagonal)."""
    e = scenario.execution
    return SPEED_SHARE * min(e.max_base_speed, e.max_wheel_speed * e.wheel_radius / math.sqrt(2.0))


def run(scenario: Scenario, waypoints: np.ndarray, kp: float, feedforward: bool = True) -> dict:
    """Drives the kinematic station along ``waypoints`` with :class:`WaypointFollower` of gain ``kp`` (1/s).

    Runs until the robot is within the scenario's tolerances of the last
    waypoint after the reference has stopped there, or until
    ``execution.time_limit``.

    Returns:
        ``reached``, ``time_to_goal`` (s: the first logged sample within the
        tolerances after the reference stopped, or None), ``max_tracking_error``
        (largest |r_xy - q_xy| at the logged samples, m), ``max_point_deviation``
        (m), ``speed`` (the reference's base speed, m/s), and the logged ``times`` and ``q``.
    """
    e = scenario.execution
    station = make_station(scenario, mode="kinematic")
    follower = WaypointFollower(waypoints, base_speed=reference_speed(scenario), arm_speed=min(e.arm_max_velocity),
                                kp=kp, max_speed=e.max_base_speed, wheel_radius=e.wheel_radius,
                                max_wheel_speed=e.max_wheel_speed, feedforward=feedforward)
    builder = DiagramBuilder()
    robot = builder.AddNamedSystem("station", station.diagram)
    mine = builder.AddNamedSystem("my_controller", follower)
    builder.Connect(robot.GetOutputPort("robot_state"), mine.GetInputPort("robot_state"))
    for name in ("wheel_speeds", "arm_command"):
        builder.Connect(mine.GetOutputPort(name), robot.GetInputPort(name))
    state_log = LogVectorOutput(robot.GetOutputPort("robot_state"), builder, publish_period=e.control_period)
    reference_log = LogVectorOutput(mine.GetOutputPort("reference"), builder, publish_period=e.control_period)
    simulator = Simulator(builder.Build())
    ApplySimulatorConfig(scenario_simulator_config(scenario), simulator)
    root = simulator.get_mutable_context()
    simulator.Initialize()
    goal = np.asarray(waypoints, float)[-1]

    def arrived(q: np.ndarray) -> np.ndarray:
        return ((np.linalg.norm(q[..., :2] - goal[:2], axis=-1) <= e.base_tolerance)
                & np.all(np.abs(q[..., 2:] - goal[2:]) <= e.joint_tolerance, axis=-1))

    while root.get_time() < e.time_limit:
        simulator.AdvanceTo(min(e.time_limit, root.get_time() + 0.25))
        if root.get_time() >= follower.duration and arrived(robot.GetOutputPort("robot_state").Eval(
                robot.GetMyContextFromRoot(root))[:4]):
            break
    times = state_log.FindLog(root).sample_times()
    q = state_log.FindLog(root).data().T[:, :4]
    reference = reference_log.FindLog(root).data().T
    done = np.flatnonzero((times >= follower.duration) & arrived(q))
    return {
        "reached": bool(len(done)),
        "time_to_goal": float(times[done[0]]) if len(done) else None,
        "max_tracking_error": float(np.max(np.linalg.norm(reference[:, :2] - q[:, :2], axis=1))),
        "max_point_deviation": point_deviation(arm_geometry(scenario), waypoints, q)["max"],
        "speed": reference_speed(scenario),
        "times": times,
        "q": q,
    }


def main(argv: list[str] | None = None) -> None:
    argv = sys.argv[1:] if argv is None else argv
    path = argv[0] if argv else Path(__file__).resolve().parents[2] / "scenarios" / "tiny.yaml"
    scenario = load_scenario(path)
    planned = plan(scenario, make_checker(scenario, "planar"))
    if not planned.success:
        raise SystemExit(f"no path: {planned.message}")
    waypoints = np.asarray(planned.waypoints, float)
    print(f"{len(waypoints)} waypoints planned")
    for kp in (1.5, 6.0):
        result = run(scenario, waypoints, kp)
        to_goal = "not reached" if result["time_to_goal"] is None else f"{result['time_to_goal']:.2f} s"
        print(f"kp = {kp:g} 1/s: reached {result['reached']}, time to goal {to_goal}, "
              f"max tracking error {1000 * result['max_tracking_error']:.3f} mm, "
              f"max point deviation {1000 * result['max_point_deviation']:.3f} mm")


if __name__ == "__main__":
    main()
