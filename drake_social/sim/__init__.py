"""Simulation of a scenario: the diagram, the Simulator run, Meshcat replays.

* :mod:`drake_social.sim.station` :func:`make_station`: the robot and its
  world (plant or integrator, drivers, people, SceneGraph); driver inputs,
  sensor outputs, no planner or controller.
* :mod:`drake_social.sim.autonomy` :func:`make_autonomy`: path source,
  sequencer, Ruckig reference, base controller, safety monitor; a record of
  named ports.
* :mod:`drake_social.sim.diagram` :func:`build_diagram`: the two wired by
  port name, with the run's loggers. A script wires its own controller or
  path source instead (``docs/examples/``).
* :mod:`drake_social.sim.run` :func:`simulate`: runs it; its results
  (:class:`SimulationResult`) are in :mod:`drake_social.sim.results`.
* :mod:`drake_social.sim.execution_analysis` :func:`analyze_execution`: what the
  executed trajectory did (:class:`ExecutionReport`).
* :mod:`drake_social.sim.analysis` deviation and densification (no Drake;
  its inner loops compiled in :mod:`drake_social.sim.analysis_kernel`).
* :mod:`drake_social.sim.replay` Meshcat recording, overlays (heat map,
  facing arrows, path ribbon), the top view and the standalone HTML replay.

Exports are resolved lazily (PEP 562), so importing one submodule does not
import the others (nor matplotlib, which the replay's heat map uses). Add a
module's public names to ``_EXPORTS``.
"""

from importlib import import_module

_EXPORTS = {
    name: "drake_social.sim.replay"
    for name in (
        "OVERLAY_PREFIX",
        "VISUALIZER_PREFIX",
        "add_visualizer",
        "draw_overlays",
        "finish_recording",
        "make_meshcat",
        "set_top_view",
        "start_recording",
        "top_view_frame",
        "write_replay_html",
    )
}

_EXPORTS.update({name: "drake_social.sim.diagram" for name in ("TransportDiagram", "build_diagram")})
_EXPORTS.update({name: "drake_social.sim.station" for name in ("Station", "make_station", "scenario_plant_config",
                                                                 "servo_gains")})
_EXPORTS.update({name: "drake_social.sim.autonomy" for name in ("Autonomy", "ExternalPath", "GivenWaypoints",
                                                                  "PlanAtInit", "Replan", "make_autonomy")})
_EXPORTS.update({name: "drake_social.sim.run" for name in ("scenario_simulator_config", "simulate")})
_EXPORTS.update({name: "drake_social.sim.results"
                 for name in ("ExecutionReport", "LimitViolation", "SimulationResult")})
_EXPORTS.update({name: "drake_social.sim.execution_analysis" for name in ("analyze_execution", "limit_violations")})

__all__ = sorted(_EXPORTS)


def __getattr__(name: str):
    try:
        module = _EXPORTS[name]
    except KeyError:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}") from None
    return getattr(import_module(module), name)
