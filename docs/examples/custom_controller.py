"""Wire your own base controller into the drake_social station.

The station (:func:`drake_social.sim.diagram.build_diagram`) is built without
its base controller (``controller=False``) and with fixed waypoints (planned
once here, instead of by the station's planner). It then has an input port
``wheel_speeds`` and output ports ``robot_state``, ``reference`` and
``reference_feedforward``; this script closes the loop with its own
controller, a LeafSystem of a few lines (a proportional law without the
station's feed-forward), simulates with Drake's Simulator and prints what
was measured, for two gains::

    python docs/examples/custom_controller.py [scenarios/tiny.yaml]

Nothing of drake_social's builder is edited: the controller below could be
any Drake system with those ports.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from pydrake.systems.analysis import ApplySimulatorConfig, Simulator
from pydrake.systems.framework import BasicVector, Context, DiagramBuilder, LeafSystem

from drake_social.collision.drake_checker import make_checker
from drake_social.control import saturate_norm, wheel_speeds
from drake_social.planning.algorithms import plan
from drake_social.scenario import Scenario, load_scenario
from drake_social.scenario.geometry import arm_geometry
from drake_social.sim.analysis import point_deviation
from drake_social.sim.diagram import build_diagram
from drake_social.sim.run import scenario_simulator_config


class VelocityController(LeafSystem):
    """Base velocity ``v = kp (reference_xy - q_xy)`` (plus the reference's
    feed-forward ``v_ff`` when ``feedforward``), its norm capped at
    ``max_speed`` (m/s), then the mecanum wheel speeds (rad/s), scaled down
    together when one exceeds ``max_wheel_speed``. With the feed-forward it is
    the station's own law; without, the base lags the reference by about
    ``speed / kp``."""

    def __init__(self, kp: float, max_speed: float, wheel_radius: float, max_wheel_speed: float,
                 feedforward: bool):
        super().__init__()
        self._kp, self._max_speed, self._feedforward = kp, max_speed, feedforward
        self._radius, self._max_wheel = wheel_radius, max_wheel_speed
        self.DeclareVectorInputPort("robot_state", 8)
        self.DeclareVectorInputPort("reference", 4)
        self.DeclareVectorInputPort("reference_feedforward", 4)
        self.DeclareVectorOutputPort("wheel_speeds", 4, self._CalcWheelSpeeds)

    def _CalcWheelSpeeds(self, context: Context, output: BasicVector) -> None:
        q = self.get_input_port(0).Eval(context)[:2]
        reference = self.get_input_port(1).Eval(context)[:2]
        v = self._kp * (reference - q)
        if self._feedforward:
            v = self.get_input_port(2).Eval(context)[:2] + v
        v = saturate_norm(v, self._max_speed)
        w = wheel_speeds(v, self._radius)
        largest = np.max(np.abs(w))
        output.SetFromVector(w * (self._max_wheel / largest) if largest > self._max_wheel else w)


def run(scenario: Scenario, waypoints: np.ndarray, kp: float, feedforward: bool = False) -> dict:
    """Executes ``waypoints`` with :class:`VelocityController` of gain ``kp``
    (1/s) in kinematic, synchronized execution.

    Returns:
        ``reached``, ``time_to_goal`` (s), ``max_tracking_error`` (largest
        |reference_xy - q_xy| at the logged samples, m), ``max_point_deviation``
        (m), and the logged ``times`` and ``q``.
    """
    station = build_diagram(scenario, mode="kinematic", execution="synchronized", waypoints=waypoints,
                            controller=False)
    e = scenario.execution
    builder = DiagramBuilder()
    inner = builder.AddNamedSystem("station", station.diagram)
    controller = builder.AddNamedSystem(
        "my_controller", VelocityController(kp, e.max_base_speed, e.wheel_radius, e.max_wheel_speed, feedforward))
    for name in ("robot_state", "reference", "reference_feedforward"):
        builder.Connect(inner.GetOutputPort(name), controller.GetInputPort(name))
    builder.Connect(controller.GetOutputPort("wheel_speeds"), inner.GetInputPort("wheel_speeds"))
    diagram = builder.Build()

    simulator = Simulator(diagram)
    ApplySimulatorConfig(scenario_simulator_config(scenario), simulator)
    root = simulator.get_mutable_context()
    station_context = inner.GetMyContextFromRoot(root)  # the loggers find their own logs from the root
    simulator.Initialize()
    done = inner.GetOutputPort("done")
    while root.get_time() < e.time_limit and done.Eval(station_context)[0] < 0.5:
        simulator.AdvanceTo(min(e.time_limit, root.get_time() + 0.25))

    times = station.loggers["q"].FindLog(root).sample_times()
    q = station.loggers["q"].FindLog(root).data().T
    reference = station.loggers["reference"].FindLog(root).data().T
    finished = np.flatnonzero(station.loggers["done"].FindLog(root).data()[0] > 0.5)
    keep = int(finished[0]) + 1 if len(finished) else len(times)  # up to the first sample that shows done
    times, q, reference = times[:keep], q[:keep], reference[:keep]
    return {
        "reached": bool(len(finished)),
        # The sequencer decided at the sample before the one that shows done.
        "time_to_goal": float(times[max(keep - 2, 0)]) if len(finished) else None,
        "max_tracking_error": float(np.max(np.linalg.norm(reference[:, :2] - q[:, :2], axis=1))),
        "max_point_deviation": point_deviation(arm_geometry(scenario), waypoints, q)["max"],
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
