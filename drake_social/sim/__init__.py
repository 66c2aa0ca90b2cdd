"""Simulation of a scenario: the diagram, the Simulator run, Meshcat replays.

* :mod:`drake_social.sim.replay` Meshcat recording, overlays (heat map,
  facing arrows, path ribbon), the top view and the standalone HTML replay.
"""

from drake_social.sim.replay import (
    OVERLAY_PREFIX,
    VISUALIZER_PREFIX,
    add_visualizer,
    draw_overlays,
    finish_recording,
    make_meshcat,
    set_top_view,
    start_recording,
    write_replay_html,
)

__all__ = [
    "OVERLAY_PREFIX",
    "VISUALIZER_PREFIX",
    "add_visualizer",
    "draw_overlays",
    "finish_recording",
    "make_meshcat",
    "set_top_view",
    "start_recording",
    "write_replay_html",
]
