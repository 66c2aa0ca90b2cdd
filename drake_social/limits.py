"""Limits shared by the scenario check and the compiled kernels.

A module of its own so that the kernels can compile its constants in and
:mod:`drake_social._kernel_cache` can drop their cached code when one
changes (it hashes this file with the kernel sources). No imports.
"""

#: Largest iteration budget K of a planner (``planner.iterations``,
#: ``--iterations``, ``RrtStarOptions.iterations``): the tree grows with the
#: nodes added, but K samples still take time (10^7 is hours of planning).
MAX_ITERATIONS = 10_000_000

#: The most trapezoid steps of ``social.resolution`` one motion's social cost
#: may take (its samples are held in memory): 100 km at the default 0.1 m.
#: ``validate_scenario`` refuses a resolution that a motion in the room could
#: need more steps of.
MAX_MOTION_STEPS = 1_000_000

#: The most waypoints a path to execute may have (``simulate --path``, the
#: ``waypoints`` of ``simulate`` and ``build_diagram``). The sequencer moves
#: on at most once per control period and stops at every waypoint of a
#: synchronized run: a densified 10,000-waypoint path cannot be executed within
#: the longest time limit (600 s; one reached waypoint 1,501 in 300 s), so
#: this bounds the checks and the analysis (whose memory does not grow with
#: the path), not what a run can finish.
MAX_WAYPOINTS = 10_000
