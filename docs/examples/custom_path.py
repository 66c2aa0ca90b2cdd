"""Replace the autonomy's path source with one of your own.

The package's autonomy (:func:`drake_social.sim.autonomy.make_autonomy`)
takes its path from one of four sources; with
:class:`~drake_social.sim.autonomy.ExternalPath` it reads it from its input
port ``path`` (an (N, 4) array of waypoints in a ``Value[object]``). This
script feeds that port from :class:`ViaPointPath`, a LeafSystem of its own:
at initialization it reads where the robot stands (the station's
``robot_state``) and takes the straight motion to the goal when the checker
finds it free, else the first free detour through one of a few hand-written
via points. The station, the autonomy and the path source are wired by port
name, simulated with Drake's Simulator, and what was measured is printed::

    python docs/examples/custom_path.py [scenarios/tiny.yaml]

Nothing of drake_social's builders is edited: the path source below could be
any Drake system with an abstract ``path`` output.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from pydrake.common.value import AbstractValue
from pydrake.systems.analysis import ApplySimulatorConfig, Simulator
from pydrake.systems.framework import Context, DiagramBuilder, LeafSystem, State
from pydrake.systems.primitives import LogVectorOutput

from drake_social.collision.drake_checker import make_checker
from drake_social.collision.validity import ValidityChecker
from drake_social.scenario import Scenario, load_scenario
from drake_social.sim.autonomy import ExternalPath, make_autonomy
from drake_social.sim.run import scenario_simulator_config
from drake_social.sim.station import make_station

#: The detours tried, in order, when the straight motion is not free: a
#: configuration [x, y, psi1, psi2] (m, rad) half way, south of the room's middle.
VIA_POINTS = np.array([[4.0, 1.9, 0.0, 1.5708], [4.0, 1.5, 0.0, 1.5708]])


class ViaPointPath(LeafSystem):
    """A path source: straight to ``goal``, or through the first free via point.

    At initialization it reads the robot's configuration from its input
    ``robot_state`` (8) and keeps, in abstract state, the first of
    ``[q, goal]``, ``[q, via, goal]`` (``via`` in ``via_points``' order)
    whose every straight motion ``checker`` finds free; its output ``path``
    is that (N, 4) array.

    Raises:
        RuntimeError: (at initialization) no candidate is free.
    """

    def __init__(self, goal, via_points, checker: ValidityChecker):
        super().__init__()
        self._goal = np.asarray(goal, float)
        self._via = np.asarray(via_points, float).reshape(-1, 4)
        self._checker = checker
        self.DeclareVectorInputPort("robot_state", 8)
        self._path = self.DeclareAbstractState(AbstractValue.Make(np.zeros((0, 4))))
        self.DeclareInitializationUnrestrictedUpdateEvent(self._Choose)
        self.DeclareAbstractOutputPort("path", lambda: AbstractValue.Make(np.zeros((0, 4))), self._CalcPath,
                                       prerequisites_of_calc={self.abstract_state_ticket(self._path)})

    def candidates(self, q: np.ndarray) -> list[np.ndarray]:
        """The paths tried from ``q``, in order."""
        return [np.array([q, self._goal])] + [np.array([q, via, self._goal]) for via in self._via]

    def _Choose(self, context: Context, state: State) -> None:
        q = np.array(self.get_input_port(0).Eval(context)[:4], float)
        for path in self.candidates(q):
            if np.all(self._checker.are_motions_valid(path[:-1], path[1:])):
                state.get_mutable_abstract_state(self._path).set_value(path)
                return
        raise RuntimeError(f"ViaPointPath: no free path from {q.tolist()}: straight and through "
                           f"{len(self._via)} via points all collide")

    def _CalcPath(self, context: Context, output: AbstractValue) -> None:
        output.set_value(context.get_abstract_state(self._path).get_value())


def run(scenario: Scenario, via_points=VIA_POINTS, mode: str = "kinematic") -> dict:
    """Executes the path :class:`ViaPointPath` chooses with the package's
    station and autonomy (the scenario's execution), until the sequencer's
    goal flag or ``execution.time_limit``.

    Returns:
        ``path`` (the waypoints chosen), ``reached``, ``time_to_goal`` (s:
        the sequencer's decision, as :func:`~drake_social.sim.simulate` times
        it, or None), and the logged ``times`` and ``q`` up to the first
        sample that shows the goal reached.
    """
    e = scenario.execution
    station = make_station(scenario, mode=mode)
    autonomy = make_autonomy(scenario, path=ExternalPath(), people=station.people.model)
    source = ViaPointPath(scenario.goal, via_points, make_checker(scenario, "planar"))
    builder = DiagramBuilder()
    robot = builder.AddNamedSystem("station", station.diagram)
    driver = builder.AddNamedSystem("autonomy", autonomy.diagram)
    mine = builder.AddNamedSystem("my_path", source)
    for name in autonomy.input_port_names():  # robot_state (and people_state when people move) from the station
        if name != "path":
            builder.Connect(robot.GetOutputPort(name), driver.GetInputPort(name))
    for name in station.input_port_names():  # wheel_speeds, arm_command
        builder.Connect(driver.GetOutputPort(name), robot.GetInputPort(name))
    builder.Connect(robot.GetOutputPort("robot_state"), mine.GetInputPort("robot_state"))
    builder.Connect(mine.GetOutputPort("path"), driver.GetInputPort("path"))
    state_log = LogVectorOutput(robot.GetOutputPort("robot_state"), builder, publish_period=e.control_period)
    done_log = LogVectorOutput(driver.GetOutputPort("done"), builder, publish_period=e.control_period)
    simulator = Simulator(builder.Build())
    ApplySimulatorConfig(scenario_simulator_config(scenario), simulator)
    root = simulator.get_mutable_context()
    simulator.Initialize()
    done = driver.GetOutputPort("done")
    while root.get_time() < e.time_limit and done.Eval(driver.GetMyContextFromRoot(root))[0] < 0.5:
        simulator.AdvanceTo(min(e.time_limit, root.get_time() + 0.25))

    times = state_log.FindLog(root).sample_times()
    q = state_log.FindLog(root).data().T[:, :4]
    finished = np.flatnonzero(done_log.FindLog(root).data()[0] > 0.5)
    keep = int(finished[0]) + 1 if len(finished) else len(times)  # up to the first sample that shows done
    return {
        "path": mine.GetOutputPort("path").Eval(mine.GetMyContextFromRoot(root)),
        "reached": bool(len(finished)),
        # The sequencer decided at the sample before the one that shows done.
        "time_to_goal": float(times[max(keep - 2, 0)]) if len(finished) else None,
        "times": times[:keep],
        "q": q[:keep],
    }


def main(argv: list[str] | None = None) -> None:
    argv = sys.argv[1:] if argv is None else argv
    path = argv[0] if argv else Path(__file__).resolve().parents[2] / "scenarios" / "tiny.yaml"
    result = run(load_scenario(path))
    to_goal = "not reached" if result["time_to_goal"] is None else f"{result['time_to_goal']:.2f} s"
    print(f"path of {len(result['path'])} waypoints: {np.round(result['path'], 3).tolist()}")
    print(f"reached {result['reached']}, time to goal {to_goal}")


if __name__ == "__main__":
    main()
